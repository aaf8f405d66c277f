"""Training throughput against the env alone, in one run: how much of what the env can step the trainer keeps.

Every figure is **game decisions per second**: one step of one game (arena), whatever the number of cars in it,
so that learner rows and opponent rows count alike (a 2v2 self-play decision is two learner rows; a Penalty
decision is one). Columns per config, for each worker count N:

- ``env N`` (largest N only): the env alone, the same games (the config's env, overrides and ``n_envs`` copies split over N
  processes like the workers split them) with uniformly random actions, N processes at once;
- ``collect N`` (largest N only): the rollout workers and the policy, no learning; ``train N``: full training (collection and PPO
  updates), from the first batch on;
- ``before N`` with ``--baseline REF``: full training by the trainer at git ``REF`` (checked out into a temporary
  folder), so a change is measured against its predecessor in the same run.

Then the ratios the performance targets read: ``train / env`` and ``collect / env`` at the largest N, ``train
N / train 1``, ``train / before``, and the learner's share of the wall time. With ``--profile DIR`` every cell
runs under ``py-spy record --subprocesses`` and its raw profile is written to DIR (``profile_top.py`` prints
the top frames). Self-play configs run without their imitation warm start and without ``init_path`` (neither
changes the speed of a step). The load average is printed: a run at load > 1.5 is not a result.

Run from the repo root: ``.venv/bin/python benchmarks/scaling.py [--configs policies/penalty_tuned.yaml]
[--workers 1 2] [--iterations 6] [--baseline REF] [--profile DIR] [--ray] [--min-steps N]``
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from ray_cluster import LocalRayCluster  # noqa: E402  (the tests' real local cluster)

CONFIGS = ("policies/penalty_tuned.yaml", "policies/selfplay_1v1.yaml", "policies/selfplay_2v2_from_1v1.yaml")

MIN_STEPS = 100_000  # learner rows a training cell runs at least (a 2,048-row buffer would be over in seconds)

CELL = r"""
import json, sys, time
MIN_STEPS = %d
import yaml
from rocketdrl_ma.policies.ppo import validate_train_config
kind, config, workers, iterations, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
ray = sys.argv[6] if len(sys.argv) > 6 else None
with open(config) as f:
    raw = yaml.safe_load(f)
raw.pop("init_path", None)
if raw.get("selfplay"):
    raw["selfplay"] = {**raw["selfplay"], "imitate": {}}
