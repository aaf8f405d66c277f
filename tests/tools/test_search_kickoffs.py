"""``tools/search_kickoffs.py``, the search behind the rotator's kickoff tables: a small run from the command line
writes its candidates' tallies and a tuning file the rotator reads; its choices combine as its help says."""
from __future__ import annotations

import functools
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

from rocketdrl_ma.policies.rotator_tuning import (KickoffLane, KickoffTable, parse_kickoff_table, read_tuning,
                                                  shipped_tuning, with_kickoff_table)

REPO = Path(__file__).resolve().parents[2]
TOOL = REPO / "tools" / "search_kickoffs.py"
DIAGONAL, OFF_CENTRE, BACK = KickoffLane.DIAGONAL, KickoffLane.OFF_CENTRE, KickoffLane.BACK


@functools.cache
def _tool():
    """The tool as a module (it is a script, not part of the package)."""
    spec = importlib.util.spec_from_file_location("search_kickoffs", TOOL)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_a_small_search_writes_its_tallies_and_a_tuning_file_the_rotator_plays_by(tmp_path):
    """2v2 at phase 0 only (40 kickoffs a candidate): the shipped table, and the diagonal car beside the back spot's
    taken alone or not (the other aiming 200 uu in)."""
    out, written = tmp_path / "results.jsonl", tmp_path / "tuning.yaml"
    done = subprocess.run([sys.executable, str(TOOL), "--size", "2", "--phases", "0", "--try",
                           "diagonal/back=alone,-200", "--out", str(out), "--write", str(written)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    rows = [json.loads(line) for line in out.read_text().splitlines()]
    assert [row["start"] for row in rows] == [True, False]  # the shipped table takes that layout alone already
    assert all(row["kickoffs"] == 40 and row["by_phase"].keys() == {"0"} for row in rows)
    assert rows[1]["table"]["second_aim_uu"]["diagonal"]["back"] == -200.0
    best = max(rows, key=lambda row: row["weighted_net"])  # the first of equals: the starting table
    best_table = parse_kickoff_table("best", best["table"])
    assert read_tuning(written) == with_kickoff_table(shipped_tuning(), 2, best_table)  # the rest as shipped


def test_the_choices_combine_into_whole_tables():
    tool = _tool()
    base = KickoffTable({(DIAGONAL, OFF_CENTRE): -80.0}, frozenset({(DIAGONAL, BACK)}))
    both_off = "off_centre/off_centre+off_centre/back"
    tables = tool.candidate_tables(base, [tool.parse_try("diagonal/off_centre=-80,0"),
                                          tool.parse_try(f"{both_off}=alone,50")])
    assert tables == [
        base,  # always first; then -80 with both off-centre layouts alone, -80 with them at 50 uu, 0 (the centre)...
        KickoffTable({(DIAGONAL, OFF_CENTRE): -80.0},
                     frozenset({(DIAGONAL, BACK), (OFF_CENTRE, OFF_CENTRE), (OFF_CENTRE, BACK)})),
        KickoffTable({(DIAGONAL, OFF_CENTRE): -80.0, (OFF_CENTRE, OFF_CENTRE): 50.0, (OFF_CENTRE, BACK): 50.0},
                     frozenset({(DIAGONAL, BACK)})),
        KickoffTable({}, frozenset({(DIAGONAL, BACK), (OFF_CENTRE, OFF_CENTRE), (OFF_CENTRE, BACK)})),
        KickoffTable({(OFF_CENTRE, OFF_CENTRE): 50.0, (OFF_CENTRE, BACK): 50.0}, frozenset({(DIAGONAL, BACK)})),
    ]
    assert tool.parse_phases("0-2,6") == [0, 1, 2, 6]
