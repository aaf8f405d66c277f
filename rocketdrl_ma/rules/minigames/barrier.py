"""Barrier free kick: a wall of defenders stands between the ball and the goal; sometimes it is lifted."""
from __future__ import annotations

import numpy as np

from rocketdrl_ma.physics import Arena, Car
from rocketdrl_ma.physics import constants as C

from ..mutators import StateMutator
from ..state import Obstacle
from .shot import ShotMinigame, ShotSpawn, check_number, check_range

#: where the barrier waits before the first spawn (any spot inside the arena, away from everything)
_PARKED_CENTER = np.array([0.0, -3000.0, 1500.0])


class BarrierPlacement(StateMutator):
    """Moves the barrier box onto the line from the ball to the goal centre, ``distance_uu`` out from the
    ball, shifted along x by up to ``x_jitter_uu``; with ``lift_probability`` its bottom edge is raised to a
    height in ``lift_uu``, else it stands with its top ``standing_top_uu`` above the floor (sunk into the floor
    if that is below its height). Runs after the ball is placed; ``obstacle`` and ``lifted`` tell the rules
    what it did."""

    def __init__(self, box_id: int, half_extents: np.ndarray, distance_uu: tuple[float, float],
                 x_jitter_uu: float, lift_probability: float, lift_uu: tuple[float, float],
                 standing_top_uu: float):
        self.box_id, self.half_extents, self.standing_top_uu = box_id, half_extents, standing_top_uu
        self.distance_uu, self.x_jitter_uu = distance_uu, x_jitter_uu
        self.lift_probability, self.lift_uu = lift_probability, lift_uu
        self.obstacle: Obstacle | None = None
        self.lifted = False

    def apply(self, arena: Arena, cars: dict[str, Car], rng: np.random.Generator) -> None:
        ball = arena.ball.get_state().pos
        to_goal = np.array([0.0, C.ARENA_EXTENT_Y]) - ball[:2]
        center_xy = ball[:2] + to_goal / np.linalg.norm(to_goal) * rng.uniform(*self.distance_uu)
        center_xy[0] += rng.uniform(-self.x_jitter_uu, self.x_jitter_uu)
        self.lifted = bool(rng.random() < self.lift_probability)
        bottom = rng.uniform(*self.lift_uu) if self.lifted else self.standing_top_uu - 2.0 * self.half_extents[2]
        center = np.array([center_xy[0], center_xy[1], bottom + self.half_extents[2]])
        arena.move_static_box(self.box_id, center)
        self.obstacle = Obstacle(center=center, half_extents=self.half_extents.copy())


