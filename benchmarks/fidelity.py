"""Fidelity benchmark: every scripted scenario on RocketSim (the oracle) and on our PyBullet physics.

Prints a markdown table: quantity | reference | RocketSim | ours | error % (ours vs RocketSim), then the 5 trajectory
scenarios (distance between final positions as a percentage of the RocketSim path length; the test allows 10 %), then
the contact grids of tests/physics/contact_scenes.py (every scene at 8 sub-tick phases), worst case per family group:
car-ball (ball speed and direction 12 ticks after the first touch), floor bounces (rebound ratio), car-car (outcome,
speeds 6 ticks after the hit), then the signed distance from our analytic arena to the game's collision meshes
(tests/physics/arena_mesh_distance.py) per surface family and the game's fillet radii and goal dimensions next to ours
(tests/physics/arena_mesh_profile.py), if rlgym-rocket-league's meshes are installed.

Run from the repo root: ``python benchmarks/fidelity.py`` (``--rocketsim-only`` skips our engine,
``--arena-mesh-only`` prints the two arena-mesh tables alone, ``--arena-shape game`` measures the game shape,
``--arena-ball-grid-only`` prints the game shape's ball grid alone).
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

import contact_scenes as cs  # noqa: E402
from fidelity_scenarios import QUANTITIES, TRAJECTORIES, run_quantity, run_trajectory_on  # noqa: E402
from rocketsim_oracle import OursAdapter, RocketSimAdapter, init_rocketsim  # noqa: E402


def _fmt(v: float | None) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    a = abs(v)
    return f"{v:.4f}" if a < 10 else f"{v:.2f}" if a < 1000 else f"{v:.1f}"


def _group(scene: cs.Scene) -> str:
    return scene.key.split("-")[0]


def _worst_by_group(scenes: list[cs.Scene], errors: list[tuple[float, ...]]) -> dict[str, tuple[int, tuple]]:
    """Scene count and element-wise worst error tuple per group."""
    out: dict[str, tuple[int, tuple]] = {}
    for scene, err in zip(scenes, errors):
        n, worst = out.get(_group(scene), (0, tuple(0.0 for _ in err)))
        out[_group(scene)] = (n + 1, tuple(max(w, e) for w, e in zip(worst, err)))
    return out


def print_contact_grids() -> None:
    print("| contact grid (8 sub-tick phases each) | scenes | worst speed error % | worst angle (deg) | "
          "same contact ticks / pushes | issue bound |")
    print("|---|---:|---:|---:|---|---|")
    scenes = cs.car_ball_grid()
    theirs, ours = cs.run_rocketsim(scenes), cs.run_ours(scenes)
    errors, same = [], {}
    for scene, a, b in zip(scenes, theirs, ours):
        speed_err, angle = cs.speed_and_angle_error(cs.ball_velocity_after_touch(b), cs.ball_velocity_after_touch(a))
        errors.append((100.0 * abs(speed_err), angle))
        ok = b.touches == a.touches and b.extra_pushes == a.extra_pushes
        same[_group(scene)] = same.get(_group(scene), True) and ok
    for group, (n, (speed, angle)) in _worst_by_group(scenes, errors).items():
        print(f"| car-ball, {group} (500-2300 uu/s, ball centred / +-40 uu) | {n} | {speed:.2f} | {angle:.2f} | "
              f"{'yes' if same[group] else 'NO'} | 5 % / 2 deg |")

    scenes = cs.bounce_grid()
    theirs, ours = cs.run_rocketsim(scenes), cs.run_ours(scenes)
    ratios = [cs.rebound_ratio(b) for b in ours]
    rs_ratios = [cs.rebound_ratio(a) for a in theirs]
    path = max(float(np.abs(b.ball_pos - a.ball_pos).max()) for a, b in zip(theirs, ours))
    print(f"| floor bounce, 150-3000 uu/s straight and 45 deg | {len(scenes)} | rebound {min(ratios):.3f}-"
          f"{max(ratios):.3f} (RocketSim {min(rs_ratios):.3f}-{max(rs_ratios):.3f}) | path within {path:.4f} uu | "
          f"- | 0.57-0.63 |")

    scenes = cs.car_car_grid()
    theirs, ours = cs.run_rocketsim(scenes), cs.run_ours(scenes)
    errors, same = [], {}
    for scene, a, b in zip(scenes, theirs, ours):
        t = a.hits[0][0] + 6 if a.hits else len(a.car_vel) - 1
        speed_a, speed_b = np.linalg.norm(a.car_vel[t], axis=1), np.linalg.norm(b.car_vel[t], axis=1)
        floor = 0.1 * float(np.linalg.norm(scene.cars[0].vel))
        alive = np.flatnonzero(~a.car_demoed[t])
        errors.append((max((100.0 * abs(speed_b[c] - speed_a[c]) / max(speed_a[c], floor) for c in alive),
                           default=0.0),))
        same[_group(scene)] = same.get(_group(scene), True) and cs.car_hit_outcome(b) == cs.car_hit_outcome(a)
    for group, (n, (speed,)) in _worst_by_group(scenes, errors).items():
        print(f"| car-car, {group} | {n} | {speed:.2f} | - | outcome {'same' if same[group] else 'DIFFERS'} | "
              f"5 %, same outcome |")


def print_arena_mesh_tables(n_mesh_points: int, seed: int, arena_shape: str = "classic") -> None:
    from arena_mesh_distance import distance_table, format_table, sample_game_surface
    from arena_mesh_profile import format_measurements, measure_game_arena
    from rocketdrl_ma.physics.mesh_file import installed_rlgym_mesh_folder
    folder = installed_rlgym_mesh_folder()
    if folder is None:
        print("Arena vs the game's meshes: skipped, rlgym-rocket-league's collision meshes are not installed "
              "(pip install --no-deps rlgym-rocket-league==2.0.1).")
        return
    sample = sample_game_surface(folder, n_mesh_points, seed)
    print(f"Signed distance (uu) from our {arena_shape!r} arena to the game's ({n_mesh_points} points on RocketSim's "
          f"soccar meshes and {int((~sample.from_mesh).sum())} on its planes, uniform by area, seed {seed}; + where "
          f"the game's surface lies in our playable space):")
    print()
    print(format_table(distance_table(sample, arena_shape)))
    print()
    print("The game's arena measured on the meshes (circle fits to cross-sections) and ours:")
    print()
    print(format_measurements(measure_game_arena(folder)))


def print_arena_ball_grid() -> None:
    """The game shape's ball grid (tests/physics/arena_ball_scenes.py) against RocketSim on the meshes, worst case
    per surface family over its speeds, incidences and phases."""
    import arena_ball_scenes as grid
    from rocketsim_mesh_oracle import ball_trajectories_on_meshes, mesh_folder_or_none
    folder = mesh_folder_or_none()
    if folder is None:
        print("Ball grid on the game shape: skipped, rlgym-rocket-league's collision meshes are not installed.")
        return
    scenes = grid.ball_grid()
    theirs = ball_trajectories_on_meshes([s.scene for s in scenes], folder)
    pairs = grid.outgoing_pairs(scenes, [t.vel for t in theirs], grid.run_ours(scenes))
    worst: dict[str, list] = {}
    for scene in scenes:
        speed, angle = grid.speed_and_angle_error(*reversed(pairs[scene.key]))
        entry = worst.setdefault(scene.family, [0.0, 0.0, {}])
        entry[0], entry[1] = max(entry[0], 100.0 * abs(speed)), max(entry[1], angle)
        cell = grid.cell_of(scene.key)
        entry[2][cell] = entry[2].get(cell, True) and abs(speed) <= 0.05 and angle <= 2.0
    print(f"| ball off the game shape ({len(grid.SPEEDS_UU_S)} speeds x {len(grid.INCIDENCES_DEG)} incidences x "
          f"{grid.PHASES} phases a family) | worst speed error % | worst angle (deg) | cells within 5 % / 2 deg |")
    print("|---|---:|---:|---:|")
    for family, (speed, angle, cells) in worst.items():
        print(f"| {family} | {speed:.2f} | {angle:.2f} | {sum(cells.values())} of {len(cells)} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rocketsim-only", action="store_true", help="do not run our engine")
    ap.add_argument("--arena-mesh-only", action="store_true", help="print only the arena-mesh tables")
    ap.add_argument("--arena-ball-grid-only", action="store_true",
                    help="print only the game shape's ball grid against RocketSim on the meshes")
    ap.add_argument("--mesh-points", type=int, default=100_000, help="points sampled on the game's meshes")
    ap.add_argument("--mesh-seed", type=int, default=0)
    ap.add_argument("--arena-shape", choices=("classic", "game"), default="classic",
                    help="our arena shape measured against the game's meshes")
    args = ap.parse_args(argv)
    if args.mesh_points < 1:
        ap.error(f"--mesh-points must be >= 1, got {args.mesh_points}")
    if args.arena_mesh_only:
        print_arena_mesh_tables(args.mesh_points, args.mesh_seed, args.arena_shape)
        return 0
    if args.arena_ball_grid_only:
        print_arena_ball_grid()
        return 0

    init_rocketsim(tempfile.mkdtemp(prefix="rocketsim_dummy_meshes_"))
    ours_ok, ours_err = not args.rocketsim_only, None
    if ours_ok:
        try:
            import rocketdrl_ma.physics  # noqa: F401
        except Exception as e:  # the engine may not be importable yet
            ours_ok, ours_err = False, f"{type(e).__name__}: {e}"

    t0 = time.perf_counter()
    print("| quantity | reference (wiki / docs/reference/physics.md) | RocketSim | ours | error % |")
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

    if ours_ok:
        print()
        print_contact_grids()
        print()
        print_arena_mesh_tables(args.mesh_points, args.mesh_seed, args.arena_shape)
        print()
        print_arena_ball_grid()

    print()
    if ours_err:
        print(f"Our engine was not run: {ours_err}")
    elif ours_ok:
        print(f"Worst quantity error vs RocketSim: {worst:.2f} % (tests allow 5 %).")
    print(f"Wall time {time.perf_counter() - t0:.1f} s.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
