"""RocketSim on the game's arena meshes (the ones ``rlgym-rocket-league`` installs), as a test oracle.

``RocketSim.init`` loads meshes once per process and ignores any later call, and the planes-only oracle
(``rocketsim_oracle.init_rocketsim``, called by the physics and RLGym fixtures) has usually run first in a pytest
process. So every run here happens in a fresh Python process (this file run as a script) that initialises
RocketSim with the mesh folder; the results come back as JSON and are cached for the test session.

``ball_trajectories_on_meshes(scenes)`` runs each ``BallScene`` (a ball alone in a soccar arena) and returns
per tick after each step: the ball's position, velocity and angular velocity. ``car_trajectories_on_meshes(scenes)``
runs each ``CarScene`` (one car under constant controls, the ball parked) the same way for the car.
"""
from __future__ import annotations

import functools
import json
import math
import subprocess
import sys
from dataclasses import asdict, dataclass

import numpy as np

TICK_RATE = 120
WORKER_TIMEOUT_S = 300


@dataclass(frozen=True)
class BallScene:
    pos: tuple[float, float, float]
    vel: tuple[float, float, float]
    ticks: int
    ang_vel: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gravity_z: float = -650.0


@dataclass(frozen=True)
class CarScene:
    """One car placed level (``yaw``) at ``pos`` with ``vel``, held ``controls`` (CarControls field names)."""
    pos: tuple[float, float, float]
    vel: tuple[float, float, float]
    ticks: int
    yaw: float = 0.0
    boost: float = 100.0
    preset: str = "octane"
    controls: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class BallTrajectory:
    pos: np.ndarray  # (ticks, 3), after each tick
    vel: np.ndarray
    ang_vel: np.ndarray


def mesh_folder_or_none() -> str | None:
    """The collision mesh folder of the installed ``rlgym-rocket-league``, None if it is missing."""
    from rocketdrl_ma.physics.mesh_file import installed_rlgym_mesh_folder
    folder = installed_rlgym_mesh_folder()
    return None if folder is None else str(folder)


def mesh_folder_or_skip() -> str:
    """The installed collision mesh folder; skips the calling test without RocketSim or the meshes."""
    import pytest
    pytest.importorskip("RocketSim", reason="the rocketsim package (test extra) is the physics oracle")
    folder = mesh_folder_or_none()
    if folder is None:
        pytest.skip("rlgym-rocket-league's collision meshes are not installed")
    return folder


def ball_trajectories_on_meshes(scenes: list[BallScene], mesh_folder: str | None = None) -> list[BallTrajectory]:
    """Each scene run on RocketSim with the real arena meshes (in a subprocess; see the module docstring).
    ``mesh_folder`` defaults to the installed ``rlgym-rocket-league``'s; ValueError if there is none."""
    folder = mesh_folder or mesh_folder_or_none()
    if folder is None:
        raise ValueError("mesh_folder: none given and rlgym-rocket-league's collision meshes are not installed")
    return list(_run_cached(folder, tuple(scenes)))


def car_trajectories_on_meshes(scenes: list[CarScene], mesh_folder: str | None = None) -> list[BallTrajectory]:
    """Each car scene on RocketSim with the real arena meshes: the car's position, velocity and angular velocity
    after every tick (a ``BallTrajectory`` of the car)."""
    folder = mesh_folder or mesh_folder_or_none()
    if folder is None:
        raise ValueError("mesh_folder: none given and rlgym-rocket-league's collision meshes are not installed")
    return list(_run_cached(folder, tuple(scenes)))


@functools.lru_cache(maxsize=None)
def _run_cached(folder: str, scenes: tuple[BallScene | CarScene, ...]) -> tuple[BallTrajectory, ...]:
    request = json.dumps({"mesh_folder": folder,
                          "scenes": [dict(asdict(s), kind=type(s).__name__) for s in scenes]})
    done = subprocess.run([sys.executable, __file__], input=request, capture_output=True, text=True,
                          timeout=WORKER_TIMEOUT_S, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"RocketSim mesh worker failed ({done.returncode}):\n{done.stderr[-4000:]}")
    results = json.loads(done.stdout.strip().splitlines()[-1])
    return tuple(BallTrajectory(*(np.array(r[k], dtype=np.float64) for k in ("pos", "vel", "ang_vel")))
                 for r in results)


def _worker() -> None:
    """Read a request on stdin, run it on RocketSim initialised with the meshes, print the results as JSON."""
    import RocketSim as rs
    request = json.loads(sys.stdin.read())
    rs.init(request["mesh_folder"])
    out = []
    for scene in request["scenes"]:
        if scene["kind"] == "CarScene":
            out.append(_car_scene(rs, scene))
            continue
        arena = rs.Arena(rs.GameMode.SOCCAR, tick_rate=float(TICK_RATE))
        mutators = arena.get_mutator_config()
        mutators.gravity = rs.Vec(0.0, 0.0, float(scene["gravity_z"]))
        arena.set_mutator_config(mutators)
        state = rs.BallState()
        state.pos, state.vel, state.ang_vel = (rs.Vec(*map(float, scene[k])) for k in ("pos", "vel", "ang_vel"))
        arena.ball.set_state(state)
        pos, vel, ang_vel = [], [], []
        for _ in range(int(scene["ticks"])):
            arena.step(1)
            s = arena.ball.get_state()
            pos.append(s.pos.as_numpy().tolist())
            vel.append(s.vel.as_numpy().tolist())
            ang_vel.append(s.ang_vel.as_numpy().tolist())
        out.append({"pos": pos, "vel": vel, "ang_vel": ang_vel})
    print(json.dumps(out))


def _car_scene(rs, scene: dict) -> dict:
    arena = rs.Arena(rs.GameMode.SOCCAR, tick_rate=float(TICK_RATE))
    ball = rs.BallState()
    ball.pos = rs.Vec(0.0, 3000.0, 93.15)
    arena.ball.set_state(ball)
    arena.step(1)  # a new arena's first tick solves on Bullet's default 1/60 s step (test_spawn_fidelity.py)
    car = arena.add_car(rs.Team.BLUE, rs.CarConfig(getattr(rs.CarConfig, scene["preset"].upper())))
    c, s = math.cos(scene["yaw"]), math.sin(scene["yaw"])
    state = rs.CarState()
    state.pos, state.vel = rs.Vec(*map(float, scene["pos"])), rs.Vec(*map(float, scene["vel"]))
    state.rot_mat = rs.RotMat(rs.Vec(c, s, 0.0), rs.Vec(-s, c, 0.0), rs.Vec(0.0, 0.0, 1.0))
    state.boost, state.is_on_ground = float(scene["boost"]), False
    car.set_state(state)
    controls = rs.CarControls()
    for name, value in scene["controls"]:
        setattr(controls, name, value)
    car.set_controls(controls)
    pos, vel, ang_vel = [], [], []
    for _ in range(int(scene["ticks"])):
        arena.step(1)
        st = car.get_state()
        pos.append(st.pos.as_numpy().tolist())
        vel.append(st.vel.as_numpy().tolist())
        ang_vel.append(st.ang_vel.as_numpy().tolist())
    return {"pos": pos, "vel": vel, "ang_vel": ang_vel}


if __name__ == "__main__":
    _worker()
