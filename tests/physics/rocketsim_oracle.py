"""Two small simulator adapters with one interface: RocketSim (the oracle) and our PyBullet ``Arena``.

Everything is in Rocket League units (uu, uu/s, rad; z up). ``rot_mat`` is 3x3 with the COLUMNS forward, right, up.

RocketSim needs collision meshes before its first arena is made. ``init_rocketsim(dir)`` writes one dummy ``.cmf``
mesh (a single tiny triangle at z = -5000) into ``dir/soccar/`` and calls ``RocketSim.init`` once per process, so only
RocketSim's four built-in planes exist: floor z = 0, ceiling z = 2048, side walls x = +-4096 and no back walls
(docs/reference/physics.md sections 1 and 12). The fidelity scenarios therefore stay well inside |x| < 3500, |y| < 4600.

Interface of both adapters::

    sim.add_car(preset="octane")
    sim.set_car(pos, vel=(0,0,0), ang_vel=(0,0,0), rot_mat=None, yaw=0.0, boost=100/3)
    sim.set_ball(pos, vel=(0,0,0), ang_vel=(0,0,0))
    sim.set_controls(throttle=0, steer=0, pitch=0, yaw=0, roll=0, jump=False, boost=False, handbrake=False)
    sim.step(n=1)
    sim.car()  -> dict(pos, vel, ang_vel, rot_mat, on_ground, boost)
    sim.car_mechanics() -> dict of the jump/flip/supersonic flags and timers (MECHANICS_FIELDS, our CarState names)
    sim.ball() -> dict(pos, vel, ang_vel)
    sim.close()
"""
from __future__ import annotations

import math
import os
import struct
import tempfile

import numpy as np

TICK_RATE = 120
DT = 1.0 / TICK_RATE
CAR_REST_Z = 17.03  # measured Octane resting CoM height (docs/reference/physics.md section 12)
BALL_REST_Z = 93.15
# Where the ball is parked in car-only scenarios: far from every scripted car path, away from walls and corners.
BALL_PARKED = (3000.0, 4000.0, BALL_REST_Z)

_RS_INITIALISED_DIR: str | None = None


def write_dummy_mesh(mesh_dir: str) -> str:
    """Write ``mesh_dir/soccar/dummy.cmf``: one tiny triangle far below the floor. Returns ``mesh_dir``.

    CMF layout (little-endian): int32 triangle count, int32 vertex count, triangles as 3 x int32 vertex indices,
    vertices as 3 x float32.
    """
    soccar = os.path.join(mesh_dir, "soccar")
    os.makedirs(soccar, exist_ok=True)
    verts = [(0.0, 0.0, -5000.0), (1.0, 0.0, -5000.0), (0.0, 1.0, -5000.0)]
    with open(os.path.join(soccar, "dummy.cmf"), "wb") as f:
        f.write(struct.pack("<ii", 1, len(verts)))
        f.write(struct.pack("<iii", 0, 1, 2))
        for v in verts:
            f.write(struct.pack("<fff", *v))
    return mesh_dir


def init_rocketsim(mesh_dir: str | None = None) -> str:
    """Idempotent ``RocketSim.init`` on a dummy-mesh folder (RocketSim allows one init per process).

    ``mesh_dir`` defaults to a fresh temporary folder. Returns the folder actually used.
    """
    global _RS_INITIALISED_DIR
    if _RS_INITIALISED_DIR is not None:
        return _RS_INITIALISED_DIR
    import RocketSim as rs
    if mesh_dir is None:
        mesh_dir = tempfile.mkdtemp(prefix="rocketsim_dummy_meshes_")
    write_dummy_mesh(mesh_dir)
    rs.init(str(mesh_dir))
    _RS_INITIALISED_DIR = str(mesh_dir)
    return _RS_INITIALISED_DIR


