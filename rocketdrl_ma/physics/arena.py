"""The single-arena API, shaped like RocketSim's Python binding so RLGym users feel at home.

An ``Arena`` is a view on one arena of an ``ArenaBatch``; ``Arena()`` on its own makes a batch of one.
Game logic uses only this surface: controls and states, ``MutatorConfig``, typed events (``drain_events``),
boost pads (``get_boost_pads``), each car's last ball hit and bump cooldown.
"""
from __future__ import annotations

import numpy as np

from . import constants as C
from .arena_shape import DEFAULT_ARENA_SHAPE, shape_contains
from .world import PhysicsWorld, box_vector
from .car_config import CarConfig
from .car_kernel import (CS_AIR_TIME_SINCE_JUMP, CS_AUTOFLIP_SCALE, CS_AUTOFLIP_TIMER, CS_BOOST, CS_BOOSTING_TIME,
                         CS_DEMO_TIMER, CS_FLIP_TIME, CS_FLIP_TORQUE_X, CS_FLIP_TORQUE_Y, CS_HANDBRAKE,
                         CS_HAS_DOUBLE_JUMPED, CS_HAS_FLIPPED, CS_HAS_JUMPED, CS_IS_AUTOFLIPPING, CS_IS_DEMOED,
                         CS_IS_FLIPPING, CS_IS_JUMPING, CS_IS_SUPERSONIC, CS_JUMP_TIME, CS_LAST_JUMP, CS_ON_GROUND,
                         CS_SUPERSONIC_TIME, CS_TICK_MEMORY, CS_WHEEL_0)
from .events import PhysicsEvent
from .frames import team_spot
from .mutators import MutatorConfig
from .state import (BallHitInfo, BallState, BoostPadState, CarControls, CarExtraState, CarState, _trusted,
                    yaw_rot_mat)


def _check_inside(name: str, pos: np.ndarray, margin: float, arena_shape: str) -> None:
    if not shape_contains(arena_shape, float(pos[0]), float(pos[1]), float(pos[2]), margin):
        raise ValueError(f"{name}: position {pos.tolist()} is outside the arena")


class Car:
    """A car in an arena. Its identity is stable; its state lives in the batch arrays."""

    def __init__(self, batch: PhysicsWorld, car_id: int, team: int, config: CarConfig):
        self._batch, self.id, self.team, self.config = batch, car_id, team, config

    @property
    def _k(self) -> int:
        return self._batch._slot(self.id).index

    @property
    def batch_row(self) -> int:
        """This car's row in the batch's arrays (``ArenaBatch.controls``, ``ArenaBatch.arrays()``); it changes
        when a car is added to or removed from the batch."""
        return self._k

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
        b = self._batch
        _check_inside("pos", state.pos, 0.0, b.arena_shape)
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

    def get_extra_state(self) -> CarExtraState:
        b = self._batch
        cs = b.cs[self._k].tolist()
        slot = b._slot(self.id)
        victim = slot.contact_id
        cooldown = max(slot.contact_until - b.tick_count, 0) * b.dt if victim is not None else 0.0
        return CarExtraState(
            holding_jump=cs[CS_LAST_JUMP] > 0.5, boost_active_time_s=cs[CS_BOOSTING_TIME],
            flip_torque=(cs[CS_FLIP_TORQUE_X], cs[CS_FLIP_TORQUE_Y], 0.0),
            # The kernel, as RocketSim, lets the timer run a fraction of a tick below 0 before it stops the
            # auto-flip; at 0 the next tick stops it the same way.
            is_auto_flipping=cs[CS_IS_AUTOFLIPPING] > 0.5, auto_flip_timer_s=max(cs[CS_AUTOFLIP_TIMER], 0.0),
            auto_flip_direction=cs[CS_AUTOFLIP_SCALE], car_contact_id=victim, car_contact_cooldown_s=cooldown)

    def set_extra_state(self, extra: CarExtraState) -> None:
        """Restore what ``get_extra_state`` gave (after ``set_state``, which clears it)."""
        if not isinstance(extra, CarExtraState):
            raise ValueError(f"extra: expected CarExtraState, got {type(extra).__name__}")
        b = self._batch
        slot = b._slot(self.id)
        if extra.car_contact_id is not None:
            other = b._slot_by_id.get(extra.car_contact_id)
            if other is None or other.arena != slot.arena or other is slot:
                raise ValueError(f"car_contact_id: {extra.car_contact_id!r} is not another car of this arena")
        cs = b.cs[self._k]
        cs[CS_LAST_JUMP] = extra.holding_jump
        cs[CS_BOOSTING_TIME] = extra.boost_active_time_s
        cs[CS_FLIP_TORQUE_X], cs[CS_FLIP_TORQUE_Y] = extra.flip_torque[0], extra.flip_torque[1]
        cs[CS_IS_AUTOFLIPPING] = extra.is_auto_flipping
        cs[CS_AUTOFLIP_TIMER] = extra.auto_flip_timer_s
        cs[CS_AUTOFLIP_SCALE] = extra.auto_flip_direction
        slot.contact_id = extra.car_contact_id
        slot.contact_until = b.tick_count + int(round(extra.car_contact_cooldown_s * b.tick_rate))

    def get_ball_hit_info(self) -> BallHitInfo | None:
        """This car's last touch of the ball, or None if it has not touched it."""
        return self._batch._slot(self.id).ball_hit

    def demolish(self) -> None:
        self._batch.demolish(self.id)

    def respawn(self) -> None:
        self._batch.respawn(self.id)

    def __repr__(self) -> str:
        return f"Car(id={self.id}, team={self.team}, preset={self.config.name!r})"


