"""Many soccar arenas in one PyBullet world, stepped together: the machinery under ``Arena`` and ``ArenaBatch``.

Each arena sits at its own origin on a grid far enough apart that nothing crosses over; the floor
and ceiling planes are shared. Every per-tick quantity is held as arrays over all cars (or balls)
of all arenas, so the car model runs as one compiled kernel and a lone ``Arena`` is simply a batch
of one. Rocket League units (uu) everywhere outside this module's PyBullet calls, which use metres.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pybullet as pb
from numba import njit

from . import constants as C
from .arena_geometry import arena_mesh
from .body_io import read_rows, unpack_rows
from .car_config import CarConfig, get_preset
from .car_kernel import (CS_AIR_TIME_SINCE_JUMP, CS_BODY_CONTACT, CS_BODY_NORMAL_X, CS_BOOST, CS_DEMO_TIMER,
                         CS_HAS_DOUBLE_JUMPED, CS_HAS_FLIPPED, CS_HAS_JUMPED, CS_IS_DEMOED, CS_IS_SUPERSONIC,
                         CS_ON_GROUND, CS_SIZE, boost_pad_tick, car_post_tick, car_pre_tick, interp)
from .events import BallTouch, BoostPickup, Bump, Demo, PhysicsEvent
from .mutators import MUT_BALL_MAX_SPEED, DemoMode, MutatorConfig
from .state import BallHitInfo

M_PER_UU = 1.0 / C.UU_PER_M
ARENA_SPACING_UU = 20000.0  # arenas are ~8200 x 12000 uu; the gap keeps every body in its own arena
ARENA_GRID_COLUMNS = 8
# Bullet applies restitution to the approach speed before this tick's gravity; 0.575 gives the game's
# measured floor bounce of 0.60 (RocketSim: v_out / v_in = 0.5998) at 120 Hz.
BALL_RESTITUTION_BULLET = 0.575
_BALL_HIT_CURVE = np.array(C.BALL_HIT_SCALE_CURVE)
_BUMP_GROUND = np.array(C.BUMP_VEL_CURVE_GROUND)
_BUMP_AIR = np.array(C.BUMP_VEL_CURVE_AIR)
_BUMP_UP = np.array(C.BUMP_UPWARD_VEL_CURVE)


@njit(cache=True)
def ball_post_tick(pos, vel, ang_vel, frozen, frozen_pos, dirty, mut):
    """Hold frozen balls still and apply the speed and spin caps; ``dirty`` marks balls to write back.

    Returns how many are dirty."""
    n_dirty = 0
    for k in range(vel.shape[0]):
        dirty[k] = False
        if frozen[k]:
            pos[k] = frozen_pos[k]
            vel[k] = 0.0
            ang_vel[k] = 0.0
            continue
        speed = np.sqrt(vel[k, 0] ** 2 + vel[k, 1] ** 2 + vel[k, 2] ** 2)
        max_speed = mut[k, MUT_BALL_MAX_SPEED]
        if speed > max_speed:
            vel[k] *= max_speed / speed
            dirty[k] = True
        spin = np.sqrt(ang_vel[k, 0] ** 2 + ang_vel[k, 1] ** 2 + ang_vel[k, 2] ** 2)
        if spin > C.BALL_MAX_ANG_SPEED:
            ang_vel[k] *= C.BALL_MAX_ANG_SPEED / spin
            dirty[k] = True
        n_dirty += dirty[k]
    return n_dirty


@njit(cache=True)
def post_tick_kernels(ball_pos, ball_vel, ball_ang_vel, ball_frozen, ball_frozen_pos, ball_dirty, car_pos, car_vel,
                      car_ang_vel, car_arena, car_active, cs, pad_timer, pad_picked, pad_gained, mut, dt):
    """The compiled after-step work of one tick in one call: ``ball_post_tick``, ``car_post_tick`` and
    ``boost_pad_tick``. Returns (balls to write back, cars due to respawn, pads picked up)."""
    n_dirty = ball_post_tick(ball_pos, ball_vel, ball_ang_vel, ball_frozen, ball_frozen_pos, ball_dirty, mut)
    respawn_due = 0
    n_picked = 0
    if car_pos.shape[0] > 0:
        respawn_due = car_post_tick(car_vel, car_ang_vel, car_active, cs, dt)
        n_picked = boost_pad_tick(car_pos, car_arena, car_active, cs, C.BOOST_PAD_POSITIONS, C.BOOST_PAD_IS_BIG,
                                  pad_timer, pad_picked, pad_gained, mut, dt)
    return n_dirty, respawn_due, n_picked


@njit(cache=True)
def hold_frozen_arrays(frozen, ball_pos, ball_vel, frozen_pos, hold_vel):
    """Frozen balls ``frozen`` (indices) back at their place with the velocity that cancels a tick's gravity."""
    for k in frozen:
        ball_pos[k] = frozen_pos[k]
        ball_vel[k] = hold_vel


