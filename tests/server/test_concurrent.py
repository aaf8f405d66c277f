"""Several matches at once in one server: four 4v4 matches, each team's four bots in its own process."""
from __future__ import annotations

import pytest
from server_helpers import SHORT

from rocketdrl_ma.results import ResultsStore

TEAMS = {"blue": [f"blue_{i}" for i in range(4)], "orange": [f"orange_{i}" for i in range(4)]}


@pytest.mark.slow
def test_four_concurrent_4v4_matches_finish_and_record_results(running, procs):
    matches = [f"m{i}" for i in range(4)]
    for match in matches:
        running.lobby.create("matches/4v4.yaml", match, overrides=SHORT, ready_timeout_s=300)
    bots = [procs.botproc(running, match, slots) for match in matches for slots in TEAMS.values()]
    infos = {match: running.wait_status(match, timeout_s=300) for match in matches}
    for p in bots:
        assert p.wait(60) == 0, p.output()
        assert sum(line.startswith("done") and line.endswith("finished") for line in p.lines) == 4, p.output()
    results = {r.details["match_id"]: r for r in ResultsStore(running.results).results()}
    assert set(results) == set(matches)
    for match, info in infos.items():
        result = results[match]
        assert result.match_key == info["result_key"] and len(result.entrants) == 8
        assert set(result.entrants.values()) == {"scripted:ball_chaser+0ms"}  # every slot played remotely
        assert {s["occupant"] for s in info["slot_status"].values()} == {"remote"}
        # on a busy 2-core machine many 50 ms deadlines slip (32 bots), but every bot played
        assert all(s["received"] > 0 for s in info["slot_status"].values()), info
        assert result.duration_s >= SHORT["clock_s"]
