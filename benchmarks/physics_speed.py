"""Physics speed: ticks/s for 1v1..4v4 kickoff scenes with random controls changed (and state read) every 8 ticks.

Columns: our single ``Arena``; our ``ArenaBatch`` of 16 and 64 arenas (arena-ticks/s: ticks times arenas);
RocketSim driven from Python the same way; bare PyBullet ``stepSimulation`` of our bodies, one arena and 64
(no car model, no state reads: the ceiling of our design). Then the ratios. The machine is shared: compare within one run.

Run from the repo root: ``nice -n 10 .venv/bin/python benchmarks/physics_speed.py [--seconds 2] [--sizes 1 2 3 4] [--clock cpu]``
"""
from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from _reference import (ROOT, TICKS_PER_DECISION, bare_pybullet_runner, random_controls,  # noqa: E402
                        rocketsim_runner, timed)
from rocketdrl_ma.physics import Arena, ArenaBatch, CarControls  # noqa: E402

COLUMNS = ("arena", "batch16", "batch64", "rocketsim", "bare_pybullet", "bare_pybullet64")


def ours_single(team_size: int, seed: int = 0):
    arena = Arena(seed=seed)
    cars = [arena.add_car(team=team) for team in (0, 1) for _ in range(team_size)]
    arena.reset_kickoff(seed=seed)
    rng = np.random.default_rng(seed)

    def run(decisions: int) -> None:
        for _ in range(decisions):
            for car, v in zip(cars, random_controls(rng, len(cars)).tolist()):
                car.set_controls(CarControls(*v[:5], jump=v[5] > 0.5, boost=v[6] > 0.5, handbrake=v[7] > 0.5))
            arena.step(TICKS_PER_DECISION)
            for car in cars:
                car.get_state()
            arena.ball.get_state()

    return run, arena


def ours_batch(team_size: int, n_arenas: int, seed: int = 0):
    """The batch the vectorised way: one controls array for every car, one state read for every arena."""
    batch = ArenaBatch(n_arenas, seed=seed)
    for arena in batch.arenas:
        for team in (0, 1):
            for _ in range(team_size):
                arena.add_car(team=team)
        arena.reset_kickoff(seed=seed)
    rng = np.random.default_rng(seed)
    n_cars = batch.controls.shape[0]

    def run(decisions: int) -> None:
        for _ in range(decisions):
            batch.controls[:] = random_controls(rng, n_cars)
            batch.step(TICKS_PER_DECISION)
            batch.arenas[0].ball.get_state()  # refreshes the state arrays of every car and ball

    return run, batch


def measure(column: str, team_size: int, seconds: float, clock: str = "wall") -> float:
    """Ticks/s (arena-ticks/s for batches) of one column on one scene."""
    closer = None
    n_arenas = 1
    if column == "arena":
        run, closer = ours_single(team_size)
    elif column.startswith("batch"):
        n_arenas = int(column[len("batch"):])
        run, closer = ours_batch(team_size, n_arenas)
    elif column == "rocketsim":
        run = rocketsim_runner(team_size)
    elif column.startswith("bare_pybullet"):
        n_arenas = int(column[len("bare_pybullet"):] or 1)
        run, closer = bare_pybullet_runner(team_size, n_arenas)
    else:
        raise ValueError(f"column: {column!r} is not one of {COLUMNS}")
    run(2)  # warm-up (numba dispatch, first contacts)
    decisions, elapsed = timed(run, seconds, chunk=max(1, 40 // n_arenas), clock=clock)
    if closer is not None:
        closer.close()
    return decisions * TICKS_PER_DECISION * n_arenas / elapsed


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=2.0, help="timed seconds per cell (default 2)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[1, 2, 3, 4], help="team sizes (default 1 2 3 4)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="wall: elapsed time; cpu: the process's CPU time (steadier on a shared machine)")
    args = ap.parse_args(argv)
    for size in args.sizes:
        if size not in (1, 2, 3, 4):
            raise ValueError(f"--sizes: team sizes are 1..4, got {size}")
    os.chdir(ROOT)
    load = os.getloadavg()[0]
    print(f"# physics ticks per {args.clock} second, random controls every {TICKS_PER_DECISION} ticks, "
          f"{args.seconds:g} s per cell, "
          f"load average {load:.2f} on {os.cpu_count()} cores")
    print("| scene | Arena | ArenaBatch 16 | ArenaBatch 64 | RocketSim | bare PyBullet 1 | bare PyBullet 64 | "
          "Arena / RocketSim | Batch64 / RocketSim | Arena / bare 1 | Batch64 / bare 64 |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for size in args.sizes:
        r = {column: measure(column, size, args.seconds, args.clock) for column in COLUMNS}
        print(f"| {size}v{size} | {r['arena']:,.0f} | {r['batch16']:,.0f} | {r['batch64']:,.0f} | "
              f"{r['rocketsim']:,.0f} | {r['bare_pybullet']:,.0f} | {r['bare_pybullet64']:,.0f} | "
              f"{r['arena'] / r['rocketsim']:.2f} | {r['batch64'] / r['rocketsim']:.2f} | "
              f"{r['arena'] / r['bare_pybullet']:.2f} | {r['batch64'] / r['bare_pybullet64']:.2f} |", flush=True)
    print("Batches count arena-ticks (ticks x arenas). bare PyBullet: stepSimulation only, 1 or 64 arenas.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
