"""League: config validation, ratings from real matches in a real SQLite file, resume after SIGKILL."""
from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from itertools import repeat
from pathlib import Path

import pytest
import yaml

from rocketdrl_ma.league.config import load_league_config, validate_league_config
from rocketdrl_ma.league.play import play_local
from rocketdrl_ma.league.ratings import rate
from rocketdrl_ma.league.report import write_report
from rocketdrl_ma.league.runner import run_league
from rocketdrl_ma.league.schedule import schedule
from rocketdrl_ma.policies.base import Policy
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.results import ResultsStore
from processes import two_processes

REPO = Path(__file__).resolve().parents[2]


def league(tmp_path: Path, name: str, clock_s: float, **extra) -> dict:
    return {"name": name, "match": "matches/1v1.yaml", "results": str(tmp_path / "results.sqlite"),
            "report": str(tmp_path / "report"),
            "overrides": {"clock_s": clock_s, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
            "entrants": [{"name": "chaser", "policy": "scripted:ball_chaser"},
                         {"name": "idle", "policy": "scripted:idle"}], **extra}


COMMITTED_LEAGUES = sorted(p.relative_to(REPO).as_posix() for p in (REPO / "leagues").glob("*.yaml"))


@pytest.mark.parametrize("path", COMMITTED_LEAGUES)
def test_every_committed_league_config_is_valid(path, monkeypatch):
    """Each committed config passes validation (its match config, entrants against the match's team size), is named
    after its file (which names its results and report), and every policy its entrants field loads: a scripted bot
    by name, a checkpoint from its committed file."""
    monkeypatch.chdir(REPO)
    config = load_league_config(path)
    assert config.name == Path(path).stem
    policies = {player.policy for entrant in config.entrants if not entrant.remote for player in entrant.players}
    assert policies
    for spec in sorted(policies):
        assert isinstance(load_policy(spec), Policy), spec


def test_config_rejects_bad_input(tmp_path):
    base = league(tmp_path, "v", 5.0)
    with pytest.raises(ValueError, match="unknown key"):
        validate_league_config({**base, "rouns": 2})
    with pytest.raises(ValueError, match="format"):
        validate_league_config({**base, "format": "swiss"})
    with pytest.raises(ValueError, match="exactly one of policy, members, remote"):
        validate_league_config({**base, "entrants": [{"name": "a"}, {"name": "b", "policy": "scripted:idle"}]})
    with pytest.raises(ValueError, match="unique"):
        validate_league_config({**base, "entrants": [{"name": "a", "policy": "scripted:idle"}] * 2})
    with pytest.raises(ValueError, match=r"members: expected a list of 2"):
        validate_league_config({**base, "match": "matches/2v2.yaml", "entrants": [
            {"name": "duo", "members": [{"name": "k", "policy": "scripted:goalie"}]},
            {"name": "b", "policy": "scripted:idle"}]})


def test_schedule_is_deterministic_with_unique_keys(tmp_path):
    cfg = validate_league_config({**league(tmp_path, "s", 5.0), "format": "round_robin", "rounds": 3, "entrants": [
        {"name": n, "policy": "scripted:idle"} for n in ("a", "b", "c")]})
    planned = schedule(cfg)
    assert planned == schedule(cfg)
    assert len(planned) == 9 and len({m.key for m in planned}) == 9
    assert len({m.seed for m in planned}) == 9
    # adding an entrant keeps the keys and seeds of the matches already scheduled
    more = validate_league_config({**league(tmp_path, "s", 5.0), "format": "round_robin", "rounds": 3, "entrants": [
        {"name": n, "policy": "scripted:idle"} for n in ("a", "b", "c", "d")]})
    assert {(m.key, m.seed) for m in planned} < {(m.key, m.seed) for m in schedule(more)}
    # sides swap from one round to the next
    assert (planned[0].blue, planned[0].orange) == (planned[3].orange, planned[3].blue)


@pytest.mark.slow
def test_ratings_order_the_stronger_bot_first_and_team_matches_rate_members(tmp_path):
    # the flip-chaser, not the ball-chaser: the ball-chaser's way back through the ball scores own goals even
    # against an idle car (on seed 4 it lost two of four 2-minute matches to one)
    cfg = validate_league_config(league(tmp_path, "strength", 120.0, format="per_pair", matches_per_pair=4, seed=4,
                                        entrants=[{"name": "chaser", "policy": "scripted:flip_chaser"},
                                                  {"name": "idle", "policy": "scripted:idle"}]))
    run = run_league(cfg)
    assert (run.scheduled, run.already_stored, run.played) == (4, 0, 4)
    with ResultsStore(cfg.results) as store:
        results = store.results(source="league")
    table = rate(cfg, schedule(cfg), results)
    assert [r.name for r in table.ratings] == ["chaser", "idle"]
    chaser, idle = table.ratings
    assert chaser.ordinal > idle.ordinal and chaser.wins >= 1 and chaser.losses == 0
    assert table.payoff["chaser"]["idle"] > 0.5 and table.payoff["idle"]["chaser"] < 0.5
    report = write_report(cfg, table, 4, "league.yaml")
    assert "| 1 | chaser |" in report.read_text() and (report.parent / "ratings.png").stat().st_size > 1000

    # a 2v2 team entrant: each member gets its own rating from the team result
    duo = validate_league_config({**league(tmp_path, "teams", 3.0), "match": "matches/2v2.yaml", "entrants": [
        {"name": "duo", "members": [{"name": "keeper", "policy": "scripted:goalie"},
                                    {"name": "striker", "policy": "scripted:ball_chaser"}]},
        {"name": "chasers", "policy": "scripted:ball_chaser"}], "format": "per_pair", "matches_per_pair": 1})
    run_league(duo)
    with ResultsStore(duo.results) as store:
        table = rate(duo, schedule(duo), store.results(key_prefix="teams/"))
    assert sorted(r.name for r in table.ratings) == ["chasers", "keeper", "striker"]
    assert all(r.matches == 1 for r in table.ratings)
    keeper, striker = (next(r for r in table.ratings if r.name == n) for n in ("keeper", "striker"))
    assert keeper.mu == striker.mu != 25.0 or table.ratings[0].draws == 1


@pytest.mark.slow
def test_killed_league_resumes_without_losing_or_duplicating(tmp_path):
    config = tmp_path / "league.yaml"
    config.write_text(yaml.safe_dump({**league(tmp_path, "resume", 20.0), "format": "per_pair",
                                      "matches_per_pair": 5}))
    cfg = validate_league_config(yaml.safe_load(config.read_text()))
    db = Path(cfg.results)
    # one match at a time: played at once, the five would end together and leave no third match to kill
    proc = subprocess.Popen([sys.executable, "-m", "rocketdrl_ma.cli", "league", str(config), "--at-once", "1"],
                            cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def stored() -> int:
        if not db.exists():
            return 0
        try:
            with sqlite3.connect(db) as con:
                return con.execute("SELECT COUNT(*) FROM matches").fetchone()[0]
        except sqlite3.OperationalError:  # the schema is not there yet
            return 0

    deadline = time.monotonic() + 120
    while stored() < 2 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)  # in the middle of the third match
    proc.wait()
    before = stored()
    assert 2 <= before < 5, "the league was not killed mid-run"

    run = run_league(cfg)
    assert (run.scheduled, run.already_stored, run.played) == (5, before, 5 - before)
    with ResultsStore(cfg.results) as store:
        keys = [r.match_key for r in store.results()]
    assert sorted(keys) == sorted(m.key for m in schedule(cfg))  # every match once, none lost
    assert run_league(cfg).played == 0  # a finished league plays nothing more


@pytest.mark.parametrize("league_yaml, trained, opponent", [
    ("leagues/selfplay_kickstart_vs_ball_chaser.yaml", "selfplay_kickstart", "ball_chaser"),
    pytest.param("leagues/selfplay_2v2_from_1v1_vs_ball_chaser.yaml", "selfplay_2v2_from_1v1", "ball_chaser",
                 marks=pytest.mark.slow)])
def test_a_delivered_policy_outscores_its_opponent_over_its_first_two_league_matches(league_yaml, trained, opponent):
    """A committed self-play checkpoint (1v1, the 2v2 team) outscores its opponent over the first two full 5-minute
    matches of its league (one per side): a change to physics, observations or the lookup table that breaks what it
    learned shows up here.
    Against the ball-chasers only: against the rotators (the trained 2v2 team wins about 70 % of its matches) a change
    to the scripted team flips single matches. A seeded match is the same on CPUs of one class, not on all (glibc's
    libm rounds differently by CPU): the 2v2 team wins 80 to 90 % of its matches, so a machine where one of these two
    is a loss is possible."""
    cfg = load_league_config(REPO / league_yaml)
    first_two = schedule(cfg)[:2]
    assert {m.blue for m in first_two} == {trained, opponent}
    with two_processes() as pool:  # the matches are independent: one per core (the 3v3 pair took 88 s in one)
        results = list(pool.map(play_local, repeat(cfg), first_two))
    goals = {trained: 0, opponent: 0}
    for match, result in zip(first_two, results):
        assert result.duration_s >= 300.0
        goals[match.blue] += result.score_blue
        goals[match.orange] += result.score_orange
    assert goals[trained] > goals[opponent], ([m.key for m in first_two], goals)


@pytest.mark.slow
def test_the_delivered_3v3_team_outscores_ball_chasers_over_its_first_ten_league_matches():
    """The 3v3 team (policies/checkpoints/selfplay_3v3_from_2v2.pt) wins most of its full matches against three
    ball-chasers, but one seeded match lands differently on a CPU whose libm rounds differently, so this test sums
    the goal difference of the league's first ten matches, which a broken observation builder turns negative (the
    figures and the odds of a false failure: docs/experiments/index.md)."""
    cfg = load_league_config(REPO / "leagues/selfplay_3v3_from_2v2_vs_ball_chaser.yaml")
    first_ten = schedule(cfg)[:10]
    assert sorted(m.blue for m in first_ten) == sorted(["selfplay_3v3_from_2v2", "ball_chaser"] * 5)
    with two_processes() as pool:
        results = list(pool.map(play_local, repeat(cfg), first_ten))
    scored = conceded = 0
    for match, result in zip(first_ten, results):
        assert result.duration_s >= 300.0
        team_is_blue = match.blue == "selfplay_3v3_from_2v2"
        scored += result.score_blue if team_is_blue else result.score_orange
        conceded += result.score_orange if team_is_blue else result.score_blue
    assert scored > conceded, (scored, conceded)