def mat_to_quat(m: np.ndarray) -> tuple[float, float, float, float]:
    """Rotation matrix to an xyzw quaternion (Shepperd's method)."""
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        q = 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        q = (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        q = (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def _box_vector(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected 3 finite numbers (uu), got {value!r}")
    return arr


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


class _CarSlot:
    """Bookkeeping of one car body; its per-tick numbers live in the batch arrays at ``index``."""

    def __init__(self, car_id: int, arena: int, team: int, config: CarConfig, body: int):
        self.car_id, self.arena, self.team, self.config, self.body = car_id, arena, team, config, body
        self.index = -1
        self.last_ball_hit_tick = -10  # the last tick the extra hit impulse was applied
        self.ball_hit: BallHitInfo | None = None
        self.cooldown_until: dict[int, int] = {}  # other car id -> tick when bumps may happen again
        self.last_victim: int | None = None  # the car this one last bumped or demolished


class PhysicsWorld:
    """``n_arenas`` independent soccar arenas in one PyBullet client, stepped by one ``stepSimulation``.

    ``arenas`` holds the ``Arena`` views of whoever made the world (``ArenaBatch`` makes one per arena; a lone
    ``Arena`` is the view of its own world of one); ``step(ticks)`` advances all.
    """

    def __init__(self, n_arenas: int = 1, tick_rate: int = C.TICK_RATE_HZ, seed: int | None = None):
        if not isinstance(n_arenas, int) or n_arenas < 1:
            raise ValueError(f"n_arenas: must be an int >= 1, got {n_arenas!r}")
        if tick_rate != C.TICK_RATE_HZ:
            raise ValueError(f"tick_rate: only {C.TICK_RATE_HZ} Hz is supported (the game's rate), got {tick_rate!r}")
        self.n_arenas = n_arenas
        self.tick_rate = tick_rate
        self.dt = 1.0 / tick_rate
        self.tick_count = 0
        self._mutators = [MutatorConfig()] * n_arenas
        self.mutator_rows = np.tile(self._mutators[0].as_row(), (n_arenas, 1))
        self.rng = np.random.default_rng(seed)
        # Each arena's own random stream (respawn spots, unseeded kickoffs); all share ``rng`` unless given their
        # own, which makes an arena of a batch draw exactly what a lone Arena with that seed draws.
        self.arena_rngs: list[np.random.Generator] = [self.rng] * n_arenas
        self.client = pb.connect(pb.DIRECT)
        cid = self.client
        pb.setGravity(0, 0, C.GRAVITY_Z * M_PER_UU, physicsClientId=cid)
        pb.setPhysicsEngineParameter(fixedTimeStep=self.dt, numSubSteps=0, numSolverIterations=10,
                                     deterministicOverlappingPairs=1, physicsClientId=cid)
        self.origins = np.array([[(k % ARENA_GRID_COLUMNS) * ARENA_SPACING_UU,
                                  (k // ARENA_GRID_COLUMNS) * ARENA_SPACING_UU, 0.0] for k in range(n_arenas)])
        self._build_static_world()
        self._static_boxes: dict[int, int] = {}  # PyBullet body id -> arena index
        self._static_half_extents: dict[int, np.ndarray] = {}  # PyBullet body id -> half extents (uu)
        self._ball_bodies = [self._make_ball(k) for k in range(n_arenas)]
        self.ball_pos = np.zeros((n_arenas, 3))
        self.ball_vel = np.zeros((n_arenas, 3))
        self.ball_ang_vel = np.zeros((n_arenas, 3))
        self.ball_frozen = np.zeros(n_arenas, dtype=bool)
        self._ball_frozen_pos = np.zeros((n_arenas, 3))
        self._ball_dirty = np.zeros(n_arenas, dtype=bool)
        # What holding a frozen ball writes each tick, computed once when it is frozen (metres, PyBullet's frame).
        self._ball_hold_vel = np.array([0.0, 0.0, -C.GRAVITY_Z * self.dt])
        self._ball_hold_vel_m = (self._ball_hold_vel * M_PER_UU).tolist()
        self._ball_hold_pos_m: list[list[float]] = [[0.0, 0.0, 0.0]] * n_arenas
        self._read_plan: tuple[bytes, list[int], np.ndarray] | None = None  # see _read_plan_for
        self.pad_timer = np.zeros((n_arenas, len(C.BOOST_PAD_POSITIONS)))
        self._slots: list[_CarSlot] = []
        self._slot_by_body: dict[int, _CarSlot] = {}
        self._slot_by_id: dict[int, _CarSlot] = {}
        self._ball_arena = {b: k for k, b in enumerate(self._ball_bodies)}
        self._next_car_id = 0
        self._rebuild_car_arrays()
        self._state_fresh = False
        self._events: list[list[PhysicsEvent]] = [[] for _ in range(n_arenas)]  # per arena, since the last drain
        self.arenas: list = []  # the Arena views, filled in by their maker
        for k in range(n_arenas):
            self.set_ball(k, np.array([0.0, 0.0, C.BALL_REST_Z]), np.zeros(3), np.zeros(3))

    # ------------------------------------------------------------------ construction
    def _build_static_world(self) -> None:
        cid = self.client
        verts, idx = arena_mesh(with_floor_and_ceiling=False)  # the planes below are the floor and ceiling
        shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=(verts * M_PER_UU).tolist(),
                                        indices=idx.reshape(-1).tolist(), flags=pb.GEOM_FORCE_CONCAVE_TRIMESH,
                                        physicsClientId=cid)
        floor = pb.createCollisionShape(pb.GEOM_PLANE, planeNormal=[0, 0, 1], physicsClientId=cid)
        ceiling = pb.createCollisionShape(pb.GEOM_PLANE, planeNormal=[0, 0, -1], physicsClientId=cid)
        self._static_bodies = [
            pb.createMultiBody(0, floor, basePosition=[0, 0, 0], physicsClientId=cid),
            pb.createMultiBody(0, ceiling, basePosition=[0, 0, C.ARENA_HEIGHT * M_PER_UU], physicsClientId=cid)]
        for origin in self.origins:
            self._static_bodies.append(
                pb.createMultiBody(0, shape, basePosition=(origin * M_PER_UU).tolist(), physicsClientId=cid))
        # Bullet multiplies both bodies' materials; the arena's 1.0 lets each body's own value through.
        self._static_set = set(self._static_bodies)
        for body in self._static_bodies:
            pb.changeDynamics(body, -1, lateralFriction=1.0, restitution=1.0, rollingFriction=0.0,
                              spinningFriction=0.0, physicsClientId=cid)

    def _make_ball(self, arena: int) -> int:
        cid = self.client
        shape = pb.createCollisionShape(pb.GEOM_SPHERE, radius=C.BALL_RADIUS * M_PER_UU, physicsClientId=cid)
        body = pb.createMultiBody(C.BALL_MASS, shape, basePosition=(self.origins[arena] * M_PER_UU).tolist(),
                                  useMaximalCoordinates=True, physicsClientId=cid)
        pb.changeDynamics(body, -1, lateralFriction=C.BALL_FRICTION, restitution=BALL_RESTITUTION_BULLET,
                          linearDamping=C.BALL_DRAG, angularDamping=0.0, rollingFriction=0.0, spinningFriction=0.0,
                          activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=cid)
        return body

    def add_car(self, arena: int, team: int, config: CarConfig | str) -> int:
        if team not in (0, 1):
            raise ValueError(f"team: must be 0 (blue) or 1 (orange), got {team!r}")
        cfg = get_preset(config) if isinstance(config, str) else config
        cid = self.client
        half = [s * 0.5 * M_PER_UU for s in cfg.hitbox_size]
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half,
                                        collisionFramePosition=[o * M_PER_UU for o in cfg.hitbox_offset],
                                        physicsClientId=cid)
        start = self.origins[arena] + np.array([0.0, 0.0, C.CAR_SPAWN_REST_Z])
        body = pb.createMultiBody(C.CAR_MASS, shape, basePosition=(start * M_PER_UU).tolist(),
                                  useMaximalCoordinates=True, physicsClientId=cid)
        self._set_car_dynamics(body, cfg)
        slot = _CarSlot(self._next_car_id, arena, team, cfg, body)
        self._next_car_id += 1
        self._state_fresh = False  # the arrays are rebuilt from the bodies
        self._read_state()
        self._slots.append(slot)
        self._slot_by_body[body] = slot
        self._slot_by_id[slot.car_id] = slot
        old = self._snapshot_car_arrays()
        self._rebuild_car_arrays(old)
        self.cs[slot.index, CS_BOOST] = self._mutators[arena].car_spawn_boost
        self._read_state()
        return slot.car_id

    def _set_car_dynamics(self, body: int, cfg: CarConfig) -> None:
        # Restitution 0 makes car-ball hits inelastic as in the game; Bullet can't set materials per pair.
        pb.changeDynamics(body, -1, mass=C.CAR_MASS, localInertiaDiagonal=cfg.inertia_diag.tolist(),
                          lateralFriction=C.CAR_WORLD_FRICTION, restitution=0.0, linearDamping=0.0,
                          angularDamping=0.0, rollingFriction=0.0, spinningFriction=0.0,
                          activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=self.client)

    def remove_car(self, car_id: int) -> None:
        slot = self._slot(car_id)
        self._read_state()
        old = self._snapshot_car_arrays()
        pb.removeBody(slot.body, physicsClientId=self.client)
        self._slots.remove(slot)
        del self._slot_by_body[slot.body]
        del self._slot_by_id[car_id]
        for other in self._slots:
            other.cooldown_until.pop(car_id, None)
        self._rebuild_car_arrays(old)

    def _snapshot_car_arrays(self) -> dict[int, tuple]:
        return {s.car_id: (self.cs[s.index].copy(), self.controls[s.index].copy())
                for s in self._slots if s.index >= 0}

    def _rebuild_car_arrays(self, old: dict[int, tuple] | None = None) -> None:
        n = len(self._slots)
        self.car_pos = np.zeros((n, 3))
        self.car_rot = np.zeros((n, 3, 3))
        self.car_quat = np.zeros((n, 4))
        self.car_vel = np.zeros((n, 3))
        self.car_ang_vel = np.zeros((n, 3))
        self.controls = np.zeros((n, 8))
        self.cs = np.zeros((n, CS_SIZE))
        self.car_arena = np.array([s.arena for s in self._slots], dtype=np.int64)
        self.car_active = np.ones(n, dtype=np.bool_)
        self.pad_picked = np.full(n, -1, dtype=np.int64)
        self.pad_gained = np.zeros(n)
        wheels = [s.config.wheel_table() for s in self._slots]
        self.wheel_conn = np.array([w["connection"] for w in wheels]).reshape(n, 4, 3)
        self.wheel_rest = np.array([w["rest_length"] for w in wheels]).reshape(n, 4)
        self.wheel_radius = np.array([w["radius"] for w in wheels]).reshape(n, 4)
        self.wheel_ray_len = np.array([w["ray_length"] for w in wheels]).reshape(n, 4)
        self.wheel_is_front = np.array([w["is_front"] for w in wheels], dtype=np.bool_).reshape(n, 4)
        self.inv_inertia = np.array([1.0 / (s.config.inertia_diag * C.UU_PER_M**2) for s in self._slots]).reshape(n, 3)
        self.three_wheel = np.array([s.config.three_wheel for s in self._slots], dtype=np.bool_)
        self._car_bodies = [s.body for s in self._slots]
        self._read_plan = None
        for k, s in enumerate(self._slots):
            s.index = k
            if old and s.car_id in old:
                self.cs[k], self.controls[k] = old[s.car_id]
        self._state_fresh = False

    def _slot(self, car_id: int) -> _CarSlot:
        slot = self._slot_by_id.get(car_id)
        if slot is None:
            raise ValueError(f"car: no car with id {car_id} in this batch")
        return slot

    # ------------------------------------------------------------------ state I/O (uu <-> metres)
    def _read_state(self) -> None:
        """Refresh every ball and car from PyBullet (no-op while the arrays are current)."""
        if self._state_fresh:
            return
        self._read_bodies(self._ball_bodies + self._car_bodies,
                          np.arange(self.n_arenas + len(self._car_bodies), dtype=np.int64))
        self._state_fresh = True

    def _read_bodies(self, bodies: list[int], targets: np.ndarray) -> None:
        """Read ``bodies`` into the arrays: target ``t < n_arenas`` is ball ``t``, else car ``t - n_arenas``."""
        unpack_rows(read_rows(bodies, self.client), targets, self.n_arenas, self.origins, self.car_arena,
                    self.ball_pos, self.ball_vel, self.ball_ang_vel, self.car_pos, self.car_quat, self.car_rot,
                    self.car_vel, self.car_ang_vel)

    def _read_plan_for(self, frozen: np.ndarray) -> tuple[list[int], np.ndarray]:
        """The bodies a tick reads after its step: every car, and the balls not frozen (``ball_post_tick`` puts
        a frozen ball back in place anyway). Kept until the frozen set or the cars change."""
        key = frozen.tobytes()
        if self._read_plan is None or self._read_plan[0] != key:
            balls = np.flatnonzero(~frozen).tolist()
            targets = np.array(balls + list(range(self.n_arenas, self.n_arenas + len(self._car_bodies))),
                               dtype=np.int64)
            self._read_plan = (key, [self._ball_bodies[k] for k in balls] + self._car_bodies, targets)
        return self._read_plan[1], self._read_plan[2]

    def _write_car_velocities(self, all_writable: bool) -> None:
        """Every active, non-demolished car's velocities to PyBullet (``all_writable``: that is every car)."""
        cid = self.client
        reset_velocity = pb.resetBaseVelocity
        vel = (self.car_vel * M_PER_UU).tolist()
        ang = self.car_ang_vel.tolist()
        if all_writable:
            for body, v, w in zip(self._car_bodies, vel, ang):
                reset_velocity(body, v, w, cid)
            return
        writable = (self.car_active & (self.cs[:, CS_IS_DEMOED] == 0.0)).tolist()
        for body, ok, v, w in zip(self._car_bodies, writable, vel, ang):
            if ok:
                reset_velocity(body, v, w, cid)

    def _write_ball(self, k: int, position: bool = False) -> None:
        cid = self.client
        body = self._ball_bodies[k]
        if position:
            pb.resetBasePositionAndOrientation(body, ((self.ball_pos[k] + self.origins[k]) * M_PER_UU).tolist(),
                                               (0, 0, 0, 1), physicsClientId=cid)
        pb.resetBaseVelocity(body, (self.ball_vel[k] * M_PER_UU).tolist(), self.ball_ang_vel[k].tolist(),
                             physicsClientId=cid)

    def _hold_frozen_balls(self, frozen: np.ndarray) -> None:
        """Put every frozen ball back in place with a velocity that cancels this tick's gravity, so it stays
        exactly where it is (the arithmetic of ``_write_ball``, done once when the ball was frozen)."""
        cid = self.client
        reset_pose, reset_velocity = pb.resetBasePositionAndOrientation, pb.resetBaseVelocity
        hold_frozen_arrays(frozen, self.ball_pos, self.ball_vel, self._ball_frozen_pos, self._ball_hold_vel)
        for k in frozen.tolist():
            body = self._ball_bodies[k]
            reset_pose(body, self._ball_hold_pos_m[k], (0, 0, 0, 1), cid)
            reset_velocity(body, self._ball_hold_vel_m, self.ball_ang_vel[k].tolist(), cid)

    def set_ball(self, arena: int, pos: np.ndarray, vel: np.ndarray, ang_vel: np.ndarray) -> None:
        self._read_state()
        self.ball_pos[arena], self.ball_vel[arena], self.ball_ang_vel[arena] = pos, vel, ang_vel
        # Like the game, a ball placed at rest hangs where it is until something touches it.
        self.ball_frozen[arena] = not (np.any(vel) or np.any(ang_vel))
        self._ball_frozen_pos[arena] = pos
        self._ball_hold_pos_m[arena] = ((self._ball_frozen_pos[arena] + self.origins[arena]) * M_PER_UU).tolist()
        self._write_ball(arena, position=True)

    def set_car(self, car_id: int, pos: np.ndarray, rot: np.ndarray, vel: np.ndarray, ang_vel: np.ndarray) -> None:
        self._read_state()
        s = self._slot(car_id)
        k = s.index
        world = (pos + self.origins[s.arena]) * M_PER_UU
        pb.resetBasePositionAndOrientation(s.body, world.tolist(), mat_to_quat(rot), physicsClientId=self.client)
        pb.resetBaseVelocity(s.body, (vel * M_PER_UU).tolist(), ang_vel.tolist(), physicsClientId=self.client)
        self.car_pos[k], self.car_rot[k], self.car_vel[k], self.car_ang_vel[k] = pos, rot, vel, ang_vel
        self.car_quat[k] = mat_to_quat(rot)

    # ------------------------------------------------------------------ the tick
    def step(self, ticks: int = 1) -> None:
        if not isinstance(ticks, (int, np.integer)) or ticks < 0:
            raise ValueError(f"ticks: must be an int >= 0, got {ticks!r}")
        cid = self.client
        step_simulation = pb.stepSimulation
        for _ in range(ticks):
            self._read_state()
            if self._slots:
                unwritable = car_pre_tick(self.car_pos, self.car_rot, self.car_vel, self.car_ang_vel, self.controls,
                                          self.wheel_conn, self.wheel_rest, self.wheel_radius, self.wheel_ray_len,
                                          self.wheel_is_front, self.inv_inertia, self.three_wheel, self.car_arena,
                                          self.car_active, self.ball_pos, C.BALL_RADIUS, self.cs,
                                          self.mutator_rows, self.dt)
                self._write_car_velocities(unwritable == 0)
            frozen = self.ball_frozen.nonzero()[0]
            if len(frozen):
                self._hold_frozen_balls(frozen)
            step_simulation(cid)
            self.tick_count += 1
            touches, car_pairs = self._classify_contacts(pb.getContactPoints(physicsClientId=cid))
            if touches or car_pairs:
                # RocketSim scores a car's touch from the velocities at contact, before the solver resolves it:
                # the arrays still hold them until the read below.
                self._pre_step = (self.car_pos.copy(), self.car_vel.copy(), self.ball_pos.copy(),
                                  self.ball_vel.copy())
            self._read_bodies(*self._read_plan_for(self.ball_frozen))
            self._state_fresh = True
            if touches or car_pairs:
                self._hits(touches, car_pairs)
            self._post_tick()

    def _post_tick(self) -> None:
        n_dirty, respawn_due, picked = post_tick_kernels(
            self.ball_pos, self.ball_vel, self.ball_ang_vel, self.ball_frozen, self._ball_frozen_pos, self._ball_dirty,
            self.car_pos, self.car_vel, self.car_ang_vel, self.car_arena, self.car_active, self.cs,
            self.pad_timer, self.pad_picked, self.pad_gained, self.mutator_rows, self.dt)
        if n_dirty:
            for k in self._ball_dirty.nonzero()[0].tolist():
                self._write_ball(k)
        if picked:
            for k in np.flatnonzero(self.pad_picked >= 0).tolist():
                slot = self._slots[k]
                self._events[slot.arena].append(BoostPickup(self.tick_count, slot.arena, slot.car_id,
                                                            int(self.pad_picked[k]), float(self.pad_gained[k])))
        if respawn_due:
            for k in np.flatnonzero(self.cs[:, CS_IS_DEMOED] > 0.5):
                if self.cs[k, CS_DEMO_TIMER] <= 0.0:
                    self.respawn(self._slots[k].car_id)

    def _classify_contacts(self, contacts: tuple) -> tuple[dict[tuple[int, int], tuple], dict[tuple[int, int], tuple]]:
        """This tick's contact points as ball touches {(car body, arena): (point on the ball, normal, its sign)}
        and car-car hits {(body a, body b): contact points}, each with its first contact point; a hitbox touching
        the arena is recorded for auto-flip and auto-roll here."""
        touches: dict[tuple[int, int], tuple] = {}
        car_pairs: dict[tuple[int, int], tuple] = {}
        if not contacts:
            return touches, car_pairs
        ball_arena, slot_by_body = self._ball_arena, self._slot_by_body
        for c in contacts:
            a, b = c[1], c[2]
            if a in ball_arena or b in ball_arena:
                # PyBullet's normal points from body b to body a.
                ball, other, point, sign = (a, b, c[5], 1.0) if a in ball_arena else (b, a, c[6], -1.0)
                if other in slot_by_body:
                    touches.setdefault((other, ball_arena[ball]), (point, c[7], sign))
            elif a in slot_by_body and b in slot_by_body:
                car_pairs.setdefault((a, b), (c[5], c[6]))
            elif a in self._static_set or b in self._static_set:
                # The hitbox touching the arena drives auto-flip and auto-roll next tick.
                car, sign = (a, 1.0) if a in slot_by_body else (b, -1.0)
                slot = slot_by_body.get(car)
                if slot is not None:
                    self.cs[slot.index, CS_BODY_CONTACT] = 1.0
                    self.cs[slot.index, CS_BODY_NORMAL_X:CS_BODY_NORMAL_X + 3] = np.multiply(c[7], sign)
        return touches, car_pairs

    def _hits(self, touches: dict[tuple[int, int], tuple], car_pairs: dict[tuple[int, int], tuple]) -> None:
        """Ball hits and car-car bumps or demolitions of this tick's contacts, after the bodies were read."""
        slot_by_body = self._slot_by_body
        for (body, k), (point_m, normal, sign) in sorted(touches.items()):
            if self.ball_frozen[k]:  # the tick's read skipped it: its state after the step is needed now
                self.ball_frozen[k] = False
                self._read_bodies([self._ball_bodies[k]], np.array([k], dtype=np.int64))
            point = np.array(point_m) * C.UU_PER_M - self.origins[k]
            self._ball_hit(slot_by_body[body], k, point, np.multiply(normal, sign))
        for (a, b), (pos_on_a, pos_on_b) in sorted(car_pairs.items()):
            sa, sb = slot_by_body[a], slot_by_body[b]
            self._car_hit(sa, sb, np.array(pos_on_a) * C.UU_PER_M - self.origins[sa.arena])
            self._car_hit(sb, sa, np.array(pos_on_b) * C.UU_PER_M - self.origins[sb.arena])

    def _ball_hit(self, slot: _CarSlot, arena: int, point: np.ndarray, normal: np.ndarray) -> None:
        """Record a car's touch and give Rocket League's extra push, at most once every other tick per car."""
        k = slot.index
        car_pos, car_vel, ball_pos, ball_vel = self._pre_step
        added = np.zeros(3)
        extra = self.tick_count > slot.last_ball_hit_tick + C.BALL_HIT_MIN_TICK_GAP - 1
        if extra:
            slot.last_ball_hit_tick = self.tick_count
            rel_pos = ball_pos[arena] - car_pos[k]
            rel_vel = ball_vel[arena] - car_vel[k]
            rel_speed = min(float(np.linalg.norm(rel_vel)), C.BALL_HIT_MAX_REL_SPEED)
            if rel_speed > 0.0:
                hit_dir = np.array([rel_pos[0], rel_pos[1], rel_pos[2] * C.BALL_HIT_Z_SCALE])
                hit_dir /= np.linalg.norm(hit_dir)
                fwd = self.car_rot[k][:, 0]
                hit_dir -= fwd * ((1.0 - C.BALL_HIT_FORWARD_SCALE) * (hit_dir @ fwd))
                hit_dir /= np.linalg.norm(hit_dir)
                added = hit_dir * rel_speed * interp(_BALL_HIT_CURVE, rel_speed) \
                    * self._mutators[arena].ball_hit_extra_force_scale
                self.ball_vel[arena] += added
                self._write_ball(arena)
        slot.ball_hit = BallHitInfo(tick=self.tick_count, extra_impulse_tick=slot.last_ball_hit_tick,
                                    relative_pos_on_ball=tuple((point - ball_pos[arena]).tolist()),
                                    ball_pos=tuple(ball_pos[arena].tolist()), extra_hit_vel=tuple(added.tolist()))
        self._events[arena].append(BallTouch(self.tick_count, arena, slot.car_id, tuple(point.tolist()),
                                             tuple(normal.tolist()), extra))

    def _car_hit(self, a: _CarSlot, b: _CarSlot, contact_uu: np.ndarray) -> None:
        """Car ``a`` bumping or demolishing car ``b`` (RocketSim's car-car rules)."""
        ia, ib = a.index, b.index
        if self.cs[ia, CS_IS_DEMOED] or self.cs[ib, CS_IS_DEMOED]:
            return
        if a.cooldown_until.get(b.car_id, -1) > self.tick_count:
            return
        car_pos, car_vel, _, _ = self._pre_step  # the velocities at contact, as RocketSim's callback sees them
        vel_a = car_vel[ia]
        speed_a = float(np.linalg.norm(vel_a))
        delta = car_pos[ib] - car_pos[ia]
        if speed_a <= 0.0 or vel_a @ delta <= 0.0:
            return
        direction = vel_a / speed_a
        toward = float(vel_a @ (delta / np.linalg.norm(delta)))
        if speed_a <= float(car_vel[ib] @ direction):
            return
        local = self.car_rot[ia].T @ (contact_uu - self.car_pos[ia])
        if local[0] <= C.BUMP_MIN_FORWARD_DIST:
            return
        mutators = self._mutators[a.arena]
        a.cooldown_until[b.car_id] = self.tick_count + int(round(mutators.bump_cooldown_s * self.tick_rate))
        a.last_victim = b.car_id
        if mutators.demo_mode == DemoMode.ON_CONTACT:
            is_demo = True
        elif mutators.demo_mode == DemoMode.DISABLED:
            is_demo = False
        else:
            is_demo = bool(self.cs[ia, CS_IS_SUPERSONIC])
        if is_demo and (a.team != b.team or mutators.team_demos):
            self.demolish(b.car_id)
            self._events[a.arena].append(Demo(self.tick_count, a.arena, a.car_id, b.car_id))
            return
        on_ground = self.cs[ib, CS_ON_GROUND] > 0.5
        curve = _BUMP_GROUND if on_ground else _BUMP_AIR
        up = self.car_rot[ib][:, 2] if on_ground else np.array([0.0, 0.0, 1.0])
        self.car_vel[ib] += direction * interp(curve, toward) + up * (interp(_BUMP_UP, toward)
                                                                      * mutators.bump_force_scale)
        self._events[a.arena].append(Bump(self.tick_count, a.arena, a.car_id, b.car_id))

    def demolish(self, car_id: int) -> None:
        s = self._slot(car_id)
        k = s.index
        self.cs[k, CS_IS_DEMOED] = 1.0
        self.cs[k, CS_DEMO_TIMER] = self._mutators[s.arena].respawn_delay_s
        cid = self.client
        # A demoed car leaves the world: no collisions, no gravity, until it respawns.
        pb.setCollisionFilterGroupMask(s.body, -1, 0, 0, physicsClientId=cid)
        pb.changeDynamics(s.body, -1, mass=0.0, physicsClientId=cid)
        pb.resetBaseVelocity(s.body, [0, 0, 0], [0, 0, 0], physicsClientId=cid)
        self.car_vel[k] = 0.0
        self.car_ang_vel[k] = 0.0

    def respawn(self, car_id: int) -> None:
        s = self._slot(car_id)
        k = s.index
        x, y, yaw = C.RESPAWN_SPOTS_BLUE[int(self.arena_rngs[s.arena].integers(len(C.RESPAWN_SPOTS_BLUE)))]
        if s.team == 1:
            x, y, yaw = -x, -y, yaw + math.pi
        cid = self.client
        pb.setCollisionFilterGroupMask(s.body, -1, 1, -1, physicsClientId=cid)  # Bullet's defaults
        self._set_car_dynamics(s.body, s.config)
        keep = self.controls[k].copy()
        self.cs[k] = 0.0
        self.controls[k] = keep
        self.cs[k, CS_BOOST] = self._mutators[s.arena].car_spawn_boost
        c, sn = math.cos(yaw), math.sin(yaw)
        rot = np.column_stack(([c, sn, 0.0], [-sn, c, 0.0], [0.0, 0.0, 1.0]))
        self.set_car(car_id, np.array([x, y, C.CAR_RESPAWN_Z]), rot, np.zeros(3), np.zeros(3))

    # ------------------------------------------------------------------ static boxes (minigame barriers)
    def add_static_box(self, arena: int, center_uu: np.ndarray, half_extents_uu: np.ndarray) -> int:
        """An immovable axis-aligned box in ``arena`` that cars and the ball collide with; returns its id.

        It has the arena's materials (friction and restitution 1.0, so each body's own value applies).
        """
        if not isinstance(arena, (int, np.integer)) or not 0 <= arena < self.n_arenas:
            raise ValueError(f"arena: must be an index in 0..{self.n_arenas - 1}, got {arena!r}")
        center = _box_vector("center_uu", center_uu)
        half = _box_vector("half_extents_uu", half_extents_uu)
        if np.any(half <= 0.0):
            raise ValueError(f"half_extents_uu: must all be > 0, got {half.tolist()}")
        cid = self.client
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(half * M_PER_UU).tolist(), physicsClientId=cid)
        body = pb.createMultiBody(0, shape, basePosition=((center + self.origins[arena]) * M_PER_UU).tolist(),
                                  physicsClientId=cid)
        pb.changeDynamics(body, -1, lateralFriction=1.0, restitution=1.0, rollingFriction=0.0,
                          spinningFriction=0.0, physicsClientId=cid)
        self._static_set.add(body)  # cars touching it count as touching the arena (auto-flip, auto-roll)
        self._static_boxes[body] = int(arena)
        self._static_half_extents[body] = half
        return body

    def static_box_half_extents(self, box_id: int) -> np.ndarray:
        self._static_box_arena(box_id)
        return self._static_half_extents[box_id].copy()

    def move_static_box(self, box_id: int, center_uu: np.ndarray) -> None:
        """Put a static box's centre at ``center_uu`` (between rounds; it does not sweep through bodies)."""
        arena = self._static_box_arena(box_id)
        center = _box_vector("center_uu", center_uu)
        pb.resetBasePositionAndOrientation(box_id, ((center + self.origins[arena]) * M_PER_UU).tolist(),
                                           (0, 0, 0, 1), physicsClientId=self.client)

    def remove_static_box(self, box_id: int) -> None:
        self._static_box_arena(box_id)
        pb.removeBody(box_id, physicsClientId=self.client)
        self._static_set.discard(box_id)
        del self._static_boxes[box_id], self._static_half_extents[box_id]

    def _static_box_arena(self, box_id: int) -> int:
        if box_id not in self._static_boxes:
            raise ValueError(f"box_id: no static box {box_id!r}; boxes are {sorted(self._static_boxes)}")
        return self._static_boxes[box_id]

    # ------------------------------------------------------------------ the public surface for game logic
    def set_mutator_config(self, config: MutatorConfig, arena: int | None = None) -> None:
        """Play arena ``arena`` (every arena if None) with ``config``. Gravity is PyBullet's one per world, so
        it changes only for every arena at once."""
        if not isinstance(config, MutatorConfig):
            raise ValueError(f"config: expected MutatorConfig, got {type(config).__name__}")
        targets = range(self.n_arenas) if arena is None else [self._arena_index(arena)]
        if len(targets) < self.n_arenas and config.gravity_z_uu_s2 != self._mutators[0].gravity_z_uu_s2:
            raise ValueError(f"gravity_z_uu_s2: the arenas of a batch share one gravity "
                             f"({self._mutators[0].gravity_z_uu_s2:g}); change it with "
                             f"ArenaBatch.set_mutator_config(config) for all arenas, got {config.gravity_z_uu_s2:g}")
        self._read_state()
        if config.gravity_z_uu_s2 != self._mutators[0].gravity_z_uu_s2:
            pb.setGravity(0, 0, config.gravity_z_uu_s2 * M_PER_UU, physicsClientId=self.client)
            self._ball_hold_vel = np.array([0.0, 0.0, -config.gravity_z_uu_s2 * self.dt])
            self._ball_hold_vel_m = (self._ball_hold_vel * M_PER_UU).tolist()
        for k in targets:
            if config.ball_drag != self._mutators[k].ball_drag:
                pb.changeDynamics(self._ball_bodies[k], -1, linearDamping=config.ball_drag,
                                  physicsClientId=self.client)
            self._mutators[k] = config
            self.mutator_rows[k] = config.as_row()

    def get_mutator_config(self, arena: int = 0) -> MutatorConfig:
        return self._mutators[self._arena_index(arena)]

    def _arena_index(self, arena: int) -> int:
        if not isinstance(arena, (int, np.integer)) or not 0 <= arena < self.n_arenas:
            raise ValueError(f"arena: must be an index in 0..{self.n_arenas - 1}, got {arena!r}")
        return int(arena)

    def drain_events(self, arena: int | None = None) -> list[PhysicsEvent]:
        """The events of arena ``arena`` (every arena if None, arena by arena) since the last drain, in the order
        the ticks produced them; they are removed."""
        if arena is not None:
            k = self._arena_index(arena)
            events, self._events[k] = self._events[k], []
            return events
        events = [e for per_arena in self._events for e in per_arena]
        self._events = [[] for _ in range(self.n_arenas)]
        return events

    def pybullet_bodies(self) -> tuple[list[int], list[int]]:
        """(ball body ids by arena, car body ids by batch row) of the PyBullet world ``client``: for benchmarks
        that step the bare world; the physics owns these bodies."""
        return list(self._ball_bodies), list(self._car_bodies)

    def clear_events(self, arena: int | None = None) -> None:
        """Forget the undrained events of ``arena`` (every arena if None)."""
        self.drain_events(arena)

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

    def close(self) -> None:
        if self.client is not None and pb.isConnected(self.client):
            pb.disconnect(self.client)
        self.client = None

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: pybullet may already be gone
            pass
