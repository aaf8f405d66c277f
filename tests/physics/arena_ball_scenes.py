"""A zero-g ball off every surface family of the game-shaped arena, run on RocketSim with the game's collision
meshes (``rocketsim_mesh_oracle``) and on ours (``arena_shape="game"``): issue 49's ball grid.

Each family is a point on the game's surface with its normal ``n`` (into the playable space) and a tangent ``t``;
a cell is a speed and an incidence (the angle between the ball's path and ``-n``, the path turned towards ``t``),
and each cell is played at ``PHASES`` sub-tick phases: the start is moved back along the path by ``(k + 1/2) /
PHASES`` of a tick's travel, so the contact falls at every fraction of a tick. The ball would touch the surface
at that point ``APPROACH_TICKS`` (or more, so that it starts at least ``START_GAP_UU`` off the surface) after its
start. ``outgoing_velocity`` reads a trace only (the velocity ``AFTER_CONTACT_TICKS`` after the first tick whose
velocity change is a contact's), so both simulators are measured the same way.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rocketsim_mesh_oracle import TICK_RATE, BallScene

BALL_RADIUS = 91.25
PHASES = 8
SPEEDS_UU_S = (500.0, 1500.0, 3000.0)
INCIDENCES_DEG = (15.0, 45.0, 75.0)
APPROACH_TICKS = 4
START_GAP_UU = 10.0
AFTER_CONTACT_TICKS = 12
CONTACT_DV_FRACTION = 0.005  # a tick's velocity change above this share of the speed is a contact (drag: 0.03 %)


@dataclass(frozen=True)
class SurfaceFamily:
    point: tuple[float, float, float]    # on the game's surface (uu)
    normal: tuple[float, float, float]   # unit, into the playable space
    tangent: tuple[float, float, float]  # unit, along the surface: the path leans this way as the incidence grows


_H = math.sqrt(0.5)
SIDE_Y = 1440.0  # away from the meshes' seams at x = 0 and y = 0 (the game's mirror planes)
_S40, _C40 = math.sin(math.radians(40.0)), math.cos(math.radians(40.0))
# the net's back is a polygon too (vertices every 11.6 degrees about (|y|, z) = (5760, 256), columns every 256 uu
# in x): aim between its vertices and off its quads' diagonals, at 5.8 degrees up and a quarter quad in x
_S_BACK, _C_BACK = math.sin(math.radians(5.81)), math.cos(math.radians(5.81))

# 40 degrees round each fillet from the floor or ceiling (between the polygons' vertices at 45 and 56 from the
# wall); the flat walls above the fillets' tops (256 on the side walls, 160 on the back walls) and high up; the
# corner wall between its vertical roundings; the +x post's and the crossbar's 45 degree bevels at their middle;
# the net's back.
FAMILIES = {
    "floor_fillet_side": SurfaceFamily((3840.0 + 256.0 * _S40, SIDE_Y, 256.0 - 256.0 * _C40), (-_S40, 0.0, _C40),
                                       (0.0, 1.0, 0.0)),
    "floor_fillet_back": SurfaceFamily((2000.0, 4960.0 + 160.0 * _S40, 160.0 - 160.0 * _C40), (0.0, -_S40, _C40),
                                       (1.0, 0.0, 0.0)),
    "ceiling_fillet_side": SurfaceFamily((3584.0 + 512.0 * _S40, SIDE_Y, 1536.0 + 512.0 * _C40), (-_S40, 0.0, -_C40),
                                         (0.0, 1.0, 0.0)),
    "wall_low_side": SurfaceFamily((4096.0, SIDE_Y, 320.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "wall_low_back": SurfaceFamily((1500.0, 5120.0, 220.0), (0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),
    "wall_high_side": SurfaceFamily((4096.0, SIDE_Y, 1000.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    "corner": SurfaceFamily((3523.0, 4541.0, 600.0), (-_H, -_H, 0.0), (_H, -_H, 0.0)),
    "post": SurfaceFamily((900.0, 5124.0, 300.0), (-_H, -_H, 0.0), (-_H, _H, 0.0)),
    "crossbar": SurfaceFamily((300.0, 5124.0, 644.0), (0.0, -_H, -_H), (0.0, _H, -_H)),
    "goal_back": SurfaceFamily((320.0, 5760.0 + 240.0 * _C_BACK, 256.0 + 240.0 * _S_BACK), (0.0, -_C_BACK, -_S_BACK),
                               (1.0, 0.0, 0.0)),
}


@dataclass(frozen=True)
class GridScene:
    key: str  # family-speed-incidence-phase
    family: str
    speed_uu_s: float
    incidence_deg: float
    phase: int
    scene: BallScene


def _cell_key(family: str, speed: float, incidence: float) -> str:
    return f"{family}-{speed:g}-{incidence:g}"


def cell_of(key: str) -> str:
    """The cell (family-speed-incidence) a scene's key belongs to."""
    return key.rsplit("-", 1)[0]


