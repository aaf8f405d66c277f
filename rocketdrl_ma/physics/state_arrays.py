"""The per-tick numbers of a ``PhysicsWorld`` as arrays over all cars and balls of all arenas (uu, uu/s, rad/s):
the car rows and their bookkeeping, adding and removing cars, reading the cars from PyBullet and writing them
back, and the read-only views game logic gets (``BatchArrays``)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pybullet as pb

from . import constants as C
from .body_io import read_rows, unpack_rows
from .bullet import M_PER_UU, BulletWorld
from .car_config import CarConfig, get_preset
from .car_kernel import (CS_AIR_TIME_SINCE_JUMP, CS_BOOST, CS_HAS_DOUBLE_JUMPED, CS_HAS_FLIPPED, CS_HAS_JUMPED,
                         CS_IS_DEMOED, CS_ON_GROUND, CS_SIZE, cancel_gyroscopic)
from .frames import rot_mat_to_quat
from .mutators import MutatorConfig
from .state import BallHitInfo


def _read_only(a: np.ndarray) -> np.ndarray:
    view = a.view()
    view.flags.writeable = False
    return view


class BatchArrays(NamedTuple):
    """``ArenaBatch.arrays()``: cars by batch row, balls and pad timers by arena (uu, uu/s, rad/s, s). The car
    state columns are floats, nonzero where the ``CarState`` flag of the same name is set."""
    car_pos: np.ndarray            # (cars, 3)
    car_vel: np.ndarray
    car_ang_vel: np.ndarray
    car_rot: np.ndarray            # (cars, 3, 3), columns forward, right, up
    car_boost: np.ndarray          # (cars,)
    car_on_ground: np.ndarray
    car_has_jumped: np.ndarray
    car_has_double_jumped: np.ndarray
    car_has_flipped: np.ndarray
    car_air_time_since_jump: np.ndarray
    car_is_demoed: np.ndarray
    car_arena: np.ndarray          # (cars,) int: the arena of each car
    ball_pos: np.ndarray           # (arenas, 3)
    ball_vel: np.ndarray
    ball_ang_vel: np.ndarray
    pad_timers: np.ndarray         # (arenas, 34): seconds until each pad is active again, 0 = active


class CarSlot:
    """Bookkeeping of one car body; its per-tick numbers live in the batch arrays at ``index``."""

    def __init__(self, car_id: int, arena: int, team: int, config: CarConfig, body: int):
        self.car_id, self.arena, self.team, self.config, self.body = car_id, arena, team, config, body
        self.index = -1
        self.ball_hit: BallHitInfo | None = None
        # RocketSim's car contact: the car this one last bumped or demolished, and the tick from which it may again
        self.contact_id: int | None = None
        self.contact_until = 0


class StateArrays:
    """The arrays of a ``PhysicsWorld`` (a base of it): balls, pad timers and one row per car, in the order the cars
    were added. Needs the world's ``bullet``, ``origins``, ``dt`` and ``_mutators``."""

    bullet: BulletWorld
    origins: np.ndarray
    dt: float
    _mutators: list[MutatorConfig]

    def _init_arrays(self, n_arenas: int) -> None:
        self.ball_pos = np.zeros((n_arenas, 3))
        self.ball_vel = np.zeros((n_arenas, 3))
        self.ball_ang_vel = np.zeros((n_arenas, 3))
        self.ball_frozen = np.zeros(n_arenas, dtype=bool)
        self._ball_pos_before = np.zeros((n_arenas, 3))  # where the balls were at the start of the last tick
        self.pad_timer = np.zeros((n_arenas, len(C.BOOST_PAD_POSITIONS)))
        self._slots: list[CarSlot] = []
        self._slot_by_body: dict[int, CarSlot] = {}
        self._slot_by_id: dict[int, CarSlot] = {}
        self._next_car_id = 0
        self._rebuild_car_arrays()
        self._state_fresh = False

    def add_car(self, arena: int, team: int, config: CarConfig | str) -> int:
        if team not in (0, 1):
            raise ValueError(f"team: must be 0 (blue) or 1 (orange), got {team!r}")
        cfg = get_preset(config) if isinstance(config, str) else config
        body = self.bullet.create_car_body(arena, cfg)
        slot = CarSlot(self._next_car_id, arena, team, cfg, body)
        self._next_car_id += 1
        old = self._snapshot_car_arrays()
        self._slots.append(slot)
        self._slot_by_body[body] = slot
        self._slot_by_id[slot.car_id] = slot
        self._rebuild_car_arrays(old)
        self.cs[slot.index, CS_BOOST] = self._mutators[arena].car_spawn_boost
        return slot.car_id

    def remove_car(self, car_id: int) -> None:
        slot = self._slot(car_id)
        old = self._snapshot_car_arrays()
        self.bullet.remove_body(slot.body)
        self._slots.remove(slot)
        del self._slot_by_body[slot.body]
        del self._slot_by_id[car_id]
        for other in self._slots:
            if other.contact_id == car_id:
                other.contact_id = None
        self._rebuild_car_arrays(old)

    #: the per-car arrays a rebuild carries over: the pose and velocities as they are (not read back from PyBullet,
    #: which rounds a pose that was just set), the state memory, controls and extra-hit tick
    _CARRIED_CAR_ARRAYS = ("car_pos", "car_quat", "car_rot", "car_vel", "car_ang_vel", "cs", "controls",
                           "last_extra_hit_tick")

    def _snapshot_car_arrays(self) -> dict[int, dict[str, np.ndarray]]:
        """Each car's rows of ``_CARRIED_CAR_ARRAYS``, to carry over a rebuild of the arrays."""
        self._read_state()
        return {s.car_id: {name: getattr(self, name)[s.index].copy() for name in self._CARRIED_CAR_ARRAYS}
                for s in self._slots if s.index >= 0}

    def _rebuild_car_arrays(self, old: dict[int, dict[str, np.ndarray]] | None = None) -> None:
        n = len(self._slots)
        self.car_pos = np.zeros((n, 3))
        self.car_rot = np.zeros((n, 3, 3))
        self.car_quat = np.zeros((n, 4))
        self.car_vel = np.zeros((n, 3))
        self.car_ang_vel = np.zeros((n, 3))
        self._ang_vel_out = np.zeros((n, 3))  # what is handed to PyBullet: car_ang_vel less its gyroscopic step
        self.controls = np.zeros((n, 8))
        self.cs = np.zeros((n, CS_SIZE))
        self.car_arena = np.array([s.arena for s in self._slots], dtype=np.int64)
        self.car_active = np.ones(n, dtype=np.bool_)
        self.pad_picked = np.full(n, -1, dtype=np.int64)
        self.pad_gained = np.zeros(n)
        self.last_extra_hit_tick = np.full(n, -10, dtype=np.int64)  # the last tick a car gave the extra push
        self.hitbox_half = np.array([np.array(s.config.hitbox_size) * 0.5 for s in self._slots]).reshape(n, 3)
        self.hitbox_offset = np.array([s.config.hitbox_offset for s in self._slots], dtype=np.float64).reshape(n, 3)
        # What the ball kernel reports per car each tick
        self._touched = np.zeros(n, dtype=np.bool_)
        self._touch_point = np.zeros((n, 3))
        self._touch_normal = np.zeros((n, 3))
        self._extra_vel = np.zeros((n, 3))
        self._car_push = np.zeros((n, 3))
        wheels = [s.config.wheel_table() for s in self._slots]
        self.wheel_conn = np.array([w["connection"] for w in wheels]).reshape(n, 4, 3)
        self.wheel_rest = np.array([w["rest_length"] for w in wheels]).reshape(n, 4)
        self.wheel_radius = np.array([w["radius"] for w in wheels]).reshape(n, 4)
        self.wheel_ray_len = np.array([w["ray_length"] for w in wheels]).reshape(n, 4)
        self.wheel_is_front = np.array([w["is_front"] for w in wheels], dtype=np.bool_).reshape(n, 4)
        self.inv_inertia = np.array([1.0 / (s.config.inertia_diag * C.UU_PER_M**2) for s in self._slots]).reshape(n, 3)
        self.three_wheel = np.array([s.config.three_wheel for s in self._slots], dtype=np.bool_)
        self._car_bodies = [s.body for s in self._slots]
        self._car_rows = np.arange(n, dtype=np.int64)
        added = []
        for k, s in enumerate(self._slots):
            s.index = k
            if old and s.car_id in old:
                for name, row in old[s.car_id].items():
                    getattr(self, name)[k] = row
            else:
                added.append(k)
        if added:
            unpack_rows(read_rows([self._slots[k].body for k in added], self.bullet.client),
                        np.array(added, dtype=np.int64), self.origins, self.car_arena, self.car_pos, self.car_quat,
                        self.car_rot, self.car_vel, self.car_ang_vel)
        self._state_fresh = True

    def _slot(self, car_id: int) -> CarSlot:
        slot = self._slot_by_id.get(car_id)
        if slot is None:
            raise ValueError(f"car: no car with id {car_id} in this batch")
        return slot

    # ------------------------------------------------------------------ state I/O (uu <-> metres)
    def _read_state(self) -> None:
        """Refresh every car from PyBullet (no-op while the arrays are current); the balls are the arrays."""
        if self._state_fresh:
            return
        self._read_cars()
        self._state_fresh = True

    def _read_cars(self) -> None:
        unpack_rows(read_rows(self._car_bodies, self.bullet.client), self._car_rows, self.origins, self.car_arena,
                    self.car_pos, self.car_quat, self.car_rot, self.car_vel, self.car_ang_vel)

    def _write_car_velocities(self, all_writable: bool) -> None:
        """Every active, non-demolished car's velocities to PyBullet (``all_writable``: that is every car)."""
        cid = self.bullet.client
        reset_velocity = pb.resetBaseVelocity
        vel = (self.car_vel * M_PER_UU).tolist()
        writable = self.car_active & (self.cs[:, CS_IS_DEMOED] == 0.0)
        cancel_gyroscopic(self.car_ang_vel, self.car_rot, self.inv_inertia, writable, self.dt, self._ang_vel_out)
        ang = self._ang_vel_out.tolist()
        if all_writable:
            for body, v, w in zip(self._car_bodies, vel, ang):
                reset_velocity(body, v, w, cid)
            return
        for body, ok, v, w in zip(self._car_bodies, writable.tolist(), vel, ang):
            if ok:
                reset_velocity(body, v, w, cid)

    def set_ball(self, arena: int, pos: np.ndarray, vel: np.ndarray, ang_vel: np.ndarray) -> None:
        self.ball_pos[arena], self.ball_vel[arena], self.ball_ang_vel[arena] = pos, vel, ang_vel
        # Like the game, a ball placed at rest hangs where it is until something touches it.
        self.ball_frozen[arena] = not (np.any(vel) or np.any(ang_vel))

    def set_car(self, car_id: int, pos: np.ndarray, rot: np.ndarray, vel: np.ndarray, ang_vel: np.ndarray) -> None:
        self._read_state()
        s = self._slot(car_id)
        k = s.index
        cid = self.bullet.client
        world = (pos + self.origins[s.arena]) * M_PER_UU
        pb.resetBasePositionAndOrientation(s.body, world.tolist(), rot_mat_to_quat(rot), physicsClientId=cid)
        pb.resetBaseVelocity(s.body, (vel * M_PER_UU).tolist(), ang_vel.tolist(), physicsClientId=cid)
        self.car_pos[k], self.car_rot[k], self.car_vel[k], self.car_ang_vel[k] = pos, rot, vel, ang_vel
        self.car_quat[k] = rot_mat_to_quat(rot)

    def pybullet_car_bodies(self) -> list[int]:
        """The cars' body ids (by batch row) in the PyBullet world ``client``, for benchmarks that step the bare
        world; the physics owns these bodies. (The balls are not PyBullet bodies.)"""
        return list(self._car_bodies)

    def arrays(self) -> BatchArrays:
        """Read-only views of every car and ball of the batch, current after the last tick or state change, for
        code that handles all arenas at once (batched observations). Car rows are ``Car.batch_row``; they stay valid
        until a car is added or removed."""
        self._read_state()
        cs = self.cs
        return BatchArrays(*(_read_only(a) for a in (
            self.car_pos, self.car_vel, self.car_ang_vel, self.car_rot, cs[:, CS_BOOST], cs[:, CS_ON_GROUND],
            cs[:, CS_HAS_JUMPED], cs[:, CS_HAS_DOUBLE_JUMPED], cs[:, CS_HAS_FLIPPED], cs[:, CS_AIR_TIME_SINCE_JUMP],
            cs[:, CS_IS_DEMOED], self.car_arena, self.ball_pos, self.ball_vel, self.ball_ang_vel, self.pad_timer)))
