"""What every observation builder shares: the ``ObsBuilder`` interface, the scales (uu, uu/s, rad/s) that map the
game to [-1, 1], the team frame (orange mirrored) and the final clip to the space."""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.frames import TEAM_MIRROR, team_axis_sign
from rocketdrl_ma.physics.state import CarState
from rocketdrl_ma.rules.state import GameState, agent_team

POS_SCALE = np.array([C.ARENA_EXTENT_X, C.ARENA_EXTENT_Y + C.GOAL_DEPTH, C.ARENA_HEIGHT])  # to the goal's back
#: The longest straight line in the arena (corner to corner, goal back to goal back): |car -> ball| <= this.
ARENA_DIAGONAL = float(np.linalg.norm([2.0 * POS_SCALE[0], 2.0 * POS_SCALE[1], C.ARENA_HEIGHT]))
CAR_VEL_SCALE = C.CAR_MAX_SPEED
CAR_ANG_VEL_SCALE = C.CAR_MAX_ANG_SPEED
BALL_VEL_SCALE = C.BALL_MAX_SPEED
BALL_ANG_VEL_SCALE = C.BALL_MAX_ANG_SPEED
CLOCK_SCALE_S = 300.0  # a 5-minute match
SCORE_DIFF_SCALE = 3.0  # tanh(diff / 3)
MIRROR = TEAM_MIRROR  # x -> -x, y -> -y: the half-turn about z that swaps the sides
PAD_COOLDOWN = np.where(C.BOOST_PAD_IS_BIG, C.BOOST_PAD_BIG_COOLDOWN, C.BOOST_PAD_SMALL_COOLDOWN)


def _pad_mirror_permutation() -> np.ndarray:
    """``perm[i]`` is the pad at the mirrored position of pad ``i`` (x -> -x, y -> -y)."""
    xy = C.BOOST_PAD_POSITIONS[:, :2]
    dist = np.linalg.norm(xy[:, None, :] + xy[None, :, :], axis=2)  # |p_j - (-p_i)|
    perm = np.argmin(dist, axis=1)
    assert np.all(dist[np.arange(len(xy)), perm] < 1e-6) and len(set(perm.tolist())) == len(xy)
    return perm


PAD_MIRROR = _pad_mirror_permutation()
N_PADS = len(C.BOOST_PAD_POSITIONS)


def team_sign(agent: str) -> np.ndarray:
    """The per-axis sign that takes a world vector into ``agent``'s team frame."""
    return team_axis_sign(agent_team(agent))


def has_flip_available(car: CarState) -> bool:
    """Can the car still dodge: on the ground, or airborne within the double-jump window with its flip unused."""
    if car.on_ground:
        return True
    return (not car.has_double_jumped and not car.has_flipped
            and car.air_time_since_jump < C.DOUBLEJUMP_MAX_DELAY)


def box_space(low: Sequence[float], high: Sequence[float]) -> spaces.Box:
    low_a, high_a = np.asarray(low, dtype=np.float32), np.asarray(high, dtype=np.float32)
    return spaces.Box(low_a, high_a, low_a.shape, np.float32)


def clip_to_space(values: np.ndarray, space: spaces.Box) -> np.ndarray:
    """The last step of every ``build``: clip to the space's bounds and cast to float32."""
    return np.clip(np.asarray(values, dtype=np.float64), space.low, space.high).astype(np.float32)


def check_sizes(blue_size: int, orange_size: int) -> None:
    for name, size in (("blue_size", blue_size), ("orange_size", orange_size)):
        if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or not 0 <= size <= 4:
            raise ValueError(f"{name}: must be an int in 0..4, got {size!r}")
    if blue_size + orange_size == 0:
        raise ValueError("blue_size/orange_size: a game needs at least one car")


class ObsBuilder(ABC):
    """Turns a ``GameState`` into one agent's observation (RLGym v2 style: small and composable)."""

    @abstractmethod
    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        """The observation space for this team size: float32, finite bounds, the same for every agent."""

    def reset(self, state: GameState) -> None:
        """Per-episode hook, called with the first state of each episode before any ``build``."""

    @abstractmethod
    def build(self, agent: str, state: GameState) -> np.ndarray:
        """``agent``'s observation: float32, inside ``space`` (clipped to its bounds as the last step)."""