class Barrier(ShotMinigame):
    """The seed's free kick: score past a barrier, a real static box in the arena that ball and car bounce off.

    The ball rests ``ball_distance_min_uu .. ball_distance_max_uu`` from the goal line at x within
    +-``ball_x_range_uu``; the car ``car_behind_uu`` behind it at x within +-``car_x_range_uu``, facing the
    goal. The barrier (``barrier_width_uu`` along x, ``barrier_thickness_uu`` along y,
    ``barrier_height_uu`` tall: a line of defenders) stands on the ball-to-goal line
    ``barrier_distance_min_uu .. barrier_distance_max_uu`` out from the ball, shifted along x by up to
    +-``barrier_x_jitter_uu``. With ``lift_probability`` it is lifted so its bottom edge is
    ``lift_min_uu .. lift_max_uu`` above the floor: a ball rolling on the ground (182.5 uu tall) passes
    under it, a chip hits it. ``difficulty`` narrows every range towards its easy end (0: fixed spawn, the
nearest ball and barrier, the highest lift).
    ``GameState.obstacles`` holds the barrier, so the ray sensor sees it and the renderer draws it.

    For curricula, ``easy_barrier_height_uu`` is how tall the standing barrier is at difficulty 0 (the box
    sunk into the floor); it grows to ``barrier_height_uu`` at difficulty 1, so the chip over it is learnt
    from small hops up. Unset, it is ``barrier_height_uu`` at every difficulty.
    """

    def __init__(self, ball_distance_min_uu: float = 2000.0, ball_distance_max_uu: float = 3000.0,
                 ball_x_range_uu: float = 1000.0, car_behind_uu: float = 1000.0, car_x_range_uu: float = 1000.0,
                 barrier_width_uu: float = 800.0, barrier_height_uu: float = 300.0,
                 barrier_thickness_uu: float = 100.0, barrier_distance_min_uu: float = 700.0,
                 barrier_distance_max_uu: float = 1200.0, barrier_x_jitter_uu: float = 300.0,
                 lift_probability: float = 0.5, lift_min_uu: float = 220.0, lift_max_uu: float = 300.0,
                 easy_barrier_height_uu: float | None = None, timeout_s: float = 12.0, **kwargs):
        super().__init__(timeout_s=timeout_s, **kwargs)
        self.ball_distance_uu = check_range("ball_distance_min_uu", ball_distance_min_uu, "ball_distance_max_uu",
                                            ball_distance_max_uu, 1500.0, C.ARENA_EXTENT_Y - 500.0)
        self.ball_x_range_uu = check_number("ball_x_range_uu", ball_x_range_uu, 0.0, 2000.0)
        self.car_behind_uu = check_number("car_behind_uu", car_behind_uu, 300.0, 3000.0)
        self.car_x_range_uu = check_number("car_x_range_uu", car_x_range_uu, 0.0, 2000.0)
        self.half_extents = np.array([check_number("barrier_width_uu", barrier_width_uu, 50.0, 3000.0),
                                      check_number("barrier_thickness_uu", barrier_thickness_uu, 20.0, 500.0),
                                      check_number("barrier_height_uu", barrier_height_uu, 50.0, 1000.0)]) / 2.0
        self.barrier_distance_uu = check_range("barrier_distance_min_uu", barrier_distance_min_uu,
                                               "barrier_distance_max_uu", barrier_distance_max_uu, 300.0, 3000.0)
        if self.barrier_distance_uu[1] > self.ball_distance_uu[0] - 300.0:
            raise ValueError(f"barrier_distance_max_uu: must leave the barrier 300 uu in front of the goal line "
                             f"(<= ball_distance_min_uu - 300 = {self.ball_distance_uu[0] - 300.0}), "
                             f"got {barrier_distance_max_uu!r}")
        self.barrier_x_jitter_uu = check_number("barrier_x_jitter_uu", barrier_x_jitter_uu, 0.0, 1500.0)
        self.lift_probability = check_number("lift_probability", lift_probability, 0.0, 1.0)
        self.lift_uu = check_range("lift_min_uu", lift_min_uu, "lift_max_uu", lift_max_uu, 0.0, 1200.0)
        self.barrier_height_uu = 2.0 * self.half_extents[2]
        self.easy_barrier_height_uu = self.barrier_height_uu if easy_barrier_height_uu is None else check_number(
            "easy_barrier_height_uu", easy_barrier_height_uu, 0.0, self.barrier_height_uu)
        self.barrier_id: int | None = None
        self._barrier_arena: Arena | None = None  # the arena the box was added to
        self.lifted = False
        self._placement: BarrierPlacement | None = None

    def spawn_mutators(self) -> list[StateMutator]:
        if self._barrier_arena is not self.arena:  # first spawn in this arena, however it was built
            self.barrier_id = self.arena.add_static_box(_PARKED_CENTER, self.half_extents)
            self._barrier_arena = self.arena
        d = self.difficulty
        shot = ShotSpawn(ball_distance_uu=self.scaled(*self.ball_distance_uu), ball_x_uu=d * self.ball_x_range_uu,
                         ball_z_uu=(C.BALL_REST_Z, C.BALL_REST_Z), car_behind_uu=self.car_behind_uu,
                         car_x_uu=d * self.car_x_range_uu, car_boost=self.car_boost)
        self._placement = BarrierPlacement(self.barrier_id, self.half_extents, self.scaled(*self.barrier_distance_uu),
                                           d * self.barrier_x_jitter_uu, self.lift_probability,
                                           (self.eased(self.lift_uu[1], self.lift_uu[0]), self.lift_uu[1]),
                                           self.eased(self.easy_barrier_height_uu, self.barrier_height_uu))
        return [shot, self._placement]

    def round_started(self) -> None:
        self.obstacles = (self._placement.obstacle,)
        self.lifted = self._placement.lifted

    def mode_state(self) -> dict:
        return {"barrier_lifted": self.lifted}
