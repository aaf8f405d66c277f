"""The results store: append-only, deduplicated by match key, durable across processes."""
import sqlite3
import subprocess
import sys

import pytest

from rocketdrl_ma.results import MatchResult, ResultsStore


def result(key, blue=2, orange=1):
    return MatchResult(match_key=key, source="test", config={"mode": "match", "team_size": 1},
                       entrants={"blue_0": "ball_chaser", "orange_0": "goalie"}, score_blue=blue,
                       score_orange=orange, duration_s=300.0, seed=7, details={"missed": {"blue_0": 0}})


def test_append_read_and_dedup(tmp_path):
    with ResultsStore(tmp_path / "r.sqlite") as store:
        assert store.append(result("a"))
        assert not store.append(result("a", blue=0))  # a finished match is never stored twice
        assert store.append(result("b", blue=1, orange=1))
        rows = store.results()
        assert [r.match_key for r in rows] == ["a", "b"]
        assert rows[0].score_blue == 2 and rows[0].winner == "blue" and rows[1].winner is None
        assert rows[0].entrants["orange_0"] == "goalie" and rows[0].details == {"missed": {"blue_0": 0}}
        assert store.keys() == {"a", "b"} and len(store) == 2
        assert [r.match_key for r in store.results(key_prefix="b")] == ["b"]
        with pytest.raises(ValueError, match="match_key"):
            store.append(result(""))


def test_rows_cannot_be_changed_or_deleted(tmp_path):
    path = tmp_path / "r.sqlite"
    ResultsStore(path).append(result("a"))
    db = sqlite3.connect(path)
    assert db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    with pytest.raises(sqlite3.DatabaseError, match="append-only"):
        db.execute("UPDATE matches SET score_blue = 9")
    with pytest.raises(sqlite3.DatabaseError, match="append-only"):
        db.execute("DELETE FROM matches")


def test_an_append_survives_kill_9(tmp_path):
    path = tmp_path / "r.sqlite"
    code = ("import os, signal; from rocketdrl_ma.results import ResultsStore, MatchResult;"
            f"s = ResultsStore({str(path)!r});"
            "s.append(MatchResult('k', 'test', {}, {}, 1, 0, 10.0));"
            "os.kill(os.getpid(), signal.SIGKILL)")
    proc = subprocess.run([sys.executable, "-c", code])
    assert proc.returncode == -9
    assert ResultsStore(path).keys() == {"k"}
