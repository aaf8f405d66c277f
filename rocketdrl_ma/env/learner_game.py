"""The learner's side of one game of a ``GameEngine``: actions parsed into controls, the game's state built into
observations, rewards per term, terminations, truncations and infos. ``RocketDRLParallelEnv`` is one of these over
an engine of one game; a ``VectorEnv`` holds one per game of its engine."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules import GameState, Rules
from rocketdrl_ma.validation import check_int

from .actions import make_action_parser
from .observations import make_obs_builder

STATE_CAR_FEATURES = 19  # pos 3, vel 3, ang_vel 3, forward 3, up 3, boost, on_ground, is_demoed, present
#: event kinds counted per agent in numeric infos (an agent is credited as ``agent`` or goal ``scorer``)
COUNTED_EVENTS = ("goal", "touch", "shot", "save", "demo", "bump", "boost_pickup")


def flat_numbers(tree: dict, prefix: str = "") -> dict[str, float]:
    """``{"score": {"blue": 1}, "overtime": False}`` -> ``{"score_blue": 1.0, "overtime": 0.0}``."""
    flat: dict[str, float] = {}
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flat_numbers(value, name + "_"))
        elif isinstance(value, (bool, int, float, np.number)):
            flat[name] = float(value)
    return flat


def check_seed(seed: object) -> int | None:
    """A reset seed: None or an int >= 0 (NumPy's seeds; a NumPy integer too), bools and floats refused."""
    if seed is None:
        return None
    return check_int("seed", int(seed) if isinstance(seed, np.integer) else seed, minimum=0)


def global_state_vector(state: GameState, agents: list[str]) -> np.ndarray:
    """The whole game in the blue frame for a centralised critic, every value scaled into [-1, 1]."""
    ball = state.ball
    parts = [ball.pos / 6000.0, ball.vel / C.BALL_MAX_SPEED, ball.ang_vel / C.BALL_MAX_ANG_SPEED]
    for agent in agents:
        car = state.cars.get(agent)
        if car is None:
            parts.append(np.zeros(STATE_CAR_FEATURES))
            continue
        parts += [car.pos / 6000.0, car.vel / C.CAR_MAX_SPEED, car.ang_vel / C.CAR_MAX_ANG_SPEED,
                  car.rot_mat[:, 0], car.rot_mat[:, 2],
                  [car.boost / C.BOOST_MAX, float(car.on_ground), float(car.is_demoed), 1.0]]
    cooldown = np.where(C.BOOST_PAD_IS_BIG, C.BOOST_PAD_BIG_COOLDOWN, C.BOOST_PAD_SMALL_COOLDOWN)
    parts.append(state.pad_timers / cooldown)
    parts.append([np.tanh((state.score[0] - state.score[1]) / 3.0), min(state.clock_s / 300.0, 1.0),
                  float(state.is_overtime)])
    return np.clip(np.concatenate([np.asarray(p, dtype=np.float64).ravel() for p in parts]), -1.0, 1.0).astype(
        np.float32)


class LearnerGame:
    """What learners see of one game (``rules``, played by an engine) under a loaded ``config``: its observation
    builder and action parser, the live ``agents``, the decisions played (``max_cycles``) and the last state."""

    def __init__(self, config: dict[str, Any], rules: Rules):
        self.config = config
        self.rules = rules
        obs_spec, act_spec = dict(config["observation"]), dict(config["action"])
        self.obs_builder = make_obs_builder(obs_spec.pop("name"), **obs_spec)
        self.action_parser = make_action_parser(act_spec.pop("name"), **act_spec)
        self.tick_skip: int = config["tick_skip"]
        self.max_cycles: int | None = config["max_cycles"]
        self.info_format: str = config["info_format"]
        self.possible_agents = list(rules.possible_agents)
        self.agents: list[str] = []
        self._obs_space = self.obs_builder.space(rules.blue_size, rules.orange_size)
        self._action_space = self.action_parser.space()
        n_state = 9 + STATE_CAR_FEATURES * len(self.possible_agents) + len(C.BOOST_PAD_POSITIONS) + 3
        self.state_space = spaces.Box(-1.0, 1.0, (n_state,), np.float32)
        self._state: GameState | None = None
        self._cycles = 0

    # The same space object every call, as PettingZoo asks, without its docs' ``functools.lru_cache``: a cache on the
    # method keys on ``self`` and so kept every env that was ever asked (and its PyBullet world) alive.
    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        return self._action_space

    @property
    def game_state(self) -> GameState | None:
        """The game after the last reset or step (None before the first reset)."""
        return self._state

    def state(self) -> np.ndarray:
        if self._state is None:
            raise ValueError("state: call reset() first")
        return global_state_vector(self._state, self.possible_agents)

    # ------------------------------------------------------------------ one episode, decision by decision
    def start(self, state: GameState) -> tuple[dict, dict]:
        """A new episode began in ``state``: every agent's first observation and infos."""
        self.agents = list(self.possible_agents)
        self._cycles = 0
        self._state = state
        self.obs_builder.reset(state)
        observations = {agent: self.obs_builder.build(agent, state) for agent in self.agents}
        no_terms = {term: 0.0 for term in self.rules.REWARD_TERMS}
        return observations, {agent: self._info(agent, state, no_terms) for agent in self.agents}

    def controls(self, actions: Mapping | None, given: Mapping[str, CarControls] | None = None) -> dict:
        """Every live agent's controls this decision: those in ``given`` as they are (a scripted bot, a server's
        checked action), the others' ``actions`` through the action parser."""
        if not self.agents:
            raise ValueError("step: the episode is over; call reset()")
        given = given or {}
        actions = {} if actions is None else actions
        if not isinstance(actions, Mapping):
            raise ValueError(f"actions: expected a dict of agent -> action for the live agents {self.agents}, got "
                             f"{type(actions).__name__}")
        for agent in (*actions, *given):
            if agent not in self.possible_agents:
                raise ValueError(f"actions: unknown agent {agent!r}; agents are {self.possible_agents}")
        missing = [agent for agent in self.agents if agent not in actions and agent not in given]
        if missing:
            raise ValueError(f"actions: no action for live agent(s) {missing}")
        # Actions for agents no longer in the game are ignored (torchrl sends them for finished agents).
        parse, state = self.action_parser.parse, self._state
        return {agent: given[agent] if agent in given else parse(agent, actions[agent], state)
                for agent in self.agents}

    def finish(self, state: GameState, observe: bool = True) -> tuple[dict, dict, dict, dict, dict]:
        """The decision played to ``state``: what a PettingZoo step returns (``observe=False`` leaves the
        observations out, for a face that builds them itself)."""
        self._cycles += 1
        self._state = state
        rules = self.rules
        terminated = rules.is_terminated()
        truncated = rules.is_truncated() or (self.max_cycles is not None and self._cycles >= self.max_cycles)
        observations, rewards, infos = {}, {}, {}
        for agent in self.agents:
            if observe:
                observations[agent] = self.obs_builder.build(agent, state)
            rewards[agent], terms = rules.weighted_rewards(agent, state)
            infos[agent] = self._info(agent, state, terms)
        rewards = rules.team_rewards(rewards)
        if (terminated or truncated) and self.info_format == "full":
            summary = rules.summary()
            for agent in self.agents:
                infos[agent]["summary"] = summary
        terminations = {agent: bool(terminated) for agent in self.agents}
        truncations = {agent: bool(truncated and not terminated) for agent in self.agents}
        if terminated or truncated:
            self.agents = []
        return observations, rewards, terminations, truncations, infos

    def _info(self, agent: str, state: GameState, reward_terms: dict[str, float]) -> dict:
        if self.info_format == "full":
            return {"scoreboard": self.rules.scoreboard(), "events": list(state.events), "reward_terms": reward_terms}
        info = flat_numbers(self.rules.scoreboard())
        counts = dict.fromkeys(COUNTED_EVENTS, 0.0)
        for event in state.events:
            if event.kind in counts and event.credited_to == agent:
                counts[event.kind] += 1.0
        info.update(counts)
        info.update({f"reward_{term}": value for term, value in reward_terms.items()})
        return info
