"""The committed league leagues/replay_check.yaml replays bit for bit: every recorded match (seed, sides, score, ticks,
sha256 of the final physics state and of the event list) and the ratings of leagues/replay_check.jsonl come out
identical when played again, and a record that does not match is named field by field."""
import json
from pathlib import Path

import pytest

from rocketdrl_ma.cli import main
from rocketdrl_ma.league.config import load_league_config
from rocketdrl_ma.league.replay_check import read_records, verify_records, write_records
from rocketdrl_ma.league.runner import play_local_matches
from rocketdrl_ma.league.schedule import schedule

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "leagues" / "replay_check.yaml"
RECORDS = ROOT / "leagues" / "replay_check.jsonl"


def test_the_records_cover_the_whole_schedule_with_goals_among_them():
    cfg = load_league_config(CONFIG)
    records, ratings = read_records(RECORDS)
    assert [r["key"] for r in records] == [m.key for m in schedule(cfg)]
    assert {e.name for e in cfg.entrants} == set(ratings["ratings"])
    assert any(sum(r["score"]) for r in records) and all(r["events"] > 0 for r in records)
    assert any(e.players[0].policy.startswith("checkpoint:") for e in cfg.entrants)


def test_a_recorded_match_with_goals_replays_bit_for_bit_and_a_changed_field_is_named(tmp_path):
    cfg = load_league_config(CONFIG)
    records, _ = read_records(RECORDS)
    scored = next(r for r in records if sum(r["score"]))
    one = tmp_path / "one.jsonl"
    one.write_text(json.dumps(scored) + "\n")
    assert verify_records(cfg, one) == []

    tampered = tmp_path / "tampered.jsonl"
    tampered.write_text(json.dumps({**scored, "ticks": scored["ticks"] + 1, "state_sha256": "0" * 64}) + "\n")
    differences = verify_records(cfg, tampered)
    assert [d.split(": ")[1].split(" ")[0] for d in differences] == ["ticks", "state_sha256"], differences
    assert differences[0].startswith(f"{scored['key']}: ticks was {scored['ticks'] + 1}, replayed {scored['ticks']}")


def test_records_written_from_results_are_what_the_check_reads(tmp_path):
    cfg = load_league_config(CONFIG)
    first = schedule(cfg)[:1]
    results = [result for _, result in play_local_matches(cfg, first)]
    path = write_records(cfg, results, tmp_path / "records.jsonl")
    records, ratings = read_records(path)
    recorded = read_records(RECORDS)[0][0]
    assert records == [recorded] and set(ratings["ratings"]) == {e.name for e in cfg.entrants}
    assert verify_records(cfg, path) == []  # with its ratings line


@pytest.mark.slow
def test_the_committed_league_replays_bit_for_bit(capsys):
    """Every match of the league and its ratings, through the command line as a user runs it."""
    assert main(["league", str(CONFIG), "--verify", str(RECORDS)]) == 0
    assert "6 recorded matches replayed; every field identical, bit for bit" in capsys.readouterr().out
