"""Penalty: one car, one ball at rest in front of the goal, one shot per round."""
from __future__ import annotations

from rocketdrl_ma.physics import constants as C

from ..mutators import StateMutator
from .shot import ShotMinigame, ShotSpawn, check_number


class Penalty(ShotMinigame):
    """The seed's penalty shoot-out: put the ball in the goal before ``timeout_s``.

    The ball rests ``ball_distance_uu`` in front of the +y goal line, the car ``car_behind_uu`` behind it
    facing the goal; as in the seed, both are placed at random along the width of the field (x uniform in
    +-``ball_x_range_uu`` and +-``car_x_range_uu``, times ``difficulty``). Rounds, misses and rewards: see
    ``ShotMinigame``.
    """

    def __init__(self, ball_distance_uu: float = 2000.0, ball_x_range_uu: float = 1500.0,
                 car_behind_uu: float = 1000.0, car_x_range_uu: float = 1500.0, timeout_s: float = 10.0, **kwargs):
        super().__init__(timeout_s=timeout_s, **kwargs)
        self.ball_distance_uu = check_number("ball_distance_uu", ball_distance_uu, 500.0, C.ARENA_EXTENT_Y - 500.0)
        self.ball_x_range_uu = check_number("ball_x_range_uu", ball_x_range_uu, 0.0, 2500.0)
        self.car_behind_uu = check_number("car_behind_uu", car_behind_uu, 300.0, 4000.0)
        self.car_x_range_uu = check_number("car_x_range_uu", car_x_range_uu, 0.0, 2500.0)
        if self.ball_distance_uu + self.car_behind_uu > 2.0 * C.ARENA_EXTENT_Y - 1000.0:
            raise ValueError(f"car_behind_uu: the car would start behind the far goal "
                             f"(ball_distance_uu + car_behind_uu = {self.ball_distance_uu + self.car_behind_uu})")

    def shot_spawn(self, keeper_x_uu: float = 0.0) -> ShotSpawn:
        d = self.difficulty
        return ShotSpawn(ball_distance_uu=(self.ball_distance_uu, self.ball_distance_uu),
                         ball_x_uu=d * self.ball_x_range_uu, ball_z_uu=(C.BALL_REST_Z, C.BALL_REST_Z),
                         car_behind_uu=self.car_behind_uu, car_x_uu=d * self.car_x_range_uu,
                         car_boost=self.car_boost, keeper_x_uu=d * keeper_x_uu)

    def spawn_mutators(self) -> list[StateMutator]:
        return [self.shot_spawn()]
