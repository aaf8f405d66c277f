"""Matches played at once (one forward per checkpoint for the cars of all of them) come out as the matches played one
at a time, bit for bit: scores, durations, stats, the digests of the final physics state and the events, ratings."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

import rocketdrl_ma
from rocketdrl_ma.league.batch_play import play_local_at_once
from rocketdrl_ma.league.config import validate_league_config
from rocketdrl_ma.league.play import play_local
from rocketdrl_ma.league.ratings import rate
from rocketdrl_ma.league.schedule import schedule
from rocketdrl_ma.policies.ppo import batched
from rocketdrl_ma.policies.ppo.batched import cars_controls, greedy_actions, seat_factory
from rocketdrl_ma.policies.ppo.checkpoint import load_model


def _team_league(tmp_path) -> dict:
    return {"name": "at_once", "match": "matches/2v2.yaml", "results": str(tmp_path / "r.sqlite"),
            "report": str(tmp_path / "report"), "format": "round_robin", "rounds": 2, "seed": 47,
            "overrides": {"clock_s": 6.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
            "entrants": [{"name": "team", "policy": "checkpoint:policies/checkpoints/selfplay_2v2_from_1v1.pt"},
                         {"name": "rotator", "policy": "scripted:rotator"},
                         {"name": "mixed", "members": [
                             {"name": "grown", "policy": "checkpoint:policies/checkpoints/selfplay_2v2_from_1v1.pt"},
                             {"name": "chaser", "policy": "scripted:ball_chaser"}]}]}


def test_matches_played_at_once_are_the_matches_played_one_by_one(tmp_path):
    """Six 2v2 matches, three at a time (places refilled as matches end): a checkpoint drives both teams' cars in
    some, one car beside a scripted bot in others."""
    cfg = validate_league_config(_team_league(tmp_path))
    planned = schedule(cfg)
    alone = {m.key: play_local(cfg, m) for m in planned}
    order = []
    together = {}
    for match, result in play_local_at_once(cfg, planned, at_once=3):
        order.append(match.key)
        together[match.key] = result
    assert sorted(order) == sorted(alone)
    for key, result in alone.items():
        assert dataclasses.replace(together[key], finished_at=result.finished_at) == result, key
    # the digests compare every car's final physics state and every ball touch: six different games
    assert len({r.details["state_sha256"] for r in alone.values()}) == 6
    assert all(r.details["events"] > 0 for r in alone.values())
    ratings = [(r.name, r.mu, r.sigma) for r in rate(cfg, planned, [alone[m.key] for m in planned]).ratings]
    assert ratings == [(r.name, r.mu, r.sigma) for r in rate(cfg, planned, [together[m.key] for m in planned]).ratings]


def test_at_once_must_be_a_positive_int(tmp_path):
    cfg = validate_league_config(_team_league(tmp_path))
    with pytest.raises(ValueError, match="at_once"):
        next(play_local_at_once(cfg, schedule(cfg), at_once=0))


def test_batched_greedy_actions_are_each_cars_own_on_real_observations():
    """Observations of a played 2v2 match through the shipped checkpoint: every batched action is the batch-1 one."""
    make = seat_factory("checkpoint:policies/checkpoints/selfplay_2v2_from_1v1.pt")
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", kickoff_countdown_s=0.0)
    env.reset(seed=3)
    seats = {agent: make() for agent in env.agents}
    rows = []
    for _ in range(40):
        state = env.rules.game_state()
        cars = [(seats[a], a, state) for a in env.agents]
        controls = cars_controls(cars)
        assert controls == [policy.controls(agent, s) for policy, agent, s in cars]
        rows += [policy.obs_builder.build(agent, s) for policy, agent, s in cars]
        env.step({a: env.action_parser.encode(c) for a, c in zip(env.agents, controls)})
    env.close()
    model = seats["blue_0"].model
    obs = np.stack(rows)
    assert greedy_actions(model, obs) == [int(model.act_deterministic(row[None])[0]) for row in obs]


class _BatchSensitive(torch.nn.Module):
    """Logits whose near tie between actions 0 and 1 a batched forward breaks the other way than a batch-1 one."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        logits = torch.zeros(x.shape[0], 3)
        logits[:, 0] = x[:, 0] + (1e-6 if x.shape[0] > 1 else 0.0)
        logits[:, 1] = x[:, 1]
        return logits


def test_a_near_tie_is_decided_by_the_cars_own_forward(monkeypatch):
    model, _ = load_model("policies/checkpoints/selfplay_2v2_from_1v1.pt")
    monkeypatch.setattr(model, "policy", _BatchSensitive())
    monkeypatch.setattr(model, "obs_norm", torch.nn.Identity())
    obs = np.zeros((3, 4), np.float32)
    obs[0, :2] = (5.0, 5.0)        # a tie: batched says 0 (the 1e-6), alone says 0 (first of equals)
    obs[1, :2] = (5.0, 5.0000005)  # a near tie: batched says 0, alone says 1
    obs[2, :2] = (1.0, 4.0)        # a clear lead of action 1
    alone = [int(model.act_deterministic(row[None])[0]) for row in obs]
    assert alone == [0, 1, 1]
    assert greedy_actions(model, obs) == alone
    monkeypatch.setattr(batched, "ARGMAX_MARGIN", 0.0)  # without the margin the batched forward decides alone
    assert greedy_actions(model, obs) != alone
