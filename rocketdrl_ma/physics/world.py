"""Many soccar arenas in one PyBullet world, stepped together: the machinery under ``Arena`` and ``ArenaBatch``.

Each arena sits at its own origin on a grid far enough apart that nothing crosses over; the floor
and ceiling planes are shared. PyBullet holds the cars (their hitboxes against the arena, the
minigames' boxes and each other); the balls live in arrays and move in ``ball_kernel``, which
solves their contacts as RocketSim does. Every per-tick quantity is held as arrays over all cars
and balls of all arenas, so the car and ball models run as compiled kernels and a lone ``Arena``
is simply a batch of one. Rocket League units (uu) everywhere outside this module's PyBullet
calls, which use metres.
"""
from __future__ import annotations

import functools
import math
import os
import tempfile
import weakref
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pybullet as pb
from numba import njit

from . import constants as C
from .arena_shape import DEFAULT_ARENA_SHAPE, GAME, arena_shape_index, shape_mesh
from .ball_kernel import SPLIT_IMPULSE_ERP, ball_tick_classic, ball_tick_game
from .body_io import read_rows, unpack_rows
from .car_config import CarConfig, get_preset
from .car_kernel import (CS_AIR_TIME_SINCE_JUMP, CS_BODY_CONTACT, CS_BODY_NORMAL_X, CS_BOOST, CS_DEMO_TIMER,
                         CS_HAS_DOUBLE_JUMPED, CS_HAS_FLIPPED, CS_HAS_JUMPED, CS_IS_DEMOED, CS_IS_SUPERSONIC,
                         CS_ON_GROUND, CS_SIZE, boost_pad_tick, cancel_gyroscopic, car_post_tick, car_pre_tick_classic,
                         car_pre_tick_game, interp)
from .events import BallTouch, BoostPickup, Bump, Demo, PhysicsEvent
from .mutators import DemoMode, MutatorConfig
from .state import BallHitInfo

M_PER_UU = 1.0 / C.UU_PER_M
ARENA_SPACING_UU = 20000.0  # arenas are ~8200 x 12000 uu; the gap keeps every body in its own arena
ARENA_GRID_COLUMNS = 8
# Car materials: Bullet multiplies the two bodies' values, the arena's are 1.0, so a car's friction 0.3 and
# restitution sqrt(0.1) give RocketSim's car-car 0.09 / 0.1 and car-world 0.3 / 0.32 (RocketSim: 0.3).
CAR_FRICTION = math.sqrt(C.CAR_CAR_FRICTION)
# RocketSim's cars meet only once their hitboxes overlap by 0.134 uu (bisected to 1e-6); PyBullet's meet at any
# overlap. Each car's PyBullet box is half that smaller per face, so contacts start where RocketSim's do (the ball
# meets the full box in ball_kernel).
CAR_CONTACT_SHRINK = 0.134 / 2
CAR_RESTITUTION = math.sqrt(C.CAR_CAR_RESTITUTION)
_BUMP_GROUND = np.array(C.BUMP_VEL_CURVE_GROUND)
_BUMP_AIR = np.array(C.BUMP_VEL_CURVE_AIR)
_BUMP_UP = np.array(C.BUMP_UPWARD_VEL_CURVE)


@njit(cache=True, nogil=True)
def post_tick_kernels(car_pos, car_vel, car_ang_vel, car_arena, car_active, cs, pad_timer, pad_picked, pad_gained,
                      mut, dt):
    """The compiled after-step work of one tick in one call: ``car_post_tick`` and ``boost_pad_tick``.
    Returns (cars due to respawn, pads picked up)."""
    respawn_due = car_post_tick(car_vel, car_ang_vel, car_active, cs, dt)
    n_picked = boost_pad_tick(car_pos, car_arena, car_active, cs, C.BOOST_PAD_POSITIONS, C.BOOST_PAD_IS_BIG,
                              pad_timer, pad_picked, pad_gained, mut, dt)
    return respawn_due, n_picked


