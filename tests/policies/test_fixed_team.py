"""FixedTeamEnv: one team's PettingZoo view of a game whose other team fixed policies play."""
from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test

import rocketdrl_ma
from rocketdrl_ma.policies.fixed_team import FixedTeamEnv
from rocketdrl_ma.policies.registry import load_policy

FAST = {"kickoff_countdown_s": 0.0, "max_cycles": 30}


def fixed(config="matches/2v2.yaml", team="orange", policy="scripted:ball_chaser", **overrides):
    return FixedTeamEnv(rocketdrl_ma.parallel_env(config, **{**FAST, **overrides}), team=team, policy=policy)


def test_passes_pettingzoo_parallel_api_test():
    env = fixed()
    try:
        parallel_api_test(env, num_cycles=30)
    finally:
        env.close()


@pytest.mark.parametrize("team, learners", [("orange", ["blue_0", "blue_1"]), ("blue", ["orange_0", "orange_1"])])
def test_the_fixed_team_plays_as_its_policy_does_in_the_full_game(team, learners):
    """The same seed and learner actions through FixedTeamEnv and through the full env, whose fixed-team actions
    come from separate instances of the same bot, give the same game."""
    env, full = fixed(team=team), rocketdrl_ma.parallel_env("matches/2v2.yaml", **FAST)
    try:
        assert env.possible_agents == learners
        obs, _ = env.reset(seed=3)
        full_obs, _ = full.reset(seed=3)
        bots = {a: load_policy("scripted:ball_chaser") for a in full.possible_agents if a not in learners}
        for bot in bots.values():
            bot.reset(full.game_state)
        rng = np.random.default_rng(0)
        while env.agents:
            actions = {a: rng.uniform(-1, 1, 8).astype(np.float32) for a in env.agents}
            state = full.game_state
            full_actions = {**actions, **{a: full.action_parser.encode(bots[a].controls(a, state)) for a in bots}}
            obs, rewards, terms, truncs, infos = env.step(actions)
            full_obs, full_rewards, *_ = full.step(full_actions)
            assert sorted(obs) == learners
            for agent in learners:
                np.testing.assert_array_equal(obs[agent], full_obs[agent])
                assert rewards[agent] == full_rewards[agent]
            np.testing.assert_array_equal(env.state(), full.state())  # the fixed team's cars too
        assert full.agents == [] and all(truncs.values())
    finally:
        env.close()
        full.close()


def test_actions_for_the_fixed_team_are_refused():
    env = fixed()
    try:
        env.reset(seed=0)
        with pytest.raises(ValueError, match=r"\['orange_0'\] are played by the fixed policies"):
            env.step({"blue_0": np.zeros(8), "blue_1": np.zeros(8), "orange_0": np.zeros(8)})
    finally:
        env.close()


@pytest.mark.parametrize("config, team, message", [
    ("matches/2v2.yaml", "green", "team: 'green' is not one of"),
    ("minigames/penalty.yaml", "orange", "no orange cars"),
    ("minigames/penalty.yaml", "blue", "every car of this game is blue"),
])
def test_a_team_that_cannot_be_fixed_is_refused(config, team, message):
    env = rocketdrl_ma.parallel_env(config)
    try:
        with pytest.raises(ValueError, match=message):
            FixedTeamEnv(env, team=team, policy="scripted:idle")
    finally:
        env.close()
