"""Leagues played several matches at a time (processes, or a Ray cluster) store what a sequential run stores."""
from __future__ import annotations

from pathlib import Path

import pytest
from ray_cluster import LocalRayCluster

from rocketdrl_ma.league.config import validate_league_config
from rocketdrl_ma.league.ratings import rate
from rocketdrl_ma.league.runner import run_league
from rocketdrl_ma.league.schedule import schedule
from rocketdrl_ma.results import ResultsStore


def _league(tmp_path: Path, store: str) -> dict:
    return {"name": "par", "match": "matches/1v1.yaml", "results": str(tmp_path / store),
            "report": str(tmp_path / "report"), "format": "round_robin", "rounds": 2, "seed": 11,
            "overrides": {"clock_s": 15.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
            "entrants": [{"name": "chaser", "policy": "scripted:ball_chaser"},
                         {"name": "flip", "policy": "scripted:flip_chaser"},
                         {"name": "goalie", "policy": "scripted:goalie"}]}


def _stored(cfg) -> tuple[dict, list]:
    with ResultsStore(cfg.results) as store:
        results = store.results(source="league")
    rows = {r.match_key: (r.score_blue, r.score_orange, r.seed, r.duration_s, r.entrants, r.details)
            for r in results}
    ratings = [(r.name, r.mu, r.sigma, r.wins, r.draws, r.losses) for r in rate(cfg, schedule(cfg), results).ratings]
    return rows, ratings


def _sequential_and(tmp_path: Path, **parallel) -> None:
    sequential = validate_league_config(_league(tmp_path, "seq.sqlite"))
    assert run_league(sequential).played == 6
    other = validate_league_config(_league(tmp_path, "par.sqlite"))
    order = []
    run = run_league(other, on_result=lambda match, result: order.append(match.key), **parallel)
    assert run.played == 6 and sorted(order) == sorted(m.key for m in schedule(other))
    assert _stored(other) == _stored(sequential)


@pytest.mark.slow
def test_a_league_on_two_processes_stores_the_sequential_results_and_ratings(tmp_path):
    _sequential_and(tmp_path, workers=2)


@pytest.mark.slow
@pytest.mark.xdist_group("ray")  # the tests that start a Ray cluster share an xdist worker (`make test`)
def test_a_league_on_a_ray_cluster_stores_the_sequential_results_and_ratings(tmp_path):
    cluster = LocalRayCluster()
    try:
        _sequential_and(tmp_path, ray=cluster.address)
    finally:
        cluster.stop()
    assert not cluster.processes()