@functools.lru_cache(maxsize=None)
def _arena_mesh_lists(arena_shape: str) -> tuple[list, list]:
    """The arena's walls, goals and ramps as the nested lists (m; indices) ``createCollisionShape`` takes, made once
    per process and shape: PyBullet keeps a reference to every vertex row it is given and never lets go of it, so
    fresh lists for every world leaked about 1.45 MB each (about 320 MB over a league's 220 matches in one
    process)."""
    verts, idx = shape_mesh(arena_shape, with_floor_and_ceiling=False)  # the world's planes are floor and ceiling
    return (verts * M_PER_UU).tolist(), idx.reshape(-1).tolist()


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
        self.ball_hit: BallHitInfo | None = None
        # RocketSim's car contact: the car this one last bumped or demolished, and the tick from which it may again
        self.contact_id: int | None = None
        self.contact_until = 0


class PhysicsWorld:
    """``n_arenas`` independent soccar arenas in one PyBullet client, stepped by one ``stepSimulation``.

    ``arenas`` holds the ``Arena`` views of whoever made the world (``ArenaBatch`` makes one per arena; a lone
    ``Arena`` is the view of its own world of one); ``step(ticks)`` advances all.
    """

    def __init__(self, n_arenas: int = 1, tick_rate: int = C.TICK_RATE_HZ, seed: int | None = None,
                 arena_shape: str = DEFAULT_ARENA_SHAPE):
        if not isinstance(n_arenas, int) or n_arenas < 1:
            raise ValueError(f"n_arenas: must be an int >= 1, got {n_arenas!r}")
        if tick_rate != C.TICK_RATE_HZ:
            raise ValueError(f"tick_rate: only {C.TICK_RATE_HZ} Hz is supported (the game's rate), got {tick_rate!r}")
        self._game_shape = arena_shape_index(arena_shape) == GAME  # which compiled kernels step() calls
        self.arena_shape = arena_shape
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
        self.origins = np.array([[(k % ARENA_GRID_COLUMNS) * ARENA_SPACING_UU,
                                  (k // ARENA_GRID_COLUMNS) * ARENA_SPACING_UU, 0.0] for k in range(n_arenas)])
        # Every body made or removed after the static world, in order: a copy of the world replays it (see
        # _restore_world) so that its bodies have the same ids and the same order in Bullet's arrays.
        self._body_log: list[tuple] = []
        self._connect()
        self._static_boxes: dict[int, np.ndarray] = {}  # PyBullet body id -> (arena, centre xyz, half extents xyz) uu
        self._box_rows = np.zeros((0, 7))  # the same, stacked for the ball kernel
        self.ball_pos = np.zeros((n_arenas, 3))
        self.ball_vel = np.zeros((n_arenas, 3))
        self.ball_ang_vel = np.zeros((n_arenas, 3))
        self.ball_frozen = np.zeros(n_arenas, dtype=bool)
        self._ball_pos_before = np.zeros((n_arenas, 3))  # where the balls were at the start of the last tick
        self.pad_timer = np.zeros((n_arenas, len(C.BOOST_PAD_POSITIONS)))
        self._slots: list[_CarSlot] = []
        self._slot_by_body: dict[int, _CarSlot] = {}
        self._slot_by_id: dict[int, _CarSlot] = {}
        self._next_car_id = 0
        self._rebuild_car_arrays()
        self._state_fresh = False
        self._events: list[list[PhysicsEvent]] = [[] for _ in range(n_arenas)]  # per arena, since the last drain
        self._overlap_push: dict[int, np.ndarray] = {}  # car row -> this tick's overlap correction (uu)
        self._arena_views: list = []  # an ArenaBatch's views of its arenas
        self._lone_arena: weakref.ref | None = None  # the Arena whose own world of one this is
        for k in range(n_arenas):
            self.set_ball(k, np.array([0.0, 0.0, C.BALL_REST_Z]), np.zeros(3), np.zeros(3))

    @property
    def arenas(self) -> list:
        """The ``Arena`` views of this world's arenas: an ``ArenaBatch``'s, or a lone ``Arena`` itself."""
        if self._lone_arena is not None:
            arena = self._lone_arena()
            return [] if arena is None else [arena]
        return self._arena_views

    def attach_lone_arena(self, arena: object) -> None:
        """``arena`` (an ``Arena``) is the one view of this world of one, held weakly, so the world goes with the last
        reference to its arena. Held strongly, the arena and its world formed a reference cycle, and a dropped
        arena's PyBullet world (about 10 MB, memory Python's cyclic collector does not see) waited for that
        collector: 240 3v3 matches made and dropped one after another in one process peaked at 8 GB."""
        self._lone_arena = weakref.ref(arena)

    # ------------------------------------------------------------------ construction
    def _connect(self) -> None:
        """A PyBullet world of its own with this world's settings and static bodies."""
        self.client = pb.connect(pb.DIRECT)
        cid = self.client
        pb.setGravity(0, 0, self._mutators[0].gravity_z_uu_s2 * M_PER_UU, physicsClientId=cid)
        # RocketSim's solver: 10 iterations, no restitution under 10 uu/s. (Its overlap correction, 0.8 a tick by
        # split impulse, is not PyBullet's to set: contactERP 0.8 feeds a velocity bias here, which made cars leave
        # walls faster than they came.)
        pb.setPhysicsEngineParameter(fixedTimeStep=self.dt, numSubSteps=0, numSolverIterations=10,
                                     deterministicOverlappingPairs=1, restitutionVelocityThreshold=10.0 * M_PER_UU,
                                     contactERP=0.0, physicsClientId=cid)
        self._build_static_world()

    # ------------------------------------------------------------------ copies (copy.deepcopy, pickle)
    def __getstate__(self) -> dict:
        """Everything but the PyBullet connection, plus the PyBullet world as a ``.bullet`` snapshot (transforms,
        velocities, the contact cache that warm-starts the next solve).

        A snapshot does not hold all of Bullet's internals (e.g. the broadphase's history), so a world restored
        from it goes on a little differently (float rounding) than the world it was taken from. To give the copy
        exactly this world's future, this world moves onto a fresh PyBullet world restored from the same
        snapshot too: its state is unchanged, and from here on it and every copy step identically."""
        snapshot = None
        if self.client is not None:  # a closed world copies as a closed world
            snapshot = self._bullet_snapshot()
            old_client = self.client
            self._restore_world(snapshot)
            pb.disconnect(old_client)
        state = self.__dict__.copy()
        state["client"] = None
        state["_bullet_bytes"] = snapshot
        state["_lone_arena"] = None if self._lone_arena is None else self._lone_arena()  # a weakref does not copy
        return state

    def __setstate__(self, state: dict) -> None:
        snapshot = state.pop("_bullet_bytes")
        lone = state.pop("_lone_arena", None)
        self.__dict__.update(state)
        self._lone_arena = None if lone is None else weakref.ref(lone)
        if snapshot is not None:
            self._restore_world(snapshot)

    def _bullet_snapshot(self) -> bytes:
        fd, path = tempfile.mkstemp(suffix=".bullet")
        os.close(fd)
        try:
            pb.saveBullet(path, physicsClientId=self.client)
            return Path(path).read_bytes()
        finally:
            os.unlink(path)

    def renew_bullet_world(self) -> None:
        """Move onto a new PyBullet world: the same bodies with the same ids, settings and demolitions, the static
        boxes where they are, every car where its arrays say, and none of Bullet's memory of earlier ticks.

        Bullet keeps contact manifolds, the order of their points and a broadphase that prunes stale pairs a few per
        tick from a cursor; a used world carries them into every later tick, so a game played on it drifts apart
        from the same game on a new world after a few hundred decisions. Made for the start of an episode: a car
        put somewhere since the last tick (``set_car``; a reset puts every car) is put there again exactly, and the
        world then plays on exactly as a newly made one with the same cars put the same way. A car that has moved
        on its own since it was put carries over to float rounding (its pose read back from metres)."""
        old_client = self.client
        self._read_state()
        self._remake_bodies()
        pb.disconnect(old_client)
        for box_id, row in self._static_boxes.items():
            self._place_static_box(box_id, int(row[0]), row[1:4])
        for slot in self._slots:
            k = slot.index
            if self.cs[k, CS_IS_DEMOED]:
                self._take_out_of_play(slot.body)
            self.set_car(slot.car_id, self.car_pos[k], self.car_rot[k], self.car_vel[k], self.car_ang_vel[k])

    def _remake_bodies(self) -> None:
        """Connect to a new PyBullet world: the static world, then the logged bodies made again in their order (so
        they get the same ids)."""
        kept = {key: getattr(self, key) for key in ("_static_bodies", "_static_set", "_body_log")}
        self._body_log = []
        self._connect()
        for entry in kept["_body_log"]:
            if entry[0] == "car":
                body = self._create_car_body(entry[2], entry[3])
            elif entry[0] == "box":
                body = self._create_box_body(entry[2], entry[3], entry[4])
            else:
                self._remove_body(entry[1])
                continue
            if body != entry[1]:
                raise RuntimeError(f"PhysicsWorld: body {entry[1]} came back as {body} in the new PyBullet world")
        self.__dict__.update(kept)

    def _restore_world(self, snapshot: bytes) -> None:
        """Connect to a new PyBullet world with the same bodies, then restore ``snapshot`` onto them."""
        self._remake_bodies()
        fd, path = tempfile.mkstemp(suffix=".bullet")
        try:
            os.write(fd, snapshot)
            os.close(fd)
            pb.restoreState(fileName=path, physicsClientId=self.client)
        finally:
            os.unlink(path)

    def _build_static_world(self) -> None:
        cid = self.client
        vertices, indices = _arena_mesh_lists(self.arena_shape)
        shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=vertices, indices=indices,
                                        flags=pb.GEOM_FORCE_CONCAVE_TRIMESH, physicsClientId=cid)
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

    def add_car(self, arena: int, team: int, config: CarConfig | str) -> int:
        if team not in (0, 1):
            raise ValueError(f"team: must be 0 (blue) or 1 (orange), got {team!r}")
        cfg = get_preset(config) if isinstance(config, str) else config
        body = self._create_car_body(arena, cfg)
        slot = _CarSlot(self._next_car_id, arena, team, cfg, body)
        self._next_car_id += 1
        old = self._snapshot_car_arrays()
        self._slots.append(slot)
        self._slot_by_body[body] = slot
        self._slot_by_id[slot.car_id] = slot
        self._rebuild_car_arrays(old)
        self.cs[slot.index, CS_BOOST] = self._mutators[arena].car_spawn_boost
        return slot.car_id

    def _create_car_body(self, arena: int, cfg: CarConfig) -> int:
        cid = self.client
        half = [(s * 0.5 - CAR_CONTACT_SHRINK) * M_PER_UU for s in cfg.hitbox_size]
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half,
                                        collisionFramePosition=[o * M_PER_UU for o in cfg.hitbox_offset],
                                        physicsClientId=cid)
        start = self.origins[arena] + np.array([0.0, 0.0, C.CAR_SPAWN_REST_Z])
        body = pb.createMultiBody(C.CAR_MASS, shape, basePosition=(start * M_PER_UU).tolist(),
                                  useMaximalCoordinates=True, physicsClientId=cid)
        self._set_car_dynamics(body, cfg)
        self._body_log.append(("car", body, arena, cfg))
        return body

    def _set_car_dynamics(self, body: int, cfg: CarConfig) -> None:
        pb.changeDynamics(body, -1, mass=C.CAR_MASS, localInertiaDiagonal=cfg.inertia_diag.tolist(),
                          lateralFriction=CAR_FRICTION, restitution=CAR_RESTITUTION, linearDamping=0.0,
                          angularDamping=0.0, rollingFriction=0.0, spinningFriction=0.0,
                          activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=self.client)

    def remove_car(self, car_id: int) -> None:
        slot = self._slot(car_id)
        old = self._snapshot_car_arrays()
        self._remove_body(slot.body)
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
            unpack_rows(read_rows([self._slots[k].body for k in added], self.client), np.array(added, dtype=np.int64),
                        self.origins, self.car_arena, self.car_pos, self.car_quat, self.car_rot, self.car_vel,
                        self.car_ang_vel)
        self._state_fresh = True

    def _slot(self, car_id: int) -> _CarSlot:
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
        unpack_rows(read_rows(self._car_bodies, self.client), self._car_rows, self.origins, self.car_arena,
                    self.car_pos, self.car_quat, self.car_rot, self.car_vel, self.car_ang_vel)

    def _write_car_velocities(self, all_writable: bool) -> None:
        """Every active, non-demolished car's velocities to PyBullet (``all_writable``: that is every car)."""
        cid = self.client
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
        # the arena shape's kernels (each compiled for its shape alone: no branch on the shape inside them)
        car_pre_tick = car_pre_tick_game if self._game_shape else car_pre_tick_classic
        ball_tick = ball_tick_game if self._game_shape else ball_tick_classic
        for _ in range(ticks):
            self._read_state()
            if self._slots:
                unwritable = car_pre_tick(self.car_pos, self.car_rot, self.car_vel, self.car_ang_vel, self.controls,
                                          self.wheel_conn, self.wheel_rest, self.wheel_radius, self.wheel_ray_len,
                                          self.wheel_is_front, self.inv_inertia, self.three_wheel, self.car_arena,
                                          self.car_active, self.ball_pos, C.BALL_RADIUS, self.cs,
                                          self.mutator_rows, self.dt)
            # The balls' whole tick: contacts from the positions at the start of the tick, as in RocketSim.
            self._ball_pos_before[:] = self.ball_pos
            n_touch = ball_tick(self.ball_pos, self.ball_vel, self.ball_ang_vel, self.ball_frozen, self.car_pos,
                                self.car_rot, self.car_vel, self.car_ang_vel, self.car_arena,
                                self.car_active & (self.cs[:, CS_IS_DEMOED] == 0.0), self.hitbox_half,
                                self.hitbox_offset, self.inv_inertia, self.last_extra_hit_tick, self._box_rows,
                                self.mutator_rows, self._mutators[0].gravity_z_uu_s2, self.tick_count + 1, self.dt,
                                self._touched, self._touch_point, self._touch_normal, self._extra_vel, self._car_push)
            if self._slots:
                if n_touch:
                    self._push_cars()  # before the velocities: PyBullet's pose reset clears them
                self._write_car_velocities(unwritable == 0)
            step_simulation(cid)
            self.tick_count += 1
            car_pairs = self._classify_contacts(pb.getContactPoints(physicsClientId=cid))
            if car_pairs:
                # RocketSim judges a car-car contact from the cars as they were when it was found, before the
                # solver: the arrays still hold that state until the read below.
                self._pre_step = (self.car_pos.copy(), self.car_vel.copy(), self.car_rot.copy())
            if self._slots:
                self._read_cars()
                if self._overlap_push:
                    self._push_overlapping_cars()
            self._state_fresh = True
            if n_touch:
                self._record_touches()
            if car_pairs:
                self._car_hits(car_pairs)
            if self._slots:
                self._post_tick()

    def _push_cars(self) -> None:
        """Move the cars whose overlap with the ball is being pushed apart (positions only, like Bullet's split
        impulse)."""
        cid = self.client
        for k in np.flatnonzero(np.any(self._car_push != 0.0, axis=1)).tolist():
            self.car_pos[k] += self._car_push[k]
            slot = self._slots[k]
            pb.resetBasePositionAndOrientation(slot.body, ((self.car_pos[k] + self.origins[slot.arena])
                                                           * M_PER_UU).tolist(), self.car_quat[k].tolist(), cid)

    def _record_touches(self) -> None:
        """The touch events and hit info of the cars the ball kernel found touching a ball this tick."""
        tick = self.tick_count
        for i in np.flatnonzero(self._touched).tolist():
            slot = self._slots[i]
            k = slot.arena
            point, ball_pos = self._touch_point[i], self._ball_pos_before[k]
            extra = int(self.last_extra_hit_tick[i])
            slot.ball_hit = BallHitInfo(tick=tick, extra_impulse_tick=extra,
                                        relative_pos_on_ball=tuple((point - ball_pos).tolist()),
                                        ball_pos=tuple(ball_pos.tolist()),
                                        extra_hit_vel=tuple(self._extra_vel[i].tolist()))
            self._events[k].append(BallTouch(tick, k, slot.car_id, tuple(point.tolist()),
                                             tuple(self._touch_normal[i].tolist()), extra == tick))

    def _post_tick(self) -> None:
        respawn_due, picked = post_tick_kernels(
            self.car_pos, self.car_vel, self.car_ang_vel, self.car_arena, self.car_active, self.cs,
            self.pad_timer, self.pad_picked, self.pad_gained, self.mutator_rows, self.dt)
        if picked:
            for k in np.flatnonzero(self.pad_picked >= 0).tolist():
                slot = self._slots[k]
                self._events[slot.arena].append(BoostPickup(self.tick_count, slot.arena, slot.car_id,
                                                            int(self.pad_picked[k]), float(self.pad_gained[k])))
        if respawn_due:
            for k in np.flatnonzero(self.cs[:, CS_IS_DEMOED] > 0.5):
                if self.cs[k, CS_DEMO_TIMER] <= 0.0:
                    self.respawn(self._slots[k].car_id)

    def _classify_contacts(self, contacts: tuple) -> dict[tuple[int, int], list]:
        """This tick's car-car contacts {(body a, body b): [(point on a, point on b), ...]} in PyBullet's order; a
        hitbox touching the arena is recorded for auto-flip and auto-roll here."""
        car_pairs: dict[tuple[int, int], list] = {}
        self._overlap_push.clear()
        if not contacts:
            return car_pairs
        slot_by_body = self._slot_by_body
        for c in contacts:
            a, b = c[1], c[2]
            if a in slot_by_body and b in slot_by_body:
                car_pairs.setdefault((a, b), []).append((c[5], c[6]))
                self._push_apart(slot_by_body[a].index, c[7], c[8], 0.5)
                self._push_apart(slot_by_body[b].index, np.negative(c[7]), c[8], 0.5)
            elif a in self._static_set or b in self._static_set:
                # The hitbox touching the arena drives auto-flip and auto-roll next tick.
                car, sign = (a, 1.0) if a in slot_by_body else (b, -1.0)
                slot = slot_by_body.get(car)
                if slot is not None:
                    normal = np.multiply(c[7], sign)
                    self.cs[slot.index, CS_BODY_CONTACT] = 1.0
                    self.cs[slot.index, CS_BODY_NORMAL_X:CS_BODY_NORMAL_X + 3] = normal
                    self._push_apart(slot.index, normal, c[8], 1.0)
        return car_pairs

    def _push_apart(self, k: int, normal, distance_m: float, share: float) -> None:
        """Bullet's split impulse for car ``k`` at one contact point (normal towards the car): its ``share`` of 0.8
        of the overlap, as a position change; several points along one normal push once, not once each."""
        depth = -distance_m * C.UU_PER_M
        if depth <= 0.0:
            return
        n = np.asarray(normal, dtype=np.float64)
        push = self._overlap_push.get(k)
        if push is None:
            push = self._overlap_push[k] = np.zeros(3)
        need = SPLIT_IMPULSE_ERP * depth * share - float(push @ n)
        if need > 0.0:
            push += n * need

    def _push_overlapping_cars(self) -> None:
        """Apply this tick's overlap pushes (after the cars were read; the next tick writes their velocities)."""
        cid = self.client
        for k, push in self._overlap_push.items():
            slot = self._slots[k]
            if self.cs[k, CS_IS_DEMOED]:
                continue
            self.car_pos[k] += push
            pb.resetBasePositionAndOrientation(slot.body, ((self.car_pos[k] + self.origins[slot.arena])
                                                           * M_PER_UU).tolist(), self.car_quat[k].tolist(), cid)

    def _car_hits(self, car_pairs: dict[tuple[int, int], list]) -> None:
        """Bumps and demolitions of this tick's car-car contacts, after the cars were read. As RocketSim's contact
        callback: every contact point of a pair, each tested both ways, the later-added car as the attacker
        first."""
        slot_by_body = self._slot_by_body
        pairs = []
        for (a, b), points in car_pairs.items():
            sa, sb = slot_by_body[a], slot_by_body[b]
            if sa.car_id < sb.car_id:
                sa, sb, points = sb, sa, [(on_b, on_a) for on_a, on_b in points]
            pairs.append((sa.car_id, sb.car_id, sa, sb, points))
        for _, _, sa, sb, points in sorted(pairs, key=lambda p: p[:2]):
            origin = self.origins[sa.arena]
            for pos_on_a, pos_on_b in points:
                if not self._car_hit(sa, sb, np.array(pos_on_a) * C.UU_PER_M - origin):
                    break  # a car of the pair is demolished
                if not self._car_hit(sb, sa, np.array(pos_on_b) * C.UU_PER_M - origin):
                    break

    def _car_hit(self, a: _CarSlot, b: _CarSlot, contact_uu: np.ndarray) -> bool:
        """Car ``a`` bumping or demolishing car ``b`` at the contact point ``contact_uu`` on ``a`` (RocketSim's
        car-car rules, judged from the cars as they were when the contact was found). False if either car is
        demolished (nothing more happens between them this tick)."""
        ia, ib = a.index, b.index
        if self.cs[ia, CS_IS_DEMOED] or self.cs[ib, CS_IS_DEMOED]:
            return False
        if a.contact_id == b.car_id and a.contact_until > self.tick_count:
            return True
        car_pos, car_vel, car_rot = self._pre_step
        vel_a = car_vel[ia]
        delta = car_pos[ib] - car_pos[ia]
        if vel_a @ delta <= 0.0:
            return True  # not going towards the other car
        direction = vel_a / np.linalg.norm(vel_a)
        toward = float(vel_a @ (delta / np.linalg.norm(delta)))
        if toward <= float(car_vel[ib] @ direction):
            return True  # not faster towards it than it goes away
        local = car_rot[ia].T @ (contact_uu - car_pos[ia])
        if local[0] <= C.BUMP_MIN_FORWARD_DIST:
            return True  # not the front bumper
        mutators = self._mutators[a.arena]
        a.contact_id = b.car_id
        a.contact_until = self.tick_count + int(round(mutators.bump_cooldown_s * self.tick_rate))
        if mutators.demo_mode == DemoMode.ON_CONTACT:
            is_demo = True
        elif mutators.demo_mode == DemoMode.DISABLED:
            is_demo = False
        else:
            is_demo = bool(self.cs[ia, CS_IS_SUPERSONIC])
        if is_demo and (a.team != b.team or mutators.team_demos):
            self.demolish(b.car_id)
            self._events[a.arena].append(Demo(self.tick_count, a.arena, a.car_id, b.car_id))
            return False
        on_ground = self.cs[ib, CS_ON_GROUND] > 0.5
        curve = _BUMP_GROUND if on_ground else _BUMP_AIR
        up = car_rot[ib][:, 2] if on_ground else np.array([0.0, 0.0, 1.0])
        # RocketSim adds the bump after the tick's integration (its velocity cache): the read state is after it.
        self.car_vel[ib] += direction * interp(curve, toward) + up * (interp(_BUMP_UP, toward)
                                                                      * mutators.bump_force_scale)
        self._events[a.arena].append(Bump(self.tick_count, a.arena, a.car_id, b.car_id))
        return True

    def demolish(self, car_id: int) -> None:
        s = self._slot(car_id)
        k = s.index
        self.cs[k, CS_IS_DEMOED] = 1.0
        self.cs[k, CS_DEMO_TIMER] = self._mutators[s.arena].respawn_delay_s
        self._take_out_of_play(s.body)
        pb.resetBaseVelocity(s.body, [0, 0, 0], [0, 0, 0], physicsClientId=self.client)
        self.car_vel[k] = 0.0
        self.car_ang_vel[k] = 0.0

    def _take_out_of_play(self, body: int) -> None:
        """A demoed car leaves the world: no collisions, no gravity, until it respawns."""
        pb.setCollisionFilterGroupMask(body, -1, 0, 0, physicsClientId=self.client)
        pb.changeDynamics(body, -1, mass=0.0, physicsClientId=self.client)

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

        Cars meet it in PyBullet with the arena's materials (friction and restitution 1.0, so each car's own value
        applies); the ball meets it as part of the arena (``ball_kernel``).
        """
        if not isinstance(arena, (int, np.integer)) or not 0 <= arena < self.n_arenas:
            raise ValueError(f"arena: must be an index in 0..{self.n_arenas - 1}, got {arena!r}")
        center = _box_vector("center_uu", center_uu)
        half = _box_vector("half_extents_uu", half_extents_uu)
        if np.any(half <= 0.0):
            raise ValueError(f"half_extents_uu: must all be > 0, got {half.tolist()}")
        body = self._create_box_body(arena, center, half)
        self._static_set.add(body)  # cars touching it count as touching the arena (auto-flip, auto-roll)
        self._static_boxes[body] = np.concatenate(([arena], center, half))
        self._stack_boxes()
        return body

    def _create_box_body(self, arena: int, center: np.ndarray, half: np.ndarray) -> int:
        cid = self.client
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(half * M_PER_UU).tolist(), physicsClientId=cid)
        body = pb.createMultiBody(0, shape, basePosition=((center + self.origins[arena]) * M_PER_UU).tolist(),
                                  physicsClientId=cid)
        pb.changeDynamics(body, -1, lateralFriction=1.0, restitution=1.0, rollingFriction=0.0,
                          spinningFriction=0.0, physicsClientId=cid)
        self._body_log.append(("box", body, arena, center.copy(), half.copy()))
        return body

    def _remove_body(self, body: int) -> None:
        pb.removeBody(body, physicsClientId=self.client)
        self._body_log.append(("remove", body))

    def _stack_boxes(self) -> None:
        self._box_rows = np.array(list(self._static_boxes.values()), dtype=np.float64).reshape(-1, 7)

    def static_box_half_extents(self, box_id: int) -> np.ndarray:
        self._static_box_arena(box_id)
        return self._static_boxes[box_id][4:7].copy()

    def move_static_box(self, box_id: int, center_uu: np.ndarray) -> None:
        """Put a static box's centre at ``center_uu`` (between rounds; it does not sweep through bodies)."""
        arena = self._static_box_arena(box_id)
        center = _box_vector("center_uu", center_uu)
        self._place_static_box(box_id, arena, center)
        self._static_boxes[box_id][1:4] = center
        self._stack_boxes()

    def _place_static_box(self, box_id: int, arena: int, center: np.ndarray) -> None:
        pb.resetBasePositionAndOrientation(box_id, ((center + self.origins[arena]) * M_PER_UU).tolist(),
                                           (0, 0, 0, 1), physicsClientId=self.client)

    def remove_static_box(self, box_id: int) -> None:
        self._static_box_arena(box_id)
        self._remove_body(box_id)
        self._static_set.discard(box_id)
        del self._static_boxes[box_id]
        self._stack_boxes()

    def _static_box_arena(self, box_id: int) -> int:
        if box_id not in self._static_boxes:
            raise ValueError(f"box_id: no static box {box_id!r}; boxes are {sorted(self._static_boxes)}")
        return int(self._static_boxes[box_id][0])

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
        for k in targets:
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

    def pybullet_car_bodies(self) -> list[int]:
        """The cars' body ids (by batch row) in the PyBullet world ``client``, for benchmarks that step the bare
        world; the physics owns these bodies. (The balls are not PyBullet bodies.)"""
        return list(self._car_bodies)

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