from rocketdrl_ma.policies.ppo.trainer import Probe, worker_config
cfg = validate_train_config(raw)
wcfg = worker_config(cfg)
probe = Probe.of(wcfg)
iterations = max(iterations, -(-MIN_STEPS // raw["buffer_size"]))  # enough batches for a small buffer too
if kind in ("train", "before"):
    from rocketdrl_ma.policies.ppo import train
    from rocketdrl_ma.policies.ppo.workers import WorkerPlan
    cfg = validate_train_config({**raw, "max_steps": (iterations + 1) * raw["buffer_size"]})
    result = train(cfg, out + "/final.pt", out, progress=False, workers=WorkerPlan(workers, ray=ray))
    print(json.dumps({"rate": result.steps_per_s / probe.rows_per_copy, "learner": result.learner_share}))
else:  # collect: the rollout workers and the policy, no learning
    import torch
    from rocketdrl_ma.policies.ppo.model import PPOModel
    from rocketdrl_ma.policies.ppo.rollout_policy import RolloutPolicy
    from rocketdrl_ma.policies.ppo.trainer import sync_controls
    from rocketdrl_ma.policies.ppo.workers import Rollouts, WorkerPlan
    from rocketdrl_ma.policies.ppo.selfplay.pool import OpponentPool
    torch.set_num_threads(1)
    model = PPOModel(probe.obs_dim, probe.action, cfg.hidden_units, cfg.num_layers, cfg.normalize, cfg.init_std,
                     probe.idle, cfg.features)
    pool = None
    if cfg.selfplay:
        pool = OpponentPool(cfg, out, probe.obs_dim)
        pool.attach(model, 1)
    policy = RolloutPolicy(model, pool.slot_models if pool else None, pool.n_opponents if pool else 0)
    sync_controls(policy, None, cfg.teacher_kickstart is not None, pool)
    rollouts = Rollouts(wcfg, policy, WorkerPlan(workers), probe.rows_per_copy)
    rollouts.next_batch()
    start, steps = time.monotonic(), 0
    for _ in range(iterations):
        steps += rollouts.next_batch().numel()
        rollouts.update_weights()
    rate = steps / (time.monotonic() - start)
    rollouts.close()
    print(json.dumps({"rate": rate / probe.rows_per_copy}))
"""

ENV_CELL = r"""
import json, sys, time
import numpy as np
import yaml
from gymnasium import spaces
from rocketdrl_ma.policies.ppo import validate_train_config
from rocketdrl_ma.policies.ppo.envs import EnvPool
from rocketdrl_ma.policies.ppo.rollout import worker_copies
config, workers, worker, seconds, start_at = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
with open(config) as f:
    raw = yaml.safe_load(f)
raw.pop("init_path", None)
if raw.get("selfplay"):
    raw["selfplay"] = {**raw["selfplay"], "imitate": {}}
cfg = validate_train_config(raw)
copies = worker_copies(cfg.n_envs, workers)
pool = EnvPool(cfg.env, copies, cfg.seed + worker * copies, cfg.env_overrides)
rng = np.random.default_rng(worker)
space = pool.action_space
def actions():
    if isinstance(space, spaces.Discrete):
        return rng.integers(0, space.n, pool.n_rows)
    return rng.uniform(space.low, space.high, (pool.n_rows,) + space.shape).astype(np.float32)
pool.reset()
for _ in range(20):  # kernels compiled and caches warm before the clock starts
    pool.step(actions())
while time.time() < start_at:  # every process starts stepping at the same moment
    time.sleep(0.01)
t0, decisions = time.monotonic(), 0
while time.monotonic() - t0 < seconds:
    pool.step(actions())
    decisions += copies
print(json.dumps({"rate": decisions / (time.monotonic() - t0)}))
"""


def baseline_tree(ref: str, into: Path) -> Path:
    """The package and its configs as they were at ``ref`` (git archive)."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "rocketdrl_ma", "matches", "minigames",
                              "policies"], capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into


def _command(args: list[str], profile: Path | None) -> list[str]:
    if profile is None:
        return args
    py_spy = shutil.which("py-spy") or str(Path(sys.executable).with_name("py-spy"))
    return [py_spy, "record", "--subprocesses", "-r", "50", "-f", "raw", "-o", str(profile), "--", *args]


def cell(kind: str, config: str, workers: int, iterations: int, pythonpath: Path, ray: str | None = None,
         profile: Path | None = None, min_steps: int = MIN_STEPS) -> dict:
    with tempfile.TemporaryDirectory() as out:
        env = {**os.environ, "PYTHONPATH": str(pythonpath), "RL_WARNINGS": "0"}
        if pythonpath != ROOT:  # the baseline's kernels compile once for the whole run, not once per cell
            env["NUMBA_CACHE_DIR"] = str(pythonpath / "numba_cache")
        script = Path(out) / "cell.py"  # a file, not -c: a profile names its process by the command line
        # under a main guard: the rollout workers are spawned, and a spawned process imports the main script again
        script.write_text('if __name__ == "__main__":\n' + textwrap.indent(CELL % min_steps, "    "))
        args = [sys.executable, str(script), kind, config, str(workers), str(iterations), out, *([ray] if ray else [])]
        proc = subprocess.run(_command(args, profile), cwd=pythonpath, env=env, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"{kind} {config} {workers}: {proc.stderr[-2000:]}")
        return last_json(proc.stdout)


def last_json(stdout: str) -> dict:
    """The cell's result: its last line that is a JSON object (py-spy adds lines of its own)."""
    return json.loads([line for line in stdout.splitlines() if line.startswith("{")][-1])


def env_cell(config: str, workers: int, seconds: float) -> dict:
    """The env alone in ``workers`` processes stepping at once: their game decisions per second, summed."""
    import time

    env = {**os.environ, "PYTHONPATH": str(ROOT), "RL_WARNINGS": "0"}
    start_at = time.time() + 25.0  # after every process has built its games and compiled its kernels
    script = Path(tempfile.mkdtemp()) / "env_cell.py"
    script.write_text(ENV_CELL)
    procs = [subprocess.Popen([sys.executable, str(script), config, str(workers), str(w), str(seconds),
                               str(start_at)], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True) for w in range(workers)]
    rates = []
    for proc in procs:
        out, err = proc.communicate()
        if proc.returncode != 0:
            raise RuntimeError(f"env {config} {workers}: {err[-2000:]}")
        rates.append(last_json(out)["rate"])
    shutil.rmtree(script.parent)
    return {"rate": sum(rates)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--configs", nargs="+", default=list(CONFIGS))
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    parser.add_argument("--workers", nargs="+", type=int, default=[n for n in (1, 2, 4, 8) if n <= cores])
    parser.add_argument("--iterations", type=int, default=6, help="training iterations (buffers) per cell")
    parser.add_argument("--env-seconds", type=float, default=15.0, help="how long the env alone steps")
    parser.add_argument("--min-steps", type=int, default=MIN_STEPS, help="learner rows a training cell runs at least "
                        "(a smoke run of the benchmark itself: --min-steps 1 --iterations 1 --env-seconds 1)")
    parser.add_argument("--baseline", default=None, help="git ref of the trainer to compare with, in the same run")
    parser.add_argument("--profile", type=Path, default=None, help="record every training cell with py-spy here")
    parser.add_argument("--ray", action="store_true", help="also train on a local Ray cluster of N nodes")
    parser.add_argument("--ray-port", type=int, default=6391)
    args = parser.parse_args()
    print(f"machine: {cores} cores, load average {os.getloadavg()[0]:.2f} at the start (game decisions/s)")
    if args.profile:
        args.profile.mkdir(parents=True, exist_ok=True)
    last, first = args.workers[-1], args.workers[0]
    with tempfile.TemporaryDirectory() as tmp:
        before = baseline_tree(args.baseline, Path(tmp)) if args.baseline else None
        head = ["config"]
        for n in args.workers:  # the ratios read env and collect at the largest N only
            head += ([f"env {n}", f"collect {n}"] if n == last else []) + [f"train {n}"]
            head += [f"before {n}"] if before else []
        head += [f"train {last} / env {last}", f"collect {last} / env {last}", f"learner share {last}"]
        if last != first:
            head += [f"train {last} / train {first}"]
        if before:
            head += [f"train {last} / before {last}"]
        if args.ray:
            head += [f"ray {last}", f"ray / train {last}"]
        rows = []
        for config in args.configs:
            name = Path(config).stem
            r: dict[str, float] = {}

            def profiled(kind: str, n: int) -> Path | None:
                return args.profile / f"{name}-{kind}{n}.txt" if args.profile else None

            for n in args.workers:
                if n == last:
                    r[f"env {n}"] = env_cell(config, n, args.env_seconds)["rate"]
                    r[f"collect {n}"] = cell("collect", config, n, args.iterations, ROOT,
                                             profile=profiled("collect", n), min_steps=args.min_steps)["rate"]
                trained = cell("train", config, n, args.iterations, ROOT, profile=profiled("train", n),
                               min_steps=args.min_steps)
                r[f"train {n}"], r[f"learner {n}"] = trained["rate"], trained["learner"]
                if before:
                    r[f"before {n}"] = cell("before", config, n, args.iterations, before,
                                            min_steps=args.min_steps)["rate"]
            if args.ray:
                cluster = LocalRayCluster(args.ray_port, nodes=last)
                try:
                    r["ray"] = cell("train", config, last, args.iterations, ROOT, cluster.address,
                                    min_steps=args.min_steps)["rate"]
                finally:
                    cluster.stop()
            row = [config]
            for n in args.workers:
                row += [f"{r[f'env {n}']:,.0f}", f"{r[f'collect {n}']:,.0f}"] if n == last else []
                row += [f"{r[f'train {n}']:,.0f}"] + ([f"{r[f'before {n}']:,.0f}"] if before else [])
            row += [f"{r[f'train {last}'] / r[f'env {last}']:.2f}", f"{r[f'collect {last}'] / r[f'env {last}']:.2f}",
                    f"{r[f'learner {last}']:.0%}"]
            if last != first:
                row += [f"{r[f'train {last}'] / r[f'train {first}']:.2f}"]
            if before:
                row += [f"{r[f'train {last}'] / r[f'before {last}']:.2f}"]
            if args.ray:
                row += [f"{r['ray']:,.0f}", f"{r['ray'] / r[f'train {last}']:.2f}"]
            rows.append(row)
            print(" | ".join(row), f"(load {os.getloadavg()[0]:.2f})", flush=True)
    print(f"\nload average {os.getloadavg()[0]:.2f} at the end\n")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
