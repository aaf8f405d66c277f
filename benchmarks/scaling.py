"""Training throughput on every core: agent steps/s of collection alone and of full training (collection + PPO
updates) with 1, 2, 4, 8 rollout workers (as many as the machine has cores), beside the single-process trainer
this project had before its rollout workers, in the same run.

Columns per config: ``before`` (that trainer, checked out from git at ``--baseline`` into a temporary folder),
``in-process`` (today's trainer, ``n_workers: 0``), then for N workers ``collect N`` (the rollout workers and the
policy alone, no learning) and ``train N`` (full training), and the efficiency throughput(N) / (N x
throughput(1)); with ``--ray``, ``ray N`` is full training with N workers on a real local Ray cluster of N nodes
(``ray start`` on 127.0.0.1, one CPU each, as in ``tests/ray_cluster.py``) and ``ray / train N`` its ratio to
local processes. Every cell runs in its own process; speeds count from the first batch on (process and worker
start-up left out). Self-play configs run without their imitation warm start (minutes of cloning before the
first step). The figures move with whatever else runs on the machine: the load average is printed.

Run from the repo root: ``nice -n 5 .venv/bin/python benchmarks/scaling.py [--configs policies/penalty_tuned.yaml]
[--workers 1 2] [--iterations 8] [--baseline REF] [--ray]``
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from ray_cluster import LocalRayCluster  # noqa: E402  (the tests' real local cluster)
CONFIGS = ("policies/selfplay_1v1.yaml", "policies/penalty_tuned.yaml")

CELL = r"""
import json, sys, time
import yaml
from rocketdrl_ma.policies.ppo import validate_train_config
kind, config, workers, iterations, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
ray = sys.argv[6] if len(sys.argv) > 6 else None
with open(config) as f:  # the YAML's mapping (with buffer_size), which the trainer of either checkout validates
    raw = yaml.safe_load(f)
if raw.get("selfplay"):
    raw["selfplay"] = {**raw["selfplay"], "imitate": {}}
if kind == "before":
    raw = {k: v for k, v in raw.items() if k not in ("n_workers", "async")}
    import rocketdrl_ma.policies.ppo.trainer as trainer
    rates = []
    class Bar:  # the old trainer reports its speed only on its progress bar
        def __init__(self, *a, **k): pass
        def update(self, n): pass
        def close(self): pass
        def set_postfix_str(self, text): rates.append(float(text.split(" steps/s")[0].replace(",", "")))
    trainer.tqdm = Bar
    # a first short run compiles the physics kernels of this checkout (numba caches per source file)
    trainer.train(validate_train_config({**raw, "max_steps": raw["buffer_size"]}), out + "/warm.pt", out + "/warm")
    cfg = validate_train_config({**raw, "max_steps": iterations * raw["buffer_size"]})
    trainer.train(cfg, out + "/final.pt", out)
    print(json.dumps({"rate": rates[-1]}))
elif kind == "train":
    from rocketdrl_ma.policies.ppo import train
    from rocketdrl_ma.policies.ppo.workers import WorkerPlan
    cfg = validate_train_config({**raw, "max_steps": (iterations + 1) * raw["buffer_size"]})
    result = train(cfg, out + "/final.pt", out, progress=False, workers=WorkerPlan(workers, ray=ray))
    print(json.dumps({"rate": result.steps_per_s, "learner": result.learner_share}))
else:  # collect: the rollout workers and the policy, no learning
    import torch
    from rocketdrl_ma.policies.ppo.model import PPOModel
    from rocketdrl_ma.policies.ppo.rollout_policy import RolloutPolicy
    from rocketdrl_ma.policies.ppo.trainer import Probe, sync_controls, worker_config
    from rocketdrl_ma.policies.ppo.workers import Rollouts, WorkerPlan
    from rocketdrl_ma.policies.ppo.selfplay.pool import OpponentPool
    torch.set_num_threads(1)
    cfg = validate_train_config(raw)
    wcfg = worker_config(cfg)
    probe = Probe.of(wcfg)
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
    print(json.dumps({"rate": rate}))
