"""League throughput: matches per minute of the same scheduled matches played by the league code of a git ref
(``--baseline``, checked out with git archive into a temporary folder) and by this checkout's, in one run.

Both sides play the first ``--matches`` matches of ``--league`` (default: the 2v2 self-play checkpoint against two
rotators, full 5-minute matches) with ``--workers`` processes, into fresh results stores, each after a short
warm-up match in its own tree (so that neither side's time holds numba compiling its kernels). Printed: each side's
seconds and matches per minute, its CPU seconds (all its processes) and matches per CPU minute, the ratios after /
before, whether every match's score is the same on both sides, and the load average. Wall time moves with whatever
else runs on the machine (a run at load > 1.5 on 2 cores does not count); CPU time moves much less.

Run from the repo root: ``nice -n 5 .venv/bin/python benchmarks/league_speed.py [--matches 4] [--workers 2]
[--at-once N] [--baseline REF] [--clock-s SECONDS]``
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]

# One side's run, in its own process with its tree first on the path: a warm-up match, then the timed league.
CELL = r"""
import json, resource, sys, time
import yaml
from rocketdrl_ma.league.config import load_league_config, validate_league_config
from rocketdrl_ma.league.play import play_local
from rocketdrl_ma.league.runner import run_league
from rocketdrl_ma.league.schedule import schedule
from rocketdrl_ma.results import ResultsStore

path, matches, workers, at_once = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
raw = yaml.safe_load(open(path))
warm = validate_league_config({**raw, "overrides": {**raw.get("overrides", {}), "clock_s": 2.0}})
play_local(warm, schedule(warm)[0])
cfg = load_league_config(path)
options = {} if at_once == "-" else {"at_once": int(at_once)}
def cpu_s():
    return sum(r.ru_utime + r.ru_stime for r in (resource.getrusage(resource.RUSAGE_SELF),
                                               resource.getrusage(resource.RUSAGE_CHILDREN)))
start, start_cpu = time.perf_counter(), cpu_s()
run = run_league(cfg, max_matches=matches, workers=workers, **options)
seconds, cpu = time.perf_counter() - start, cpu_s() - start_cpu
with ResultsStore(cfg.results) as store:
    scores = {r.match_key: [r.score_blue, r.score_orange] for r in store.results(source="league")}
print(json.dumps({"seconds": seconds, "cpu_s": cpu, "played": run.played, "scores": scores}))
"""


def baseline_tree(ref: str, into: Path) -> Path:
    """The package and its shipped configs and checkpoints as they were at ``ref`` (git archive)."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "rocketdrl_ma", "matches", "minigames",
                              "policies"], capture_output=True, check=True).stdout
    into.mkdir(parents=True, exist_ok=True)
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into


def default_baseline() -> str:
    """The commit before leagues played matches at once (the parent of the one that added ``batch_play.py``)."""
    added = subprocess.run(["git", "-C", str(ROOT), "log", "--diff-filter=A", "--format=%H", "--",
                            "rocketdrl_ma/league/batch_play.py"], capture_output=True, text=True).stdout.split()
    return f"{added[-1]}^" if added else "HEAD"


def side(tree: Path, league: Path, matches: int, workers: int, at_once: str) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree), "RL_WARNINGS": "0"}
    proc = subprocess.run([sys.executable, "-c", CELL, str(league), str(matches), str(workers), at_once], cwd=tree,
                          env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"league in {tree}: {proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--league", default="leagues/selfplay_2v2_from_1v1_vs_rotator.yaml")
    parser.add_argument("--matches", type=int, default=4, help="the schedule's first N matches, on both sides")
    parser.add_argument("--workers", type=int, default=2, help="league processes, on both sides")
    parser.add_argument("--at-once", type=int, default=None, help="matches each process plays at once (after)")
    parser.add_argument("--baseline", default=None, help="git ref of the league code to compare with")
    parser.add_argument("--clock-s", type=float, default=None, help="a shorter match clock, to try the benchmark")
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the start", flush=True)
    raw = yaml.safe_load((ROOT / args.league).read_text())
    if args.clock_s is not None:
        raw["overrides"] = {**(raw.get("overrides") or {}), "clock_s": args.clock_s}
    with tempfile.TemporaryDirectory() as tmp:
        runs = {}
        before_tree = baseline_tree(args.baseline or default_baseline(), Path(tmp) / "before")
        for name, tree in (("before", before_tree), ("after", ROOT)):
            league = Path(tmp) / f"{name}.yaml"
            league.write_text(yaml.safe_dump({**raw, "results": str(Path(tmp) / f"{name}.sqlite"),
                                              "report": str(Path(tmp) / f"{name}-report")}))
            at_once = "-" if name == "before" or args.at_once is None else str(args.at_once)
            runs[name] = side(tree, league, args.matches, args.workers, at_once)
            r = runs[name]
            print(f"{name}: {r['played']} matches in {r['seconds']:.1f} s, {60.0 * r['played'] / r['seconds']:.2f} "
                  f"matches/min; {r['cpu_s']:.1f} CPU s, {60.0 * r['played'] / r['cpu_s']:.2f} matches per CPU minute "
                  f"(load average {os.getloadavg()[0]:.2f})", flush=True)
    before, after = runs["before"], runs["after"]
    ratio = (after["played"] / after["seconds"]) / (before["played"] / before["seconds"])
    cpu_ratio = (after["played"] / after["cpu_s"]) / (before["played"] / before["cpu_s"])
    same = before["scores"] == after["scores"]
    print(f"after / before: {ratio:.2f} x matches/min, {cpu_ratio:.2f} x matches per CPU minute; "
          f"scores {'identical' if same else 'DIFFER'}: {after['scores']}")
    print(f"load average {os.getloadavg()[0]:.2f} at the end")


if __name__ == "__main__":
    main()