def yaw_rot_mat(yaw: float) -> np.ndarray:
    """Rotation matrix (columns forward, right, up) of a level car facing ``yaw``."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack(([c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]))


# Our CarState name -> RocketSim's CarState name, for ``car_mechanics``.
MECHANICS_FIELDS = {"has_jumped": "has_jumped", "is_jumping": "is_jumping", "jump_time": "jump_time",
                    "has_double_jumped": "has_double_jumped", "has_flipped": "has_flipped",
                    "is_flipping": "is_flipping", "flip_time": "flip_time",
                    "air_time_since_jump": "air_time_since_jump", "is_supersonic": "is_supersonic",
                    "supersonic_time": "supersonic_time", "on_ground": "is_on_ground"}


def _rot(rot_mat, yaw) -> np.ndarray:
    return yaw_rot_mat(yaw) if rot_mat is None else np.asarray(rot_mat, dtype=np.float64)


class RocketSimAdapter:
    """RocketSim 2.2.x soccar arena on the dummy mesh (planes only). ``init_rocketsim`` must have run first,
    or is run here with a temporary folder."""

    name = "RocketSim"

    def __init__(self, park_ball: bool = True):
        import RocketSim as rs
        init_rocketsim()
        self._rs = rs
        self.arena = rs.Arena(rs.GameMode.SOCCAR, tick_rate=float(TICK_RATE))
        self._car = None
        if park_ball:
            self.set_ball(BALL_PARKED)

    # --- helpers
    def _vec(self, v):
        return self._rs.Vec(*(float(x) for x in v))

    def add_car(self, preset: str = "octane"):
        rs = self._rs
        template = getattr(rs.CarConfig, preset.upper())
        self._car = self.arena.add_car(rs.Team.BLUE, rs.CarConfig(template))
        return self._car

    def set_car(self, pos, vel=(0.0, 0.0, 0.0), ang_vel=(0.0, 0.0, 0.0), rot_mat=None, yaw: float = 0.0,
                boost: float = 100.0 / 3.0):
        rs = self._rs
        r = _rot(rot_mat, yaw)
        st = rs.CarState()
        st.pos = self._vec(pos)
        st.vel = self._vec(vel)
        st.ang_vel = self._vec(ang_vel)
        # RotMat(forward, right, up): our columns.
        st.rot_mat = rs.RotMat(self._vec(r[:, 0]), self._vec(r[:, 1]), self._vec(r[:, 2]))
        st.boost = float(boost)
        st.is_on_ground = False  # RocketSim's CarState() default is True; let the wheel rays decide next tick
        self._car.set_state(st)

    def set_ball(self, pos, vel=(0.0, 0.0, 0.0), ang_vel=(0.0, 0.0, 0.0)):
        st = self._rs.BallState()
        st.pos = self._vec(pos)
        st.vel = self._vec(vel)
        st.ang_vel = self._vec(ang_vel)
        self.arena.ball.set_state(st)

    def set_controls(self, throttle=0.0, steer=0.0, pitch=0.0, yaw=0.0, roll=0.0, jump=False, boost=False,
                     handbrake=False):
        c = self._rs.CarControls()
        c.throttle, c.steer, c.pitch, c.yaw, c.roll = (float(throttle), float(steer), float(pitch), float(yaw),
                                                       float(roll))
        c.jump, c.boost, c.handbrake = bool(jump), bool(boost), bool(handbrake)
        self._car.set_controls(c)

    def step(self, n: int = 1):
        self.arena.step(int(n))

    def car(self) -> dict:
        s = self._car.get_state()
        return dict(pos=s.pos.as_numpy().astype(np.float64), vel=s.vel.as_numpy().astype(np.float64),
                    ang_vel=s.ang_vel.as_numpy().astype(np.float64),
                    # as_numpy() gives the ROWS forward, right, up; transpose to our column convention.
                    rot_mat=s.rot_mat.as_numpy().astype(np.float64).T,
                    on_ground=bool(s.is_on_ground), boost=float(s.boost))

    def car_mechanics(self) -> dict:
        s = self._car.get_state()
        return {ours: getattr(s, theirs) for ours, theirs in MECHANICS_FIELDS.items()}

    def ball(self) -> dict:
        s = self.arena.ball.get_state()
        return dict(pos=s.pos.as_numpy().astype(np.float64), vel=s.vel.as_numpy().astype(np.float64),
                    ang_vel=s.ang_vel.as_numpy().astype(np.float64))

    def close(self):
        self.arena = None
        self._car = None


class OursAdapter:
    """Our PyBullet ``rocketdrl_ma.physics.Arena`` behind the same interface (imported lazily)."""

    name = "ours"

    def __init__(self, park_ball: bool = True):
        from rocketdrl_ma import physics
        self._p = physics
        self.arena = physics.Arena(tick_rate=TICK_RATE)
        self._car = None
        if park_ball:
            self.set_ball(BALL_PARKED)

    def add_car(self, preset: str = "octane"):
        self._car = self.arena.add_car(team=0, preset=preset)
        return self._car

    def set_car(self, pos, vel=(0.0, 0.0, 0.0), ang_vel=(0.0, 0.0, 0.0), rot_mat=None, yaw: float = 0.0,
                boost: float = 100.0 / 3.0):
        self._car.set_state(self._p.CarState(pos=np.asarray(pos, float), vel=np.asarray(vel, float),
                                             ang_vel=np.asarray(ang_vel, float), rot_mat=_rot(rot_mat, yaw),
                                             boost=float(boost)))

    def set_ball(self, pos, vel=(0.0, 0.0, 0.0), ang_vel=(0.0, 0.0, 0.0)):
        self.arena.ball.set_state(self._p.BallState(pos=np.asarray(pos, float), vel=np.asarray(vel, float),
                                                    ang_vel=np.asarray(ang_vel, float)))

    def set_controls(self, throttle=0.0, steer=0.0, pitch=0.0, yaw=0.0, roll=0.0, jump=False, boost=False,
                     handbrake=False):
        clip = lambda v: float(min(1.0, max(-1.0, v)))  # noqa: E731  (our CarControls rejects out-of-range input)
        self._car.set_controls(self._p.CarControls(throttle=clip(throttle), steer=clip(steer), pitch=clip(pitch),
                                                   yaw=clip(yaw), roll=clip(roll), jump=bool(jump),
                                                   boost=bool(boost), handbrake=bool(handbrake)))

    def step(self, n: int = 1):
        self.arena.step(int(n))

    def car(self) -> dict:
        s = self._car.get_state()
        return dict(pos=np.array(s.pos, float), vel=np.array(s.vel, float), ang_vel=np.array(s.ang_vel, float),
                    rot_mat=np.array(s.rot_mat, float), on_ground=bool(s.on_ground), boost=float(s.boost))

    def car_mechanics(self) -> dict:
        s = self._car.get_state()
        return {ours: getattr(s, ours) for ours in MECHANICS_FIELDS}

    def ball(self) -> dict:
        s = self.arena.ball.get_state()
        return dict(pos=np.array(s.pos, float), vel=np.array(s.vel, float), ang_vel=np.array(s.ang_vel, float))

    def close(self):
        if self.arena is not None:
            self.arena.close()
        self.arena = None
        self._car = None
