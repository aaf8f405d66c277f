"""What the speed benchmarks compare against: RocketSim and bare PyBullet stepping the same scenes.

Shared by ``physics_speed.py`` (ticks/s) and ``throughput.py`` (agent-steps/s). Every runner steps a kickoff
scene of ``team_size`` cars a side with random controls drawn every ``ticks_per_decision`` ticks, reads the
state back after each decision, and returns how many ticks it ran in how many seconds.
"""
from __future__ import annotations

import os
import sys
import time
from typing import Callable

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for _p in (ROOT, os.path.join(ROOT, "tests", "physics")):
    if _p not in sys.path:
        sys.path.insert(0, _p)

TICKS_PER_DECISION = 8


def random_controls(rng: np.random.Generator, n_cars: int) -> np.ndarray:
    """(n_cars, 8) controls: throttle, steer, pitch, yaw, roll uniform in [-1, 1]; jump, boost, handbrake 0/1."""
    c = rng.uniform(-1.0, 1.0, (n_cars, 8))
    c[:, 5:] = c[:, 5:] > 0.0
    return c


CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}


def timed(run_decisions: Callable[[int], None], min_seconds: float, chunk: int = 10,
          clock: str = "wall") -> tuple[int, float]:
    """Call ``run_decisions(chunk)`` until ``min_seconds`` have passed on ``clock``; returns (decisions, seconds).

    ``clock="cpu"`` counts this process's CPU time: on a shared machine it reads what the code costs, not how
    much of a core the scheduler gave it."""
    if clock not in CLOCKS:
        raise ValueError(f"clock: {clock!r} is not one of {sorted(CLOCKS)}")
    now = CLOCKS[clock]
    decisions, t0 = 0, now()
    while True:
        run_decisions(chunk)
        decisions += chunk
        elapsed = now() - t0
        if elapsed >= min_seconds:
            return decisions, elapsed


def rocketsim_runner(team_size: int, seed: int = 0) -> Callable[[int], None]:
    """RocketSim's soccar arena (built-in planes only, see tests/physics/rocketsim_oracle.py), driven from Python."""
    import RocketSim as rs
    from rocketsim_oracle import init_rocketsim

    init_rocketsim()
    arena = rs.Arena(rs.GameMode.SOCCAR, tick_rate=120.0)
    cars = [arena.add_car(team, rs.CarConfig(rs.CarConfig.OCTANE))
            for team in (rs.Team.BLUE, rs.Team.ORANGE) for _ in range(team_size)]
    arena.reset_kickoff(seed)
    rng = np.random.default_rng(seed)
    controls = [rs.CarControls() for _ in cars]

    def run(decisions: int) -> None:
        for _ in range(decisions):
            values = random_controls(rng, len(cars)).tolist()
            for car, c, v in zip(cars, controls, values):
                c.throttle, c.steer, c.pitch, c.yaw, c.roll = v[:5]
                c.jump, c.boost, c.handbrake = v[5] > 0.5, v[6] > 0.5, v[7] > 0.5
                car.set_controls(c)
            arena.step(TICKS_PER_DECISION)
            for car in cars:
                car.get_state()
            arena.ball.get_state()

    return run


def bare_pybullet_runner(team_size: int, n_arenas: int = 1, seed: int = 0,
                         state_io: bool = False) -> tuple[Callable[[int], None], object]:
    """Our PyBullet world (arena meshes, planes, car boxes; the balls are not PyBullet bodies) stepped by
    ``stepSimulation`` alone.

    No car model, no state reads: the cost of Bullet's collision detection and solver for these bodies, which is
    the ceiling of a design that steps PyBullet every tick. With ``state_io`` each tick also makes the PyBullet
    calls any car model driving these bodies tick by tick must make, through PyBullet's one-body-per-call API:
    every car's velocities written before the step, every body's pose and velocities read after it (our
    ``read_rows``). Returns (runner, batch) so the caller can close it.
    """
    import pybullet as pb

    from rocketdrl_ma.physics import ArenaBatch
    from rocketdrl_ma.physics.body_io import read_rows

    batch = ArenaBatch(n_arenas, seed=seed)
    for arena in batch.arenas:
        for team in (0, 1):
            for _ in range(team_size):
                arena.add_car(team=team)
        arena.reset_kickoff(seed=seed)
    client = batch.client
    cars = batch.pybullet_car_bodies()
    bodies = cars
    still = [0.0, 0.0, 0.0]

    def run(decisions: int) -> None:
        for _ in range(decisions * TICKS_PER_DECISION):
            pb.stepSimulation(physicsClientId=client)

    def run_with_io(decisions: int) -> None:
        for _ in range(decisions * TICKS_PER_DECISION):
            for car in cars:
                pb.resetBaseVelocity(car, still, still, client)
            pb.stepSimulation(physicsClientId=client)
            read_rows(bodies, client)

    return (run_with_io if state_io else run), batch