"""


def baseline_tree(ref: str, into: Path) -> Path | None:
    """The package as it was at ``ref`` (git archive), or None outside a git clone."""
    if not (ROOT / ".git").exists():
        return None
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "rocketdrl_ma", "matches", "minigames",
                              "policies"], capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into


def default_baseline() -> str:
    """The commit before the rollout workers arrived (the parent of the one that added ``rollout.py``)."""
    added = subprocess.run(["git", "-C", str(ROOT), "log", "--diff-filter=A", "--format=%H", "--",
                            "rocketdrl_ma/policies/ppo/rollout.py"], capture_output=True, text=True).stdout.split()
    return f"{added[-1]}^" if added else "HEAD"


def cell(kind: str, config: str, workers: int, iterations: int, pythonpath: Path, ray: str | None = None) -> dict:
    with tempfile.TemporaryDirectory() as out:
        env = {**os.environ, "PYTHONPATH": str(pythonpath), "RL_WARNINGS": "0"}
        proc = subprocess.run([sys.executable, "-c", CELL, kind, config, str(workers), str(iterations), out,
                               *([ray] if ray else [])], cwd=pythonpath, env=env, capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"{kind} {config} {workers}: {proc.stderr[-2000:]}")
        return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--configs", nargs="+", default=list(CONFIGS))
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    parser.add_argument("--workers", nargs="+", type=int, default=[n for n in (1, 2, 4, 8) if n <= cores])
    parser.add_argument("--iterations", type=int, default=8, help="training iterations (buffers) per cell")
    parser.add_argument("--baseline", default=None, help="git ref of the single-process trainer to compare with")
    parser.add_argument("--ray", action="store_true", help="also train on a local Ray cluster of N nodes")
    parser.add_argument("--ray-port", type=int, default=6391)
    args = parser.parse_args()
    print(f"machine: {cores} cores, load average {os.getloadavg()[0]:.2f} at the start")
    with tempfile.TemporaryDirectory() as tmp:
        before = baseline_tree(args.baseline or default_baseline(), Path(tmp))
        head = ["config", "before", "in-process"]
        for n in args.workers:
            head += [f"collect {n}", f"train {n}"]
        last = args.workers[-1]
        head += [f"train {last} / before", f"train {last} / collect {last}",
                 "learner share"] + [f"efficiency train {n}" for n in args.workers[1:]]
        if args.ray:
            head += [f"ray {last}", f"ray / train {last}"]
        rows = []
        for config in args.configs:
            iters = args.iterations
            r = {"before": cell("before", config, 0, iters, before)["rate"] if before else float("nan"),
                 "in-process": cell("train", config, 0, iters, ROOT)["rate"]}
            for n in args.workers:
                r[f"collect {n}"] = cell("collect", config, n, iters, ROOT)["rate"]
                trained = cell("train", config, n, iters, ROOT)
                r[f"train {n}"], r[f"learner {n}"] = trained["rate"], trained["learner"]
            if args.ray:
                cluster = LocalRayCluster(args.ray_port, nodes=last)
                try:
                    r["ray"] = cell("train", config, last, iters, ROOT, cluster.address)["rate"]
                finally:
                    cluster.stop()
            one = r[f"train {args.workers[0]}"] / args.workers[0]
            row = [config, *(f"{r[k]:,.0f}" for k in head[1:3 + 2 * len(args.workers)]),
                   f"{r[f'train {last}'] / r['before']:.2f}", f"{r[f'train {last}'] / r[f'collect {last}']:.2f}",
                   f"{r[f'learner {last}']:.0%}"] + [f"{r[f'train {n}'] / (n * one):.2f}" for n in args.workers[1:]]
            if args.ray:
                row += [f"{r['ray']:,.0f}", f"{r['ray'] / r[f'train {last}']:.2f}"]
            rows.append(row)
            print(" | ".join(row), flush=True)
    print(f"\nload average {os.getloadavg()[0]:.2f} at the end\n")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