def ball_grid() -> list[GridScene]:
    scenes = []
    for name, fam in FAMILIES.items():
        n, t = np.array(fam.normal), np.array(fam.tangent)
        centre_at_contact = np.array(fam.point) + BALL_RADIUS * n
        for speed in SPEEDS_UU_S:
            for incidence in INCIDENCES_DEG:
                a = math.radians(incidence)
                direction = -math.cos(a) * n + math.sin(a) * t
                closing_uu_s = speed * math.cos(a)
                approach = max(APPROACH_TICKS, math.ceil(START_GAP_UU * TICK_RATE / closing_uu_s))
                for k in range(PHASES):
                    back_s = (approach + (k + 0.5) / PHASES) / TICK_RATE
                    start = centre_at_contact - direction * speed * back_s
                    scene = BallScene(pos=tuple(start.tolist()), vel=tuple((direction * speed).tolist()),
                                      ticks=approach + AFTER_CONTACT_TICKS + 8, gravity_z=0.0)
                    scenes.append(GridScene(f"{_cell_key(name, speed, incidence)}-{k}", name, speed, incidence, k,
                                            scene))
    return scenes


def run_ours(scenes: list[GridScene], batch_size: int = 128, arena_shape: str = "game") -> list[np.ndarray]:
    """The ball's velocity after every tick ((ticks, 3) each) in our arena of ``arena_shape``, ``batch_size`` at
    once."""
    out: list[np.ndarray] = []
    for start in range(0, len(scenes), batch_size):
        out += _run_ours_batch([s.scene for s in scenes[start:start + batch_size]], arena_shape)
    return out


def _run_ours_batch(scenes: list[BallScene], arena_shape: str) -> list[np.ndarray]:
    from rocketdrl_ma.physics import ArenaBatch, BallState, MutatorConfig
    batch = ArenaBatch(len(scenes), tick_rate=TICK_RATE, arena_shape=arena_shape)
    try:
        (gravity_z,) = {s.gravity_z for s in scenes}  # the arenas of a batch share one gravity
        batch.set_mutator_config(MutatorConfig(gravity_z_uu_s2=gravity_z))
        for arena, scene in zip(batch.arenas, scenes):
            arena.ball.set_state(BallState(pos=np.array(scene.pos), vel=np.array(scene.vel),
                                           ang_vel=np.array(scene.ang_vel)))
        ticks = max(s.ticks for s in scenes)
        vel = np.zeros((len(scenes), ticks, 3))
        for t in range(ticks):
            batch.step(1)
            vel[:, t] = batch.arrays().ball_vel[:len(scenes)]
        return [vel[k, :s.ticks] for k, s in enumerate(scenes)]
    finally:
        batch.close()


def first_contact_tick(vel: np.ndarray, start_vel: np.ndarray) -> int | None:
    """The index of the first tick whose velocity change is a contact's, None if there is none."""
    before = np.vstack([start_vel[None, :], vel[:-1]])
    change = np.linalg.norm(vel - before, axis=1) > CONTACT_DV_FRACTION * np.linalg.norm(before, axis=1)
    return int(np.argmax(change)) if change.any() else None


def outgoing_velocity(vel: np.ndarray, contact_tick: int) -> np.ndarray:
    """The velocity ``AFTER_CONTACT_TICKS`` after ``contact_tick`` (or the last one recorded)."""
    return vel[min(contact_tick + AFTER_CONTACT_TICKS, len(vel) - 1)]


def outgoing_pairs(scenes: list[GridScene], theirs: list[np.ndarray], ours: list[np.ndarray]
                   ) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per scene key, (RocketSim's outgoing velocity, ours), both read ``AFTER_CONTACT_TICKS`` after the later of
    the two first contact ticks; ValueError naming the scene if a ball never met the surface or met it before the
    scene's approach was over (it started too close)."""
    out = {}
    for scene, a, b in zip(scenes, theirs, ours):
        start_vel = np.array(scene.scene.vel)
        contacts = first_contact_tick(a, start_vel), first_contact_tick(b, start_vel)
        if None in contacts or min(contacts) < APPROACH_TICKS - 1:
            raise ValueError(f"scene {scene.key}: the ball's first contact ticks (RocketSim's, ours) are {contacts}, "
                             f"expected after the approach's {APPROACH_TICKS - 1} ticks")
        tick = max(contacts)
        out[scene.key] = outgoing_velocity(a, tick), outgoing_velocity(b, tick)
    return out


def speed_and_angle_error(ours: np.ndarray, theirs: np.ndarray) -> tuple[float, float]:
    """Our speed's relative error and the angle (degrees) between the two velocities."""
    speed = float(np.linalg.norm(ours) / np.linalg.norm(theirs) - 1.0)
    cos = float(np.dot(ours, theirs) / (np.linalg.norm(ours) * np.linalg.norm(theirs)))
    return speed, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
