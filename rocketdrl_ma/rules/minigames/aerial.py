"""Aerial shot: the ball hangs in the air, then drops; only a goal after a touch high in the air counts."""
from __future__ import annotations

from rocketdrl_ma.physics import BallState
from rocketdrl_ma.physics import constants as C

from .. import events as game_events
from .. import rewards
from ..mutators import StateMutator
from .shot import ShotMinigame, ShotSpawn, check_number, check_range

#: the ball is on the floor when its centre is this close to its radius (uu)
BALL_FLOOR_MARGIN_UU = 5.0


class Aerial(ShotMinigame):
    """The seed's aerial shoot: the ball is held frozen ``ball_height_min_uu .. ball_height_max_uu`` above the
    floor, ``ball_distance_min_uu .. ball_distance_max_uu`` in front of the goal (x within
    +-``ball_x_range_uu``), and released after ``release_after_s`` (3 s) unless touched before. The car starts
    ``car_behind_uu`` behind it, facing the goal.

    **Aerial touch**: a touch while the car is airborne (not on its wheels) with its centre above
    ``aerial_min_height_uu`` (400 uu, 4 m). The first one of a round earns the ``aerial_touch`` term once
    (+5 by default). **Goal**: only counts after the round's aerial touch; a goal without one is a miss
    (``goal_not_counted``). **Extra miss**: ``ball_on_ground``, the released ball reaches the floor before any
    aerial touch. After the aerial touch the ball may bounce and roll in: that goal counts.

    ``GameState.mode_state`` carries the sensors' flags (``aerial_sensors``): ``ball_frozen``, ``release_in_s``,
    ``release_after_s``, and per agent ``aerial_touch_done`` and ``touch_waiting_reset`` (touched the ball
    and not back on the ground since). ``difficulty`` narrows the ranges to the lowest, nearest, centred ball.

    For curricula, ``easy_ball_height_uu`` and ``easy_aerial_min_height_uu`` move the easy end below the
    task's own: at difficulty ``d`` the ball hangs ``easy + d * (min - easy) .. easy + d * (max - easy)``
    high and an aerial touch needs the car above ``easy + d * (aerial_min_height_uu - easy)``. A ball
    hanging low enough to reach with one jump is where a car learns to touch it in the air at all; at
    difficulty 1 (evaluation) the task is the seed's whatever these are. Unset, they equal the task's values.
    """

    REWARD_TERMS = {**ShotMinigame.REWARD_TERMS, "aerial_touch": rewards.AerialTouched}
    DEFAULT_REWARD_WEIGHTS = {**ShotMinigame.DEFAULT_REWARD_WEIGHTS, "aerial_touch": 5.0}

    def __init__(self, ball_distance_min_uu: float = 1500.0, ball_distance_max_uu: float = 2500.0,
                 ball_x_range_uu: float = 800.0, ball_height_min_uu: float = 550.0,
                 ball_height_max_uu: float = 900.0, car_behind_uu: float = 1200.0, car_x_range_uu: float = 800.0,
                 release_after_s: float = 3.0, aerial_min_height_uu: float = 400.0, timeout_s: float = 10.0,
                 easy_ball_height_uu: float | None = None, easy_aerial_min_height_uu: float | None = None,
                 **kwargs):
        super().__init__(timeout_s=timeout_s, **kwargs)
        self.ball_distance_uu = check_range("ball_distance_min_uu", ball_distance_min_uu, "ball_distance_max_uu",
                                            ball_distance_max_uu, 500.0, C.ARENA_EXTENT_Y - 500.0)
        self.ball_x_range_uu = check_number("ball_x_range_uu", ball_x_range_uu, 0.0, 2500.0)
        self.ball_height_uu = check_range("ball_height_min_uu", ball_height_min_uu, "ball_height_max_uu",
                                          ball_height_max_uu, 300.0, C.ARENA_HEIGHT - 200.0)
        self.car_behind_uu = check_number("car_behind_uu", car_behind_uu, 300.0, 4000.0)
        self.car_x_range_uu = check_number("car_x_range_uu", car_x_range_uu, 0.0, 2500.0)
        self.release_after_s = check_number("release_after_s", release_after_s, 0.0)
        self.aerial_min_height_uu = check_number("aerial_min_height_uu", aerial_min_height_uu, 0.0, C.ARENA_HEIGHT)
        self.easy_ball_height_uu = self.ball_height_uu[0] if easy_ball_height_uu is None else check_number(
            "easy_ball_height_uu", easy_ball_height_uu, 2.0 * C.BALL_RADIUS, self.ball_height_uu[0])
        self.easy_aerial_min_height_uu = self.aerial_min_height_uu if easy_aerial_min_height_uu is None else (
            check_number("easy_aerial_min_height_uu", easy_aerial_min_height_uu, 0.0, self.aerial_min_height_uu))
        self.aerial_done: dict[str, bool] = {}
        self.waiting_reset: dict[str, bool] = {}
        self.aerial_height_needed_uu = self.aerial_min_height_uu  # the car's height for an aerial touch, this round

    def spawn_mutators(self) -> list[StateMutator]:
        d = self.difficulty
        ball_z_uu = (self.eased(self.easy_ball_height_uu, self.ball_height_uu[0]),
                     self.eased(self.easy_ball_height_uu, self.ball_height_uu[1]))
        return [ShotSpawn(ball_distance_uu=self.scaled(*self.ball_distance_uu), ball_x_uu=d * self.ball_x_range_uu,
                          ball_z_uu=ball_z_uu, car_behind_uu=self.car_behind_uu,
                          car_x_uu=d * self.car_x_range_uu, car_boost=self.car_boost)]

    def on_reset(self, rng) -> None:
        super().on_reset(rng)
        for agent in self.cars:
            self.stats[agent]["aerial_touches"] = 0

    def round_started(self) -> None:
        self.aerial_done = {agent: False for agent in self.cars}
        self.waiting_reset = {agent: False for agent in self.cars}
        # fixed for the round, as the spawn: a curriculum changes the difficulty between rounds
        self.aerial_height_needed_uu = self.eased(self.easy_aerial_min_height_uu, self.aerial_min_height_uu)
        if self.release_after_s == 0.0:
            self.arena.ball.release()

    def on_tick(self) -> None:
        if not self.ended:
            if self.arena.ball.is_frozen and self.round_time_s + self.arena.tick_time >= self.release_after_s - 1e-9:
                self.arena.ball.release()
            for agent, waiting in self.waiting_reset.items():
                if waiting and self.cars[agent].get_state().on_ground:
                    self.waiting_reset[agent] = False
        super().on_tick()

    def on_touch(self, agent: str) -> None:
        car = self.cars[agent].get_state()
        self.waiting_reset[agent] = True
        if car.on_ground or car.pos[2] <= self.aerial_height_needed_uu or any(self.aerial_done.values()):
            return
        self.aerial_done[agent] = True
        self.stats[agent]["aerial_touches"] += 1
        self.events.append(game_events.AerialTouch(self.arena.tick_count, agent, round(float(car.pos[2]), 2)))

    def goal_counts(self) -> bool:
        return any(self.aerial_done.values())

    def miss_reason(self, ball: BallState) -> str | None:
        if (not self.arena.ball.is_frozen and not any(self.aerial_done.values())
                and ball.pos[2] <= C.BALL_RADIUS + BALL_FLOOR_MARGIN_UU):
            return "ball_on_ground"
        return None

    def mode_state(self) -> dict:
        frozen = self.arena.ball.is_frozen
        return {"ball_frozen": frozen,
                "release_in_s": max(self.release_after_s - self.round_time_s, 0.0) if frozen else 0.0,
                "release_after_s": self.release_after_s,
                "aerial_touch_done": dict(self.aerial_done), "touch_waiting_reset": dict(self.waiting_reset)}

    def scoreboard(self) -> dict:
        return {**super().scoreboard(), "aerial_touches": sum(s.get("aerial_touches", 0) for s in self.stats.values())}
