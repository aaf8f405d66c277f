"""The single-arena API, shaped like RocketSim's Python binding so RLGym users feel at home.

An ``Arena`` is a view on one arena of an ``ArenaBatch``; ``Arena()`` on its own makes a batch of one.
"""
from __future__ import annotations

import math

import numpy as np

from . import constants as C
from .arena_geometry import is_inside_arena
from .batch import ArenaBatch, _box_vector
from .car_config import CarConfig
from .car_kernel import (CS_AIR_TIME_SINCE_JUMP, CS_BOOST, CS_DEMO_TIMER, CS_FLIP_TIME, CS_HANDBRAKE,
                         CS_HAS_DOUBLE_JUMPED, CS_HAS_FLIPPED, CS_HAS_JUMPED, CS_IS_DEMOED, CS_IS_FLIPPING,
                         CS_IS_JUMPING, CS_IS_SUPERSONIC, CS_JUMP_TIME, CS_ON_GROUND, CS_SUPERSONIC_TIME,
                         CS_TICK_MEMORY, CS_WHEEL_0)
from .state import BallState, CarControls, CarState, _trusted, yaw_rot_mat


def _check_inside(name: str, pos: np.ndarray, margin: float) -> None:
    if not is_inside_arena(float(pos[0]), float(pos[1]), float(pos[2]), margin):
        raise ValueError(f"{name}: position {pos.tolist()} is outside the arena")


class Car:
    """A car in an arena. Its identity is stable; its state lives in the batch arrays."""

    def __init__(self, batch: ArenaBatch, car_id: int, team: int, config: CarConfig):
        self._batch, self.id, self.team, self.config = batch, car_id, team, config

    @property
    def _k(self) -> int:
        return self._batch._slot(self.id).index

    def set_controls(self, controls: CarControls) -> None:
        if not isinstance(controls, CarControls):
            raise ValueError(f"controls: expected CarControls, got {type(controls).__name__}")
        self._batch.controls[self._k] = controls.as_array()

    def get_controls(self) -> CarControls:
        c = self._batch.controls[self._k]
        return CarControls(*c[:5], jump=c[5] > 0.5, boost=c[6] > 0.5, handbrake=c[7] > 0.5)

    def get_state(self) -> CarState:
        b = self._batch
        b._read_state()
        k = self._k
        cs = b.cs[k].tolist()  # Python floats: indexing a list is far cheaper than NumPy scalars
        return _trusted(CarState, dict(
            pos=b.car_pos[k].copy(), vel=b.car_vel[k].copy(), ang_vel=b.car_ang_vel[k].copy(),
            rot_mat=b.car_rot[k].copy(), boost=float(cs[CS_BOOST]), on_ground=bool(cs[CS_ON_GROUND]),
            wheels_in_contact=(bool(cs[CS_WHEEL_0]), bool(cs[CS_WHEEL_0 + 1]), bool(cs[CS_WHEEL_0 + 2]),
                               bool(cs[CS_WHEEL_0 + 3])),
            has_jumped=bool(cs[CS_HAS_JUMPED]), has_double_jumped=bool(cs[CS_HAS_DOUBLE_JUMPED]),
            has_flipped=bool(cs[CS_HAS_FLIPPED]), is_jumping=bool(cs[CS_IS_JUMPING]),
            is_flipping=bool(cs[CS_IS_FLIPPING]), is_supersonic=bool(cs[CS_IS_SUPERSONIC]),
            is_demoed=bool(cs[CS_IS_DEMOED]), handbrake_value=float(cs[CS_HANDBRAKE]),
            jump_time=float(cs[CS_JUMP_TIME]), flip_time=float(cs[CS_FLIP_TIME]),
            air_time_since_jump=float(cs[CS_AIR_TIME_SINCE_JUMP]),
            supersonic_time=float(cs[CS_SUPERSONIC_TIME]), demo_respawn_timer=float(cs[CS_DEMO_TIMER])))

    def set_state(self, state: CarState) -> None:
        if not isinstance(state, CarState):
            raise ValueError(f"state: expected CarState, got {type(state).__name__}")
        _check_inside("pos", state.pos, 0.0)
        b = self._batch
        if state.is_demoed != bool(b.cs[self._k, CS_IS_DEMOED]):
            if state.is_demoed:
                b.demolish(self.id)
            else:
                b.respawn(self.id)
        b.set_car(self.id, state.pos, state.rot_mat, state.vel, state.ang_vel)
        cs = b.cs[self._k]
        cs[CS_BOOST] = state.boost
        cs[CS_ON_GROUND] = state.on_ground
        for w in range(4):
            cs[CS_WHEEL_0 + w] = state.wheels_in_contact[w]
        cs[CS_HAS_JUMPED] = state.has_jumped
        cs[CS_HAS_DOUBLE_JUMPED] = state.has_double_jumped
        cs[CS_HAS_FLIPPED] = state.has_flipped
        cs[CS_IS_JUMPING] = state.is_jumping
        cs[CS_IS_FLIPPING] = state.is_flipping
        cs[CS_IS_SUPERSONIC] = state.is_supersonic
        cs[CS_HANDBRAKE] = state.handbrake_value
        cs[CS_JUMP_TIME] = state.jump_time
        cs[CS_FLIP_TIME] = state.flip_time
        cs[CS_AIR_TIME_SINCE_JUMP] = state.air_time_since_jump
        cs[CS_SUPERSONIC_TIME] = state.supersonic_time
        cs[CS_DEMO_TIMER] = state.demo_respawn_timer if state.is_demoed else 0.0
        cs[list(CS_TICK_MEMORY)] = 0.0

    def demolish(self) -> None:
        self._batch.demolish(self.id)

    def respawn(self) -> None:
        self._batch.respawn(self.id)

    def __repr__(self) -> str:
        return f"Car(id={self.id}, team={self.team}, preset={self.config.name!r})"


