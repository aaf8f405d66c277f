"""Search a team size's kickoff table for the rotator (``RotatorTuning.kickoff``): the search that produced the
shipped tables (docs/experiments/rotator-tuning.md has the runs and their figures).

Every candidate table plays every kickoff a match can have (each layout from both ends at each decision phase,
``rocketdrl_ma.policies.kickoff_trials``) against flip-chasers with the real 3 s countdown, and is scored by the goals
within ``--horizon-s`` of the countdown's end, scored minus conceded, a phase-0 kickoff (every match's first)
counting 2.25 times. The table to start from (``--tuning``, default the shipped one) is always a candidate, and a
candidate has to beat it to win. ``--try`` gives the choices for a layout (or several at once, joined by ``+``): an
offset (uu beside the ball for the second taker, towards its own side when positive; 0 aims at the centre) or
``alone`` (only the nearest car goes); the candidates are every combination of the choices. One JSON line per
candidate goes to ``--out``, and ``--write`` writes the tuning file with the winning table.

Run from the repository's root, e.g. the 3v3 table's last step (576 + 288 + 96 kickoffs a candidate):

    python tools/search_kickoffs.py --size 3 --try diagonal/off_centre=-100,-90,-80 --workers 2 \\
        --out runs/kickoffs_3v3.jsonl --write rocketdrl_ma/policies/data/rotator_tuning.yaml
"""
from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from itertools import product
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the checkout's package, also when another is installed

from rocketdrl_ma.policies import kickoff_trials  # noqa: E402
from rocketdrl_ma.policies.rotator_tuning import (  # noqa: E402
    LANE_NAMES, TEAM_SIZES, KickoffLane, KickoffTable, Layout, format_tuning, kickoff_table_data, read_tuning,
    shipped_tuning, with_kickoff_table)

ALONE = "alone"


@dataclass(frozen=True)
class Choices:
    """What ``--try`` offers a group of layouts: each choice sets every layout of the group."""
    layouts: tuple[Layout, ...]
    options: tuple[float | str, ...]  # an offset in uu, or ALONE


def parse_try(text: str) -> Choices:
    """``first/second[+first/second...]=choice,choice...`` (lanes: diagonal, off_centre, back)."""
    group, _, options = text.partition("=")
    if not options:
        raise argparse.ArgumentTypeError(f"expected LAYOUT[+LAYOUT...]=CHOICE[,CHOICE...], got {text!r}")
    layouts = []
    for layout in group.split("+"):
        lanes = layout.split("/")
        if len(lanes) != 2 or any(lane not in LANE_NAMES for lane in lanes):
            raise argparse.ArgumentTypeError(f"{layout!r} is not first/second, the lanes one of {LANE_NAMES}")
        layouts.append((KickoffLane(lanes[0]), KickoffLane(lanes[1])))
    return Choices(tuple(layouts), tuple(_option(o) for o in options.split(",")))


def _option(text: str) -> float | str:
    if text == ALONE:
        return ALONE
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a choice is an offset in uu or {ALONE!r}, got {text!r}") from None


def parse_phases(text: str) -> list[int]:
    """``0-7``, ``0,4`` or a mix: the decision phases (0..7) to play."""
    phases: set[int] = set()
    for part in text.split(","):
        low, _, high = part.partition("-")
        try:
            span = range(int(low), int(high or low) + 1)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected phases as 0-7 or 0,4, got {text!r}") from None
        phases.update(span)
    if not phases or not phases <= set(range(kickoff_trials.DECISION_TICKS)):
        raise argparse.ArgumentTypeError(f"phases are 0-{kickoff_trials.DECISION_TICKS - 1}, got {text!r}")
    return sorted(phases)


def with_choice(table: KickoffTable, layouts: tuple[Layout, ...], option: float | str) -> KickoffTable:
    """``table`` with each of ``layouts`` taken alone or its second taker aiming ``option`` uu beside the ball."""
    aims = {layout: uu for layout, uu in table.second_aim_uu.items() if layout not in layouts}
    alone = table.alone - set(layouts)
    if option == ALONE:
        alone |= set(layouts)
    elif option != 0.0:
        aims.update({layout: float(option) for layout in layouts})
    return KickoffTable(aims, frozenset(alone))


def candidate_tables(base: KickoffTable, tries: list[Choices]) -> list[KickoffTable]:
    """``base`` first, then every combination of the choices, each table once."""
    tables = [base]
    for combination in product(*(choices.options for choices in tries)):
        table = base
        for choices, option in zip(tries, combination):
            table = with_choice(table, choices.layouts, option)
        if table not in tables:
            tables.append(table)
    return tables


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, choices=TEAM_SIZES, required=True, help="cars a side")
    parser.add_argument("--try", dest="tries", type=parse_try, action="append", default=[],
                        metavar="LAYOUT[+LAYOUT...]=CHOICE[,CHOICE...]",
                        help="choices for layouts, e.g. diagonal/off_centre=-100,-90 or "
                             "off_centre/off_centre+off_centre/back+back/off_centre=alone,50")
    parser.add_argument("--phases", type=parse_phases, default=list(range(kickoff_trials.DECISION_TICKS)),
                        help="decision phases to play (default 0-7: every kickoff a match can have)")
    parser.add_argument("--horizon-s", type=float, default=12.0, help="count goals this long after the countdown")
    parser.add_argument("--tuning", type=Path, help="the tuning file to start from (default: the shipped one)")
    parser.add_argument("--workers", type=int, default=1, help="processes that play the kickoffs")
    parser.add_argument("--out", type=Path, help="append one JSON line per candidate here")
    parser.add_argument("--write", type=Path, help="write the tuning with the winning table to this file")
    args = parser.parse_args(argv)
    if args.workers < 1:
        parser.error(f"--workers: must be >= 1, got {args.workers}")

    base = shipped_tuning() if args.tuning is None else read_tuning(args.tuning)
    tables = candidate_tables(base.kickoff[args.size], args.tries)
    tunings = [with_kickoff_table(base, args.size, table) for table in tables]
    kickoffs = kickoff_trials.every_kickoff(args.size, args.phases)
    print(f"{len(tables)} candidate tables x {len(kickoffs)} kickoffs ({args.size}v{args.size}, phases {args.phases})",
          flush=True)
    if args.workers == 1:
        tallies = kickoff_trials.play_kickoffs(tunings, args.size, kickoffs, args.horizon_s)
    else:
        with ProcessPoolExecutor(args.workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            tallies = kickoff_trials.play_kickoffs(tunings, args.size, kickoffs, args.horizon_s, pool.map)

    best = 0
    for k, (table, result) in enumerate(zip(tables, tallies)):
        row = {"size": args.size, "table": kickoff_table_data(table), "scored": result.scored,
               "conceded": result.conceded, "weighted_net": result.weighted_net,
               "by_phase": {str(p): list(sc) for p, sc in result.by_phase.items()}, "kickoffs": len(kickoffs),
               "phases": args.phases, "horizon_s": args.horizon_s, "start": k == 0}
        print(json.dumps(row), flush=True)
        if args.out is not None:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            with args.out.open("a") as f:
                f.write(json.dumps(row) + "\n")
        if result.weighted_net > tallies[best].weighted_net:
            best = k
    print(f"best: candidate {best} ({'the starting table' if best == 0 else 'new'}), weighted net "
          f"{tallies[best].weighted_net:+.2f}, goals {tallies[best].scored} - {tallies[best].conceded}")
    if args.write is not None:
        args.write.parent.mkdir(parents=True, exist_ok=True)
        args.write.write_text(format_tuning(tunings[best]))
        print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
