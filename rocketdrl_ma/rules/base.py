"""The base rule class: a game mode's logic over an ``Arena``.

A game mode says how it spawns (state mutators), what each tick means (``on_tick``: clock, goals,
events), what each agent may earn (``REWARD_TERMS``: named terms of ``rewards.py``, weighted from the
config), when it ends (``is_terminated`` / ``is_truncated``) and how it went (``summary``). The full match
and every minigame are subclasses; a new mode needs nothing else.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
import numpy as np

from rocketdrl_ma.physics import Arena, Car, CarControls, DemoMode, MutatorConfig, PhysicsEvent, PhysicsEventKind
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_shape import DEFAULT_ARENA_SHAPE, arena_shape_index

from . import events as game_events
from .mutators import KickoffMutator, StateMutator
from .rewards import CombinedReward, TermMakers, share_within_teams
from .state import GameState, Obstacle, agent_names, agent_team

NEUTRAL = CarControls()
GOAL_LINE_Y = C.ARENA_EXTENT_Y


def ball_heading_into_goal(pos: np.ndarray, vel: np.ndarray, goal_sign: float) -> bool:
    """Would the ball, flying on (gravity, no bounces), cross the goal line at ``goal_sign * 5120`` inside the mouth?"""
    vy = vel[1] * goal_sign
    if vy <= 1.0:
        return False
    t = (GOAL_LINE_Y - pos[1] * goal_sign) / vy
    if t < 0.0 or t > 3.0:
        return False
    x = pos[0] + vel[0] * t
    z = max(pos[2] + vel[2] * t + 0.5 * C.GRAVITY_Z * t * t, C.BALL_RADIUS)
    return abs(x) < C.GOAL_HALF_WIDTH - 0.1 * C.BALL_RADIUS and z < C.GOAL_HEIGHT


class Rules(ABC):
    """The logic of a game mode over one arena and its cars (one per agent); a ``GameEngine`` gives the arena and
    runs the ticks."""

    #: the reward terms a mode offers (name -> maker); the config's ``rewards:`` may weight any of them
    REWARD_TERMS: TermMakers = {}
    #: weights of terms the config does not mention
    DEFAULT_REWARD_WEIGHTS: dict[str, float] = {}

    def __init__(self, blue_size: int = 1, orange_size: int = 1, car_preset: str = "octane",
                 reward_weights: dict[str, float] | None = None, boost_pads: bool = True, demos: bool = True,
                 arena_shape: str = DEFAULT_ARENA_SHAPE, team_spirit: float = 0.0):
        for name, size in (("blue_size", blue_size), ("orange_size", orange_size)):
            if not isinstance(size, int) or not 0 <= size <= 4:
                raise ValueError(f"{name}: must be an int in 0..4, got {size!r}")
        if blue_size + orange_size == 0:
            raise ValueError("blue_size/orange_size: a game needs at least one car")
        self.blue_size, self.orange_size = blue_size, orange_size
        self.car_preset = car_preset
        self.possible_agents = agent_names(blue_size, orange_size)
        self.rewards = CombinedReward.from_weights(self.REWARD_TERMS,
                                                   {**self.DEFAULT_REWARD_WEIGHTS, **(reward_weights or {})})
        self.boost_pads, self.demos = boost_pads, demos
        if isinstance(team_spirit, bool) or not isinstance(team_spirit, (int, float)) or not 0.0 <= team_spirit <= 1.0:
            raise ValueError(f"team_spirit: must be a number in [0, 1] (0: own rewards, 1: the team's mean), "
                             f"got {team_spirit!r}")
        self.team_spirit = float(team_spirit)
        arena_shape_index(arena_shape)  # validates the name
        self.arena_shape = arena_shape
        self.arena: Arena | None = None
        self.cars: dict[str, Car] = {}
        self.obstacles: tuple[Obstacle, ...] = ()
        self.events: list[game_events.GameEvent] = []
        self.last_touch: str | None = None
        self._touching: set[str] = set()  # agents in contact with the ball on the last tick
        self.last_controls: dict[str, CarControls] = {}
        self._agent_by_car_id: dict[int, str] = {}

    # ------------------------------------------------------------------ what a game mode defines
    def spawn_mutators(self) -> list[StateMutator]:
        """How an episode (or round) starts; the default is a kickoff."""
        return [KickoffMutator()]

    def on_reset(self, rng: np.random.Generator) -> None:
        """Per-episode bookkeeping after spawning (clocks, counters)."""

    def on_tick(self) -> None:
        """Game logic after every physics tick (clock, goal detection); may append to ``self.events``."""

    def controls_frozen(self) -> bool:
        """True while inputs are ignored (a kickoff countdown)."""
        return False

    @abstractmethod
    def is_terminated(self) -> bool:
        """The game reached its natural end."""

    def is_truncated(self) -> bool:
        """The game was cut off (a time limit that is not part of the rules)."""
        return False

    def scoreboard(self) -> dict:
        return {}

    def summary(self) -> dict:
        """How the episode went, for ``infos`` at the end (score, success, durations)."""
        return self.scoreboard()

    # ------------------------------------------------------------------ machinery the engine drives
    def build(self, arena: Arena) -> None:
        """Play on ``arena`` (a game of the engine's batch): this mode's switches and one car per agent."""
        if self.arena is not None:
            raise ValueError("arena: these rules already play on an arena; make new rules for another")
        self.arena = arena
        arena.set_mutator_config(MutatorConfig(demo_mode=DemoMode.NORMAL if self.demos else DemoMode.DISABLED,
                                               boost_pads=self.boost_pads))
        for agent in self.possible_agents:
            car = arena.add_car(team=agent_team(agent), preset=self.car_preset)
            self.cars[agent] = car
            self._agent_by_car_id[car.id] = agent

    def reset(self, rng: np.random.Generator) -> None:
        """A new episode on the arena ``build`` gave, every draw from ``rng`` (the engine's stream of this game)."""
        if self.arena is None:
            raise ValueError("reset: these rules have no arena yet; a GameEngine builds them on one")
        # Drawn on every reset, not only the first, so that reset(seed=s) of a used game replays a fresh game.
        arena_seed = int(rng.integers(1 << 31))
        # A car demoed when the last episode ended comes back before the reseed: its respawn spot (the kickoff
        # moves it anyway) is a draw that a fresh arena's stream has not made, and would shift every later
        # respawn of the episode.
        for car in self.cars.values():
            if car.get_state().is_demoed:
                car.respawn()
        self.arena.reseed(arena_seed)
        for car in self.cars.values():
            car.set_controls(NEUTRAL)
        for mutator in self.spawn_mutators():
            mutator.apply(self.arena, self.cars, rng)
        self.arena.clear_events()
        self.events = []
        self.last_touch = None
        self._touching = set()
        self.last_controls = {agent: NEUTRAL for agent in self.cars}
        self.on_reset(rng)
        self.rewards.reset(list(self.cars), self.game_state())

    def begin_decision(self, controls: dict[str, CarControls]) -> None:
        """Before a decision's ticks (the engine has the controls); a subclass clears its per-decision records."""
        self.events = []
        self.last_controls.update(controls)

    def end_tick(self, physics_events: list[PhysicsEvent]) -> None:
        """After each tick: this arena's physics events (``Arena.drain_events()``) become game events, then the
        mode's per-tick logic runs."""
        if physics_events or self._touching:  # otherwise there is nothing to collect and no contact to end
            self._collect_physics_events(physics_events)
        self.on_tick()

    def _collect_physics_events(self, physics_events: list[PhysicsEvent]) -> None:
        """Turn the arena's physics events into game events. A touch is the start of a contact: a car resting
        against the ball (a dribble) is in contact every tick, and that is one touch, not 120 a second."""
        touching = set()
        agent_of = self._agent_by_car_id
        for event in physics_events:
            kind, tick = event.kind, event.tick
            if kind is PhysicsEventKind.BALL_TOUCH:
                agent = agent_of[event.car_id]
                if agent not in touching:
                    touching.add(agent)
                    self.last_touch = agent
                    if agent not in self._touching:
                        self.events.append(game_events.Touch(tick, agent))
            elif kind is PhysicsEventKind.DEMO:
                self.events.append(game_events.Demo(tick, agent_of[event.attacker_id], agent_of[event.victim_id]))
            elif kind is PhysicsEventKind.BUMP:
                self.events.append(game_events.Bump(tick, agent_of[event.attacker_id], agent_of[event.victim_id]))
            elif kind is PhysicsEventKind.BOOST_PICKUP:
                self.events.append(game_events.BoostPickup(tick, agent_of[event.car_id], int(event.pad_index)))
        self._touching = touching

    def game_state(self) -> GameState:
        arena = self.arena
        return GameState(
            tick=arena.tick_count, tick_rate=arena.tick_rate,
            cars={agent: car.get_state() for agent, car in self.cars.items()},
            ball=arena.ball.get_state(), pad_timers=arena.boost_pad_timers(),
            last_controls=dict(self.last_controls), last_touch=self.last_touch, obstacles=self.obstacles,
            events=list(self.events), car_configs={agent: car.config for agent, car in self.cars.items()},
            arena_shape=self.arena_shape, **self._scoreboard_fields())

    def _scoreboard_fields(self) -> dict:
        """GameState fields (score, clock_s, is_overtime, kickoff_pending) a subclass fills in."""
        return {}

    def weighted_rewards(self, agent: str, state: GameState) -> tuple[float, dict[str, float]]:
        """The agent's reward and its per-term breakdown (each term already weighted)."""
        return self.rewards.get(agent, state)

    def team_rewards(self, rewards: dict[str, float]) -> dict[str, float]:
        """Every agent's reward after ``team_spirit`` shared it within its team (``rewards.share_within_teams``)."""
        return share_within_teams(rewards, self.team_spirit)

    def close(self) -> None:
        """Forget the arena (its engine closes the world it belongs to)."""
        self.arena = None