class Ball:
    def __init__(self, batch: ArenaBatch, arena: int):
        self._batch, self._arena = batch, arena

    def get_state(self) -> BallState:
        b = self._batch
        b._read_state()
        k = self._arena
        return _trusted(BallState, dict(pos=b.ball_pos[k].copy(), vel=b.ball_vel[k].copy(),
                                        ang_vel=b.ball_ang_vel[k].copy()))

    def set_state(self, state: BallState) -> None:
        if not isinstance(state, BallState):
            raise ValueError(f"state: expected BallState, got {type(state).__name__}")
        _check_inside("pos", state.pos, 0.0)
        self._batch.set_ball(self._arena, state.pos, state.vel, state.ang_vel)

    @staticmethod
    def get_radius() -> float:
        return C.BALL_RADIUS

    @property
    def is_frozen(self) -> bool:
        """True while a ball placed at rest hangs where it is (until a touch or ``release``)."""
        return bool(self._batch.ball_frozen[self._arena])

    def release(self) -> None:
        """Let a hanging ball fall from where it is."""
        self._batch.ball_frozen[self._arena] = False


class Arena:
    """One soccar arena: ``Arena(tick_rate=120)``, ``add_car``, ``step``, ``reset_kickoff`` (uu, z up)."""

    def __init__(self, tick_rate: int = C.TICK_RATE_HZ, seed: int | None = None):
        batch = ArenaBatch(1, tick_rate=tick_rate, seed=seed)
        self._init_view(batch, 0)
        batch.arenas[0] = self

    @classmethod
    def _view(cls, batch: ArenaBatch, index: int) -> "Arena":
        arena = cls.__new__(cls)
        arena._init_view(batch, index)
        return arena

    def _init_view(self, batch: ArenaBatch, index: int) -> None:
        self._batch = batch
        self.index = index
        self.ball = Ball(batch, index)
        self._cars: list[Car] = []

    # ---- RocketSim-style API
    @property
    def tick_rate(self) -> int:
        return self._batch.tick_rate

    @property
    def tick_time(self) -> float:
        return self._batch.dt

    @property
    def tick_count(self) -> int:
        return self._batch.tick_count

    @property
    def cars(self) -> list[Car]:
        return list(self._cars)

    def add_car(self, team: int, preset: str | CarConfig = "octane") -> Car:
        car_id = self._batch.add_car(self.index, team, preset)
        slot = self._batch._slot(car_id)
        car = Car(self._batch, car_id, team, slot.config)
        self._cars.append(car)
        return car

    def remove_car(self, car: Car) -> None:
        if car not in self._cars:
            raise ValueError(f"car: {car!r} is not in this arena")
        self._batch.remove_car(car.id)
        self._cars.remove(car)

    def step(self, ticks: int = 1) -> None:
        if self._batch.n_arenas != 1:
            raise ValueError(f"step: this arena is one of an ArenaBatch of {self._batch.n_arenas}; step the batch")
        self._batch.step(ticks)

    def reseed(self, seed: int) -> None:
        """Restart this arena's own random stream (respawn spots, unseeded kickoffs) as ``Arena(seed=seed)`` starts it."""
        self._batch.arena_rngs[self.index] = np.random.default_rng(seed)

    def reset_kickoff(self, seed: int | None = None) -> None:
        """Standard kickoff: a random permutation of the 5 spots, car i of each team on spot i, orange mirrored."""
        rng = np.random.default_rng(seed) if seed is not None else self._batch.arena_rngs[self.index]
        perm = rng.permutation(len(C.KICKOFF_SPOTS_BLUE))
        per_team = {0: [c for c in self._cars if c.team == 0], 1: [c for c in self._cars if c.team == 1]}
        for team, cars in per_team.items():
            if len(cars) > len(C.KICKOFF_SPOTS_BLUE):
                raise ValueError(f"team {team}: at most {len(C.KICKOFF_SPOTS_BLUE)} cars per team for a kickoff")
            for i, car in enumerate(cars):
                x, y, yaw = C.KICKOFF_SPOTS_BLUE[perm[i]]
                if team == 1:
                    x, y, yaw = -x, -y, yaw + math.pi
                car.set_state(CarState(pos=np.array([x, y, C.CAR_SPAWN_REST_Z]), rot_mat=yaw_rot_mat(yaw),
                                       boost=C.BOOST_SPAWN_AMOUNT, on_ground=True,
                                       wheels_in_contact=(True, True, True, True)))
        self._batch.pad_timer[self.index] = 0.0
        self.ball.set_state(BallState())

    def scoring_team(self) -> int | None:
        """The team whose goal the ball is in (the whole ball past the line): 0 blue scored, 1 orange, or None."""
        y = self._batch.ball_pos[self.index, 1] if self._batch._state_fresh else self.ball.get_state().pos[1]
        if y > C.GOAL_SCORE_THRESHOLD_Y + C.BALL_RADIUS:
            return 0
        if y < -(C.GOAL_SCORE_THRESHOLD_Y + C.BALL_RADIUS):
            return 1
        return None

    def add_static_box(self, center: np.ndarray, half_extents: np.ndarray) -> int:
        """A fixed axis-aligned box (uu) the cars and the ball bounce off, e.g. a minigame barrier; returns its id.

        The centre of its top face must be inside the arena; the rest may reach into the floor (a low wall is
        a tall box sunk into it)."""
        half = _box_vector("half_extents", half_extents)
        _check_inside("center + top half extent", _box_vector("center", center) + [0.0, 0.0, half[2]], 0.0)
        return self._batch.add_static_box(self.index, center, half)

    def move_static_box(self, box_id: int, center: np.ndarray) -> None:
        """Move a static box (between rounds: it teleports, it does not push what is in the way); as in
        ``add_static_box``, the centre of its top face must be inside the arena."""
        top = _box_vector("center", center) + [0.0, 0.0, self._batch.static_box_half_extents(box_id)[2]]
        _check_inside("center + top half extent", top, 0.0)
        self._batch.move_static_box(box_id, center)

    def remove_static_box(self, box_id: int) -> None:
        self._batch.remove_static_box(box_id)

    def boost_pad_timers(self) -> np.ndarray:
        """Seconds until each of the 34 pads (RLBot order) is active again; 0 = active."""
        return self._batch.pad_timer[self.index].copy()

    def close(self) -> None:
        self._batch.close()
