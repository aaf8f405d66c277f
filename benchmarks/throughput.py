"""Env throughput: agent-steps/s (a decision every 8 ticks) for 1v1..4v4, plus peak memory per arena.

Columns: our PettingZoo env (``matches/NvN.yaml``, no kickoff countdown; observations, rewards and infos
included); our ``VectorEnv`` at 16 and 64 arenas (the same, batched); RocketSim with the same random-control
pattern driven from Python (controls set and every state read each decision, no observations or rewards);
bare PyBullet ``stepSimulation`` of our bodies at 64 arenas (no car model, no game logic: the ceiling of our
design); the same plus the state I/O any car model on PyBullet needs each tick (every car's velocities written,
every body read: two calls per body, PyBullet has no batched call), the real ceiling; dm_control soccer when it is
installed. An agent-step is one agent's decision. Each cell runs in a fresh
process, so its peak memory (``ru_maxrss``) is its own; memory per arena is the difference between the 64- and the
16-arena VectorEnv divided by 48, which leaves out what every process pays once (interpreter, libraries, kernels).

Run from the repo root: ``nice -n 10 .venv/bin/python benchmarks/throughput.py [--seconds 3] [--sizes 1 2 3 4] [--clock cpu]``
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from _reference import ROOT, TICKS_PER_DECISION, bare_pybullet_runner, rocketsim_runner, timed  # noqa: E402

COLUMNS = ("single", "vector16", "vector64", "rocketsim", "bare64", "bare64io", "dm_control")
TITLES = {"single": "PettingZoo env", "vector16": "VectorEnv 16", "vector64": "VectorEnv 64",
          "rocketsim": "RocketSim", "bare64": "bare PyBullet 64", "bare64io": "bare PyBullet 64 + state I/O",
          "dm_control": "dm_control soccer"}


def _config(team_size: int) -> str:
    return os.path.join("matches", f"{team_size}v{team_size}.yaml")


def _single(team_size: int, seconds: float, clock: str) -> float:
    from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv

    env = RocketDRLParallelEnv(_config(team_size), kickoff_countdown_s=0.0, tick_skip=TICKS_PER_DECISION)
    env.reset(seed=0)
    space = env.action_space(env.possible_agents[0])
    rng = np.random.default_rng(0)

    def run(decisions: int) -> None:
        for _ in range(decisions):
            if not env.agents:
                env.reset()
            env.step({agent: rng.uniform(space.low, space.high).astype(np.float32) for agent in env.agents})

    run(2)
    decisions, elapsed = timed(run, seconds, clock=clock)
    env.close()
    return decisions * 2 * team_size / elapsed


def _vector(team_size: int, n_arenas: int, seconds: float, clock: str) -> float:
    from rocketdrl_ma.env.vector_env import VectorEnv

    env = VectorEnv(_config(team_size), n_games=n_arenas, kickoff_countdown_s=0.0, tick_skip=TICKS_PER_DECISION)
    env.reset(seed=0)
    space = env.action_space
    rng = np.random.default_rng(0)
    shape = (n_arenas, env.n_agents) + space.shape

    def run(decisions: int) -> None:
        for _ in range(decisions):
            env.step(rng.uniform(space.low, space.high, shape).astype(np.float32))

    run(1)
    decisions, elapsed = timed(run, seconds, chunk=1, clock=clock)
    env.close()
    return decisions * n_arenas * env.n_agents / elapsed


def _rocketsim(team_size: int, seconds: float, clock: str) -> float:
    run = rocketsim_runner(team_size)
    run(2)
    decisions, elapsed = timed(run, seconds, clock=clock)
    return decisions * 2 * team_size / elapsed


def _bare(team_size: int, n_arenas: int, seconds: float, clock: str, state_io: bool = False) -> float:
    run, batch = bare_pybullet_runner(team_size, n_arenas, state_io=state_io)
    run(1)
    decisions, elapsed = timed(run, seconds, chunk=1, clock=clock)
    batch.close()
    return decisions * n_arenas * 2 * team_size / elapsed


def _dm_control(team_size: int, seconds: float, clock: str) -> float:
    from dm_control.locomotion import soccer

    env = soccer.load(team_size=team_size, time_limit=10.0, disable_walker_contacts=False)
    specs = env.action_spec()
    rng = np.random.default_rng(0)
    env.reset()

    def run(decisions: int) -> None:
        for _ in range(decisions):
            step = env.step([rng.uniform(s.minimum, s.maximum, s.shape) for s in specs])
            if step.last():
                env.reset()

    run(2)
    decisions, elapsed = timed(run, seconds, clock=clock)
    return decisions * 2 * team_size / elapsed


def run_cell(column: str, team_size: int, seconds: float, clock: str = "wall") -> dict:
    """One cell in this process: agent-steps/s and the process's peak resident memory (MB)."""
    if column == "dm_control":
        try:
            import dm_control  # noqa: F401
        except ImportError:
            return {"error": "not installed"}
    if column == "single":
        rate = _single(team_size, seconds, clock)
    elif column.startswith("vector"):
        rate = _vector(team_size, int(column[len("vector"):]), seconds, clock)
    elif column == "rocketsim":
        rate = _rocketsim(team_size, seconds, clock)
    elif column.startswith("bare"):
        arenas = column.removeprefix("bare").removesuffix("io")
        rate = _bare(team_size, int(arenas), seconds, clock, state_io=column.endswith("io"))
    elif column == "dm_control":
        if team_size > 2:
            return {"error": "1v1 and 2v2 only"}
        rate = _dm_control(team_size, seconds, clock)
    else:
        raise ValueError(f"column: {column!r} is not one of {COLUMNS}")
    return {"rate": rate, "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=3.0, help="timed seconds per cell (default 3)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[1, 2, 3, 4], help="team sizes (default 1 2 3 4)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="wall: elapsed time; cpu: the process's CPU time (steadier on a shared machine)")
    ap.add_argument("--cell", nargs=2, metavar=("COLUMN", "TEAM_SIZE"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    os.chdir(ROOT)
    if args.cell:
        print(json.dumps(run_cell(args.cell[0], int(args.cell[1]), args.seconds, args.clock)))
        return 0
    for size in args.sizes:
        if size not in (1, 2, 3, 4):
            raise ValueError(f"--sizes: team sizes are 1..4, got {size}")
    print(f"# agent-steps per {args.clock} second, a decision every {TICKS_PER_DECISION} ticks, "
          f"{args.seconds:g} s per cell, "
          f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    print("| scene | " + " | ".join(TITLES[c] for c in COLUMNS) + " | Vector64 / single | Vector64 / RocketSim | "
          "Vector64 / bare 64 | Vector64 / bare 64 + I/O | peak MB: env / Vector16 / Vector64 | MB per arena |")
    print("|---|" + "---:|" * (len(COLUMNS) + 6))
    notes = set()
    for size in args.sizes:
        cells = {}
        for column in COLUMNS:
            out = subprocess.run([sys.executable, os.path.abspath(__file__), "--seconds", str(args.seconds), "--clock", args.clock,
                                  "--cell", column, str(size)], capture_output=True, text=True, cwd=ROOT)
            if out.returncode != 0:
                raise RuntimeError(f"cell {column} {size}v{size} failed:\n{out.stderr}")
            cells[column] = json.loads(out.stdout.strip().splitlines()[-1])
        text = []
        for column in COLUMNS:
            cell = cells[column]
            if "error" in cell:
                text.append("—")
                notes.add(f"{TITLES[column]}: {cell['error']}")
            else:
                text.append(f"{cell['rate']:,.0f}")
        v64, single = cells["vector64"]["rate"], cells["single"]["rate"]
        print(f"| {size}v{size} | " + " | ".join(text) + f" | {v64 / single:.1f} | "
              f"{v64 / cells['rocketsim']['rate']:.2f} | {v64 / cells['bare64']['rate']:.2f} | "
              f"{v64 / cells['bare64io']['rate']:.2f} | "
              f"{cells['single']['peak_mb']:.0f} / {cells['vector16']['peak_mb']:.0f} / "
              f"{cells['vector64']['peak_mb']:.0f} | "
              f"{(cells['vector64']['peak_mb'] - cells['vector16']['peak_mb']) / 48:.2f} |", flush=True)
    for note in sorted(notes):
        print(note + ("; it is not installable on this machine, so it has no figures" if "dm_control" in note else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
