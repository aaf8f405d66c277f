"""State mutators: how a game mode places cars and ball at the start of an episode or round.

Each is a small callable object; a game mode composes them (RLGym's StateMutator idea). All draws come
from the generator they are given, which the env seeds from ``reset(seed=...)``.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from rocketdrl_ma.physics import Arena, BallState, Car, CarState, yaw_rot_mat
from rocketdrl_ma.physics import constants as C


class StateMutator(ABC):
    @abstractmethod
    def apply(self, arena: Arena, cars: dict[str, Car], rng: np.random.Generator) -> None:
        """Set the state of ``arena``'s cars (keyed by agent name) and ball."""


class KickoffMutator(StateMutator):
    """The standard kickoff: random spot permutation, orange mirrored, ball frozen at centre."""

    def apply(self, arena: Arena, cars: dict[str, Car], rng: np.random.Generator) -> None:
        arena.reset_kickoff(seed=int(rng.integers(1 << 31)))


class FixedStateMutator(StateMutator):
    """Exactly the given states; agents without a state keep theirs."""

    def __init__(self, cars: dict[str, CarState] | None = None, ball: BallState | None = None):
        self.cars, self.ball = cars or {}, ball

    def apply(self, arena: Arena, cars: dict[str, Car], rng: np.random.Generator) -> None:
        for agent, state in self.cars.items():
            if agent not in cars:
                raise ValueError(f"cars: no agent {agent!r}; agents are {sorted(cars)}")
            cars[agent].set_state(state)
        if self.ball is not None:
            arena.ball.set_state(self.ball)


class RandomStateMutator(StateMutator):
    """Cars on the floor at random spots and headings with random speeds; the ball anywhere, moving.

    Positions keep a margin from walls and each other so nothing starts inside something else.
    """

    def __init__(self, max_car_speed_uu_s: float = 1500.0, max_ball_speed_uu_s: float = 2000.0,
                 margin_uu: float = 600.0):
        self.max_car_speed_uu_s, self.max_ball_speed_uu_s, self.margin_uu = (
            max_car_speed_uu_s, max_ball_speed_uu_s, margin_uu)

    def _spot(self, rng: np.random.Generator, taken: list[np.ndarray], z: float) -> np.ndarray:
        for _ in range(1000):
            p = np.array([rng.uniform(-C.ARENA_EXTENT_X + self.margin_uu, C.ARENA_EXTENT_X - self.margin_uu),
                          rng.uniform(-C.ARENA_EXTENT_Y + self.margin_uu, C.ARENA_EXTENT_Y - self.margin_uu), z])
            if abs(p[0]) + abs(p[1]) < C.ARENA_CORNER_SUM - 2 * self.margin_uu and all(
                    np.linalg.norm(p[:2] - q[:2]) > 300.0 for q in taken):
                return p
        raise RuntimeError("RandomStateMutator: could not place every object; lower margin_uu")

    def apply(self, arena: Arena, cars: dict[str, Car], rng: np.random.Generator) -> None:
        taken: list[np.ndarray] = []
        for car in cars.values():
            pos = self._spot(rng, taken, C.CAR_SPAWN_REST_Z)
            taken.append(pos)
            yaw = rng.uniform(-np.pi, np.pi)
            rot = yaw_rot_mat(yaw)
            speed = rng.uniform(0.0, self.max_car_speed_uu_s)
            car.set_state(CarState(pos=pos, rot_mat=rot, vel=rot[:, 0] * speed, on_ground=True,
                                   boost=float(rng.uniform(0.0, C.BOOST_MAX))))
        ball_pos = self._spot(rng, taken, rng.uniform(C.BALL_REST_Z, 1200.0))
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        arena.ball.set_state(BallState(pos=ball_pos, vel=direction * rng.uniform(0.0, self.max_ball_speed_uu_s)))


class KickoffOrRandomMutator(StateMutator):
    """A random state (``RandomStateMutator``) with probability ``random_share``, else a kickoff: varied starts
    for training, with kickoffs kept."""

    def __init__(self, random_share: float):
        self.random_share = random_share

    def apply(self, arena: Arena, cars: dict[str, Car], rng: np.random.Generator) -> None:
        if rng.random() < self.random_share:
            RandomStateMutator().apply(arena, cars, rng)
        else:
            KickoffMutator().apply(arena, cars, rng)
