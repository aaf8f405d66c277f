"""What a decision sees: one read-only snapshot of the game, shared by observations, rewards and rules."""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from rocketdrl_ma.physics import BallState, CarConfig, CarControls, CarState
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_shape import DEFAULT_ARENA_SHAPE

from .events import GameEvent

BLUE, ORANGE = 0, 1
TEAM_NAMES = ("blue", "orange")
# The two points of the goal a team attacks (blue attacks +y), in uu. Shared arrays: read, never modify.
#: the centre of the goal mouth, on the goal line, in the team frame (orange's is mirrored): the seed's goal sensor
ATTACKED_GOAL_MOUTH = np.array([0.0, C.ARENA_EXTENT_Y, C.GOAL_HEIGHT / 2.0])
#: the centre of the goal box (half its depth behind the line) each team attacks, in the blue frame: the target of
#: the goal-directed reward and shaping terms
ATTACKED_GOAL_CENTER = {team: np.array([0.0, (1.0 if team == BLUE else -1.0) * (C.ARENA_EXTENT_Y + C.GOAL_DEPTH / 2),
                                        C.GOAL_HEIGHT / 2]) for team in (BLUE, ORANGE)}


@functools.lru_cache(maxsize=256)  # observations ask it for every car of every agent's view each decision
def agent_team(agent: str) -> int:
    """``blue_0`` -> 0, ``orange_3`` -> 1 (PettingZoo's ``word_N`` names)."""
    prefix = agent.rsplit("_", 1)[0]
    if prefix not in TEAM_NAMES:
        raise ValueError(f"agent: {agent!r} is not a blue_N or orange_N name")
    return TEAM_NAMES.index(prefix)


def agent_number(agent: str) -> int:
    """``blue_0`` -> 0, ``orange_3`` -> 3: the car's number in its team."""
    agent_team(agent)
    return int(agent.rsplit("_", 1)[1])


def agent_names(blue_size: int, orange_size: int) -> list[str]:
    return [f"blue_{i}" for i in range(blue_size)] + [f"orange_{i}" for i in range(orange_size)]


@dataclass(frozen=True)
class Obstacle:
    """A static box in the arena (a minigame barrier): centre and half extents in uu, axis-aligned."""
    center: np.ndarray
    half_extents: np.ndarray


@dataclass
class GameState:
    """The game after a decision's ticks, in uu and the blue team's frame (z up, blue goal at -y)."""
    tick: int
    tick_rate: int
    cars: dict[str, CarState]  # every car still in the game, keyed by agent name
    ball: BallState
    pad_timers: np.ndarray  # (34,) seconds until each pad is back; 0 = active (RLBot order)
    last_controls: dict[str, CarControls]
    score: tuple[int, int] = (0, 0)
    clock_s: float = 0.0  # seconds left in regulation; counts up in overtime
    is_overtime: bool = False
    kickoff_pending: bool = False  # the kickoff countdown is running: cars are frozen
    last_touch: str | None = None  # agent who touched the ball last
    obstacles: tuple[Obstacle, ...] = ()
    events: list[GameEvent] = field(default_factory=list)  # this decision's events, in tick order
    car_configs: dict[str, CarConfig] = field(default_factory=dict)  # hitbox preset of each car
    mode_state: dict = field(default_factory=dict)  # a game mode's own flags its sensors read (minigames)
    arena_shape: str = DEFAULT_ARENA_SHAPE  # the arena's surface (``physics.arena_shape.ARENA_SHAPES``): rays hit it
