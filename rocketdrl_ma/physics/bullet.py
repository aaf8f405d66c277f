"""The PyBullet side of a ``PhysicsWorld``: one client with the arenas' static bodies, the cars' and minigame boxes'
bodies, and copying the client's world (snapshots, renewal).

Cars and boxes are PyBullet bodies; the balls are not (they live in arrays and move in ``ball_kernel``). Every
argument and result is in Rocket League units (uu) relative to an arena's origin; metres stay in here and in the
tick's few direct PyBullet calls.
"""
from __future__ import annotations

import functools
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pybullet as pb

from . import constants as C
from .arena_shape import shape_mesh
from .car_config import CarConfig

M_PER_UU = 1.0 / C.UU_PER_M
# Car materials: Bullet multiplies the two bodies' values, the arena's are 1.0, so a car's friction 0.3 and
# restitution sqrt(0.1) give RocketSim's car-car 0.09 / 0.1 and car-world 0.3 / 0.32 (RocketSim: 0.3).
CAR_FRICTION = math.sqrt(C.CAR_CAR_FRICTION)
# RocketSim's cars meet only once their hitboxes overlap by 0.134 uu (bisected to 1e-6); PyBullet's meet at any
# overlap. Each car's PyBullet box is half that smaller per face, so contacts start where RocketSim's do (the ball
# meets the full box in ball_kernel).
CAR_CONTACT_SHRINK = 0.134 / 2
CAR_RESTITUTION = math.sqrt(C.CAR_CAR_RESTITUTION)


@functools.lru_cache(maxsize=None)
def _arena_mesh_lists(arena_shape: str) -> tuple[list, list]:
    """The arena's walls, goals and ramps as the nested lists (m; indices) ``createCollisionShape`` takes, made once
    per process and shape: PyBullet keeps a reference to every vertex row it is given and never lets go of it, so
    fresh lists for every world leaked about 1.45 MB each (about 320 MB over a league's 220 matches in one
    process)."""
    verts, idx = shape_mesh(arena_shape, with_floor_and_ceiling=False)  # the world's planes are floor and ceiling
    return (verts * M_PER_UU).tolist(), idx.reshape(-1).tolist()


def box_vector(name: str, value) -> np.ndarray:
    """``value`` as 3 finite floats (uu), or a ValueError naming ``name``."""
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected 3 finite numbers (uu), got {value!r}")
    return arr