class Ball:
    def __init__(self, batch: PhysicsWorld, arena: int):
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
        _check_inside("pos", state.pos, 0.0, self._batch.arena_shape)
        self._batch.set_ball(self._arena, state.pos, state.vel, state.ang_vel)

    def get_pos(self) -> np.ndarray:
        """The ball's centre (uu), a copy: cheaper than ``get_state`` when game logic needs only this."""
        self._batch._read_state()
        return self._batch.ball_pos[self._arena].copy()

    def get_vel(self) -> np.ndarray:
        self._batch._read_state()
        return self._batch.ball_vel[self._arena].copy()

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


class BoostPad:
    """One of the 34 boost pads of an arena, in the order of RocketSim's ``Arena.get_boost_pads()``."""

    def __init__(self, batch: PhysicsWorld, arena: int, index: int):
        self._batch, self._arena, self.index = batch, arena, index
        self.pos = C.BOOST_PAD_POSITIONS[index].copy()
        self.is_big = bool(C.BOOST_PAD_IS_BIG[index])

    def get_state(self) -> BoostPadState:
        return BoostPadState(cooldown_s=float(self._batch.pad_timer[self._arena, self.index]))

    def set_state(self, state: BoostPadState) -> None:
        if not isinstance(state, BoostPadState):
            raise ValueError(f"state: expected BoostPadState, got {type(state).__name__}")
        self._batch.pad_timer[self._arena, self.index] = state.cooldown_s

    def __repr__(self) -> str:
        return f"BoostPad(index={self.index}, pos={self.pos.tolist()}, is_big={self.is_big})"


