"""Fidelity benchmark: every scripted scenario on RocketSim (the oracle) and on our PyBullet physics.

Prints a markdown table: quantity | reference | RocketSim | ours | error % (ours vs RocketSim), then the 5 trajectory
scenarios (distance between final positions as a percentage of the RocketSim path length; the test allows 10 %).

Run from the repo root: ``python benchmarks/fidelity.py`` (``--rocketsim-only`` skips our engine).
The scenario and adapter code lives in tests/physics/ (fidelity_scenarios.py, rocketsim_oracle.py) and is shared with
tests/physics/test_fidelity.py.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
import traceback

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
for p in (ROOT, os.path.join(ROOT, "tests", "physics")):
    if p not in sys.path:
        sys.path.insert(0, p)

import numpy as np  # noqa: E402

from fidelity_scenarios import QUANTITIES, TRAJECTORIES, run_quantity, run_trajectory_on  # noqa: E402
from rocketsim_oracle import OursAdapter, RocketSimAdapter, init_rocketsim  # noqa: E402


def _fmt(v: float | None) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    a = abs(v)
    return f"{v:.4f}" if a < 10 else f"{v:.2f}" if a < 1000 else f"{v:.1f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocketsim-only", action="store_true", help="do not run our engine")
    args = ap.parse_args(argv)

    init_rocketsim(tempfile.mkdtemp(prefix="rocketsim_dummy_meshes_"))
    ours_ok, ours_err = not args.rocketsim_only, None
    if ours_ok:
        try:
            import rocketdrl_ma.physics  # noqa: F401
        except Exception as e:  # the engine may not be importable yet
            ours_ok, ours_err = False, f"{type(e).__name__}: {e}"

    t0 = time.perf_counter()
    print("| quantity | reference (wiki / RocketSim doc) | RocketSim | ours | error % |")
    print("|---|---|---|---|---|")
    worst = 0.0
    for q in QUANTITIES:
        rs = run_quantity(q, RocketSimAdapter)
        ours, err = None, ""
        if ours_ok:
            try:
                ours = run_quantity(q, OursAdapter)
                e = 100.0 * (ours - rs) / abs(rs)
                worst = max(worst, abs(e))
                err = f"{e:+.2f}"
            except Exception as e:
                err = f"failed: {type(e).__name__}"
                traceback.print_exc(file=sys.stderr)
        label = f"{q.label} ({q.unit})" if q.unit else q.label
        print(f"| {label} | {_fmt(q.reference)} ({q.ref_source}) | {_fmt(rs)} | {_fmt(ours)} | {err} |")

    print()
    print("| trajectory (2 s) | RocketSim final (x, y, z) | RocketSim path | ours final (x, y, z) | "
          "distance / RS path % |")
    print("|---|---|---|---|---|")
    for t in TRAJECTORIES:
        rs_final, rs_len = run_trajectory_on(t, RocketSimAdapter)
        ours_s, err = "—", ""
        if ours_ok:
            try:
                of, _ = run_trajectory_on(t, OursAdapter)
                ours_s = str(np.round(of, 1).tolist())
                err = f"{100.0 * float(np.linalg.norm(of - rs_final)) / rs_len:.2f}"
            except Exception as e:
                err = f"failed: {type(e).__name__}"
                traceback.print_exc(file=sys.stderr)
        print(f"| {t.label} | {np.round(rs_final, 1).tolist()} | {rs_len:.1f} | {ours_s} | {err} |")

    print()
    if ours_err:
        print(f"Our engine was not run: {ours_err}")
    elif ours_ok:
        print(f"Worst quantity error vs RocketSim: {worst:.2f} % (tests allow 5 %).")
    print(f"Wall time {time.perf_counter() - t0:.1f} s.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