class BulletWorld:
    """One PyBullet client holding the static world of ``len(origins)`` arenas (shared floor and ceiling planes,
    one arena mesh at each origin), the cars' and static boxes' bodies, and the log that remakes them."""

    def __init__(self, origins: np.ndarray, arena_shape: str, dt: float, gravity_z_uu_s2: float):
        self.origins = origins
        self.arena_shape = arena_shape
        self.dt = dt
        self.gravity_z_uu_s2 = gravity_z_uu_s2
        # Every body made or removed after the static world, in order: a copy of the world replays it (see
        # _restore) so that its bodies have the same ids and the same order in Bullet's arrays.
        self.body_log: list[tuple] = []
        self.client: int | None = None
        self._connect()
        self.static_boxes: dict[int, np.ndarray] = {}  # PyBullet body id -> (arena, centre xyz, half extents xyz) uu
        self.box_rows = np.zeros((0, 7))  # the same, stacked for the ball kernel

    # ------------------------------------------------------------------ construction
    def _connect(self) -> None:
        """A PyBullet world of its own with this world's settings and static bodies."""
        self.client = pb.connect(pb.DIRECT)
        cid = self.client
        pb.setGravity(0, 0, self.gravity_z_uu_s2 * M_PER_UU, physicsClientId=cid)
        # RocketSim's solver: 10 iterations, no restitution under 10 uu/s. (Its overlap correction, 0.8 a tick by
        # split impulse, is not PyBullet's to set: contactERP 0.8 feeds a velocity bias here, which made cars leave
        # walls faster than they came.)
        pb.setPhysicsEngineParameter(fixedTimeStep=self.dt, numSubSteps=0, numSolverIterations=10,
                                     deterministicOverlappingPairs=1, restitutionVelocityThreshold=10.0 * M_PER_UU,
                                     contactERP=0.0, physicsClientId=cid)
        self._build_static_world()

    def _build_static_world(self) -> None:
        cid = self.client
        vertices, indices = _arena_mesh_lists(self.arena_shape)
        # The game shape's mesh gets Bullet's internal-edge contacts, as RocketSim's meshes do (a box sliding over a
        # fillet's quads is not kicked sideways by their diagonals).
        flags = pb.GEOM_FORCE_CONCAVE_TRIMESH | (pb.GEOM_CONCAVE_INTERNAL_EDGE if self.arena_shape == "game" else 0)
        shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=vertices, indices=indices, flags=flags,
                                        physicsClientId=cid)
        floor = pb.createCollisionShape(pb.GEOM_PLANE, planeNormal=[0, 0, 1], physicsClientId=cid)
        ceiling = pb.createCollisionShape(pb.GEOM_PLANE, planeNormal=[0, 0, -1], physicsClientId=cid)
        self.static_bodies = [
            pb.createMultiBody(0, floor, basePosition=[0, 0, 0], physicsClientId=cid),
            pb.createMultiBody(0, ceiling, basePosition=[0, 0, C.ARENA_HEIGHT * M_PER_UU], physicsClientId=cid)]
        for origin in self.origins:
            self.static_bodies.append(
                pb.createMultiBody(0, shape, basePosition=(origin * M_PER_UU).tolist(), physicsClientId=cid))
        # Bullet multiplies both bodies' materials; the arena's 1.0 lets each body's own value through.
        self.static_set = set(self.static_bodies)
        for body in self.static_bodies:
            pb.changeDynamics(body, -1, lateralFriction=1.0, restitution=1.0, rollingFriction=0.0,
                              spinningFriction=0.0, physicsClientId=cid)

    def set_gravity(self, gravity_z_uu_s2: float) -> None:
        self.gravity_z_uu_s2 = gravity_z_uu_s2
        pb.setGravity(0, 0, gravity_z_uu_s2 * M_PER_UU, physicsClientId=self.client)

    # ------------------------------------------------------------------ car bodies
    def create_car_body(self, arena: int, cfg: CarConfig) -> int:
        cid = self.client
        half = [(s * 0.5 - CAR_CONTACT_SHRINK) * M_PER_UU for s in cfg.hitbox_size]
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half,
                                        collisionFramePosition=[o * M_PER_UU for o in cfg.hitbox_offset],
                                        physicsClientId=cid)
        start = self.origins[arena] + np.array([0.0, 0.0, C.CAR_SPAWN_REST_Z])
        body = pb.createMultiBody(C.CAR_MASS, shape, basePosition=(start * M_PER_UU).tolist(),
                                  useMaximalCoordinates=True, physicsClientId=cid)
        self.set_car_dynamics(body, cfg)
        self.body_log.append(("car", body, arena, cfg))
        return body

    def set_car_dynamics(self, body: int, cfg: CarConfig) -> None:
        pb.changeDynamics(body, -1, mass=C.CAR_MASS, localInertiaDiagonal=cfg.inertia_diag.tolist(),
                          lateralFriction=CAR_FRICTION, restitution=CAR_RESTITUTION, linearDamping=0.0,
                          angularDamping=0.0, rollingFriction=0.0, spinningFriction=0.0,
                          activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=self.client)

    def take_out_of_play(self, body: int) -> None:
        """A demoed car leaves the world: no collisions, no gravity, until it respawns."""
        pb.setCollisionFilterGroupMask(body, -1, 0, 0, physicsClientId=self.client)
        pb.changeDynamics(body, -1, mass=0.0, physicsClientId=self.client)

    def bring_into_play(self, body: int, cfg: CarConfig) -> None:
        """A respawning car collides and falls again (Bullet's default collision filter, the car's dynamics)."""
        pb.setCollisionFilterGroupMask(body, -1, 1, -1, physicsClientId=self.client)
        self.set_car_dynamics(body, cfg)

    def remove_body(self, body: int) -> None:
        pb.removeBody(body, physicsClientId=self.client)
        self.body_log.append(("remove", body))

    # ------------------------------------------------------------------ static boxes (minigame barriers)
    def add_static_box(self, arena: int, center_uu: np.ndarray, half_extents_uu: np.ndarray) -> int:
        """An immovable axis-aligned box in ``arena`` that cars and the ball collide with; returns its id.

        Cars meet it in PyBullet with the arena's materials (friction and restitution 1.0, so each car's own value
        applies); the ball meets it as part of the arena (``ball_kernel``).
        """
        if not isinstance(arena, (int, np.integer)) or not 0 <= arena < len(self.origins):
            raise ValueError(f"arena: must be an index in 0..{len(self.origins) - 1}, got {arena!r}")
        center = box_vector("center_uu", center_uu)
        half = box_vector("half_extents_uu", half_extents_uu)
        if np.any(half <= 0.0):
            raise ValueError(f"half_extents_uu: must all be > 0, got {half.tolist()}")
        body = self._create_box_body(arena, center, half)
        self.static_set.add(body)  # cars touching it count as touching the arena (auto-flip, auto-roll)
        self.static_boxes[body] = np.concatenate(([arena], center, half))
        self._stack_boxes()
        return body

    def _create_box_body(self, arena: int, center: np.ndarray, half: np.ndarray) -> int:
        cid = self.client
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(half * M_PER_UU).tolist(), physicsClientId=cid)
        body = pb.createMultiBody(0, shape, basePosition=((center + self.origins[arena]) * M_PER_UU).tolist(),
                                  physicsClientId=cid)
        pb.changeDynamics(body, -1, lateralFriction=1.0, restitution=1.0, rollingFriction=0.0,
                          spinningFriction=0.0, physicsClientId=cid)
        self.body_log.append(("box", body, arena, center.copy(), half.copy()))
        return body

    def _stack_boxes(self) -> None:
        self.box_rows = np.array(list(self.static_boxes.values()), dtype=np.float64).reshape(-1, 7)

    def static_box_half_extents(self, box_id: int) -> np.ndarray:
        self._static_box_arena(box_id)
        return self.static_boxes[box_id][4:7].copy()

    def move_static_box(self, box_id: int, center_uu: np.ndarray) -> None:
        """Put a static box's centre at ``center_uu`` (between rounds; it does not sweep through bodies)."""
        arena = self._static_box_arena(box_id)
        center = box_vector("center_uu", center_uu)
        self._place_static_box(box_id, arena, center)
        self.static_boxes[box_id][1:4] = center
        self._stack_boxes()

    def _place_static_box(self, box_id: int, arena: int, center: np.ndarray) -> None:
        pb.resetBasePositionAndOrientation(box_id, ((center + self.origins[arena]) * M_PER_UU).tolist(),
                                           (0, 0, 0, 1), physicsClientId=self.client)

    def remove_static_box(self, box_id: int) -> None:
        self._static_box_arena(box_id)
        self.remove_body(box_id)
        self.static_set.discard(box_id)
        del self.static_boxes[box_id]
        self._stack_boxes()

    def _static_box_arena(self, box_id: int) -> int:
        if box_id not in self.static_boxes:
            raise ValueError(f"box_id: no static box {box_id!r}; boxes are {sorted(self.static_boxes)}")
        return int(self.static_boxes[box_id][0])

    # ------------------------------------------------------------------ copies (copy.deepcopy, pickle) and renewal
    def __getstate__(self) -> dict:
        """Everything but the PyBullet connection, plus the PyBullet world as a ``.bullet`` snapshot (transforms,
        velocities, the contact cache that warm-starts the next solve).

        A snapshot does not hold all of Bullet's internals (e.g. the broadphase's history), so a world restored
        from it goes on a little differently (float rounding) than the world it was taken from. To give the copy
        exactly this world's future, this world moves onto a fresh PyBullet world restored from the same
        snapshot too: its state is unchanged, and from here on it and every copy step identically."""
        snapshot = None
        if self.client is not None:  # a closed world copies as a closed world
            snapshot = self._snapshot()
            old_client = self.client
            self._restore(snapshot)
            pb.disconnect(old_client)
        state = self.__dict__.copy()
        state["client"] = None
        state["_bullet_bytes"] = snapshot
        return state

    def __setstate__(self, state: dict) -> None:
        snapshot = state.pop("_bullet_bytes")
        self.__dict__.update(state)
        if snapshot is not None:
            self._restore(snapshot)

    def _snapshot(self) -> bytes:
        fd, path = tempfile.mkstemp(suffix=".bullet")
        os.close(fd)
        try:
            pb.saveBullet(path, physicsClientId=self.client)
            return Path(path).read_bytes()
        finally:
            os.unlink(path)

    def renew(self) -> None:
        """Move onto a new PyBullet world with the same bodies (same ids), settings and static boxes where they are,
        and none of Bullet's memory of earlier ticks; the cars' poses and demolitions are the caller's to put back
        (``PhysicsWorld.renew_bullet_world``)."""
        old_client = self.client
        self._remake_bodies()
        pb.disconnect(old_client)
        for box_id, row in self.static_boxes.items():
            self._place_static_box(box_id, int(row[0]), row[1:4])

    def _remake_bodies(self) -> None:
        """Connect to a new PyBullet world: the static world, then the logged bodies made again in their order (so
        they get the same ids)."""
        kept = {key: getattr(self, key) for key in ("static_bodies", "static_set", "body_log")}
        self.body_log = []
        self._connect()
        for entry in kept["body_log"]:
            if entry[0] == "car":
                body = self.create_car_body(entry[2], entry[3])
            elif entry[0] == "box":
                body = self._create_box_body(entry[2], entry[3], entry[4])
            else:
                self.remove_body(entry[1])
                continue
            if body != entry[1]:
                raise RuntimeError(f"PhysicsWorld: body {entry[1]} came back as {body} in the new PyBullet world")
        self.__dict__.update(kept)

    def _restore(self, snapshot: bytes) -> None:
        """Connect to a new PyBullet world with the same bodies, then restore ``snapshot`` onto them."""
        self._remake_bodies()
        fd, path = tempfile.mkstemp(suffix=".bullet")
        try:
            os.write(fd, snapshot)
            os.close(fd)
            pb.restoreState(fileName=path, physicsClientId=self.client)
        finally:
            os.unlink(path)

    def close(self) -> None:
        if self.client is not None and pb.isConnected(self.client):
            pb.disconnect(self.client)
        self.client = None