class Arena:
    """One soccar arena: ``Arena(tick_rate=120)``, ``add_car``, ``step``, ``reset_kickoff`` (uu, z up)."""

    def __init__(self, tick_rate: int = C.TICK_RATE_HZ, seed: int | None = None,
                 arena_shape: str = DEFAULT_ARENA_SHAPE):
        batch = PhysicsWorld(1, tick_rate=tick_rate, seed=seed, arena_shape=arena_shape)
        self._init_view(batch, 0)
        batch.attach_lone_arena(self)

    @classmethod
    def _view(cls, batch: PhysicsWorld, index: int) -> "Arena":
        arena = cls.__new__(cls)
        arena._init_view(batch, index)
        return arena

    def _init_view(self, batch: PhysicsWorld, index: int) -> None:
        self._batch = batch
        self.index = index
        self.ball = Ball(batch, index)
        self._cars: list[Car] = []

    # ---- RocketSim-style API
    @property
    def batch(self) -> PhysicsWorld:
        """The batch this arena belongs to: its ``ArenaBatch``, or for a lone ``Arena`` its own world of one (the
        ``ArenaBatch`` machinery without other arenas)."""
        return self._batch

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

    def renew_world(self) -> None:
        """Move this arena onto a new PyBullet world with the same cars and settings and none of Bullet's memory of
        earlier ticks (``PhysicsWorld.renew_bullet_world``), after every car is set for a new episode: a used arena
        then replays exactly what a new one plays from the same states. An arena of an ``ArenaBatch`` shares its
        world with the others: renew the batch."""
        if self._batch.n_arenas != 1:
            raise ValueError(f"renew_world: this arena is one of an ArenaBatch of {self._batch.n_arenas}; "
                             f"renew the batch (ArenaBatch.renew_bullet_world)")
        self._batch.renew_bullet_world()

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
                x, y, yaw = team_spot(team, *C.KICKOFF_SPOTS_BLUE[perm[i]])
                car.set_state(CarState(pos=np.array([x, y, C.CAR_SPAWN_REST_Z]), rot_mat=yaw_rot_mat(yaw),
                                       boost=self.get_mutator_config().car_spawn_boost, on_ground=True,
                                       wheels_in_contact=(True, True, True, True)))
        self._batch.pad_timer[self.index] = 0.0
        self.ball.set_state(BallState())

    def scoring_team(self) -> int | None:
        """The team whose goal the ball is in (the whole ball past the line): 0 blue scored, 1 orange, or None."""
        y = self._batch.ball_pos[self.index, 1] if self._batch._state_fresh else self.ball.get_state().pos[1]
        threshold = self.get_mutator_config().goal_threshold_y
        if y > threshold + C.BALL_RADIUS:
            return 0
        if y < -(threshold + C.BALL_RADIUS):
            return 1
        return None

    def add_static_box(self, center: np.ndarray, half_extents: np.ndarray) -> int:
        """A fixed axis-aligned box (uu) the cars and the ball bounce off, e.g. a minigame barrier; returns its id.

        The centre of its top face must be inside the arena; the rest may reach into the floor (a low wall is
        a tall box sunk into it)."""
        half = box_vector("half_extents", half_extents)
        _check_inside("center + top half extent", box_vector("center", center) + [0.0, 0.0, half[2]], 0.0,
                      self._batch.arena_shape)
        return self._batch.add_static_box(self.index, center, half)

    def move_static_box(self, box_id: int, center: np.ndarray) -> None:
        """Move a static box (between rounds: it teleports, it does not push what is in the way); as in
        ``add_static_box``, the centre of its top face must be inside the arena."""
        top = box_vector("center", center) + [0.0, 0.0, self._batch.static_box_half_extents(box_id)[2]]
        _check_inside("center + top half extent", top, 0.0, self._batch.arena_shape)
        self._batch.move_static_box(box_id, center)

    def remove_static_box(self, box_id: int) -> None:
        self._batch.remove_static_box(box_id)

    # ---- game-mode settings, events, boost pads
    def set_mutator_config(self, config: MutatorConfig) -> None:
        """Play this arena with ``config`` (RocketSim's ``Arena.set_mutator_config``)."""
        self._batch.set_mutator_config(config, None if self._batch.n_arenas == 1 else self.index)

    def get_mutator_config(self) -> MutatorConfig:
        return self._batch.get_mutator_config(self.index)

    def drain_events(self) -> list[PhysicsEvent]:
        """This arena's events (``BallTouch``, ``Bump``, ``Demo``, ``BoostPickup``) since the last drain, in the
        order the ticks produced them; they are removed."""
        return self._batch.drain_events(self.index)

    def clear_events(self) -> None:
        self._batch.clear_events(self.index)

    def get_boost_pads(self) -> list[BoostPad]:
        """The 34 pads in RocketSim's ``Arena.get_boost_pads()`` order (RLGym's ``BOOST_LOCATIONS``)."""
        return [BoostPad(self._batch, self.index, k) for k in range(len(C.BOOST_PAD_POSITIONS))]

    def boost_pad_timers(self) -> np.ndarray:
        """Seconds until each of the 34 pads (``get_boost_pads`` order) is active again; 0 = active."""
        return self._batch.pad_timer[self.index].copy()

    def set_boost_pad_timers(self, timers_s: np.ndarray) -> None:
        t = np.asarray(timers_s, dtype=np.float64)
        if t.shape != (len(C.BOOST_PAD_POSITIONS),) or not np.all(np.isfinite(t)) or np.any(t < 0.0):
            raise ValueError(f"timers_s: expected {len(C.BOOST_PAD_POSITIONS)} finite numbers >= 0, got {timers_s!r}")
        self._batch.pad_timer[self.index] = t

    def close(self) -> None:
        self._batch.close()
