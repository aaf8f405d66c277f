"""Unequal teams (blue_size / orange_size apart): agents, fixed per-agent observation spaces (padding, and
observation.max_team_size), PettingZoo's API test on 1v2 and 2v3, and clear errors for bad sizes."""
import numpy as np
import pytest
from pettingzoo.test import parallel_api_test

import rocketdrl_ma
from rocketdrl_ma.config import load_config
from rocketdrl_ma.env.observations import TeamRelativeObs, make_obs_builder
from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.league.config import validate_league_config


@pytest.mark.parametrize("blue, orange", [(1, 2), (2, 3), (3, 1), (1, 4)])
def test_unequal_teams_have_their_agents_and_one_space_for_all(blue, orange):
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", blue_size=blue, orange_size=orange, clock_s=2.0,
                                    kickoff_countdown_s=0.0)
    assert env.possible_agents == [f"blue_{i}" for i in range(blue)] + [f"orange_{i}" for i in range(orange)]
    first = env.observation_space("blue_0")
    assert all(env.observation_space(a) == first for a in env.possible_agents)
    mates, opponents = max(blue, orange) - 1, max(blue, orange)  # padded to the bigger team
    assert env.observation_space("blue_0").shape == (20 * (1 + mates + opponents) + 9 + 34 + 4,)
    obs, _ = env.reset(seed=3)
    for _ in range(5):
        obs, _, _, _, infos = env.step({a: env.action_space(a).sample() for a in env.agents})
    for agent, o in obs.items():
        assert env.observation_space(agent).contains(o)
    # every car fills one block (own car first, then the ball's 9 numbers, then the slots), its "present" flag 1;
    # the smaller team's spare team-mate or opponent slot stays zero
    for agent, o in obs.items():
        present = [o[19]] + [o[29 + 20 * k + 19] for k in range(mates + opponents)]
        assert sum(present) == blue + orange and set(present) <= {0.0, 1.0}
    env.close()


@pytest.mark.parametrize("blue, orange", [(1, 2), (2, 3)])
def test_pettingzoo_api_on_unequal_teams(blue, orange):
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", blue_size=blue, orange_size=orange, clock_s=3.0,
                                    kickoff_countdown_s=0.0)
    parallel_api_test(env, num_cycles=40)
    env.close()


def test_a_match_summary_of_a_2v3_names_every_car():
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", orange_size=3, clock_s=2.0, kickoff_countdown_s=0.0)
    env.reset(seed=0)
    infos = {}
    while env.agents:
        _, _, _, _, infos = env.step({a: env.action_space(a).sample() for a in env.agents})
    summary = next(iter(infos.values()))["summary"]
    env.close()
    assert set(summary["stats"]) == {"blue_0", "blue_1", "orange_0", "orange_1", "orange_2"}
    assert set(summary["team"]["orange"]["last_back_share"]) == {"orange_0", "orange_1", "orange_2"}


def test_max_team_size_fixes_the_layout_across_team_sizes():
    shapes = {}
    for blue, orange in [(1, 1), (1, 2), (2, 1), (2, 2)]:
        env = rocketdrl_ma.parallel_env("matches/2v2.yaml", blue_size=blue, orange_size=orange,
                                        observation={"name": "team_relative", "max_team_size": 2})
        shapes[(blue, orange)] = env.observation_space("blue_0").shape
        obs, _ = env.reset(seed=1)
        assert all(o.shape == shapes[(blue, orange)] for o in obs.values())
        env.close()
    assert set(shapes.values()) == {(127,)}  # the 2v2 layout everywhere
    with pytest.raises(ValueError, match=r"max_team_size: .*up to 2 cars, but orange_size is 3"):
        rocketdrl_ma.parallel_env("matches/2v2.yaml", orange_size=3,
                                  observation={"name": "team_relative", "max_team_size": 2})
    with pytest.raises(ValueError, match=r"max_team_size: must be an int in 1..4 or null, got 5"):
        make_obs_builder("team_relative", max_team_size=5)


def test_vector_env_batched_observations_match_the_reference_on_unequal_teams():
    vec = VectorEnv("matches/2v2.yaml", n_games=2, blue_size=1, orange_size=2, kickoff_countdown_s=0.0)
    obs, _ = vec.reset(seed=4)
    for _ in range(4):
        actions = np.stack([[vec.games[0].action_space(a).sample() for a in vec.possible_agents] for _ in range(2)])
        obs, _, _, _, _ = vec.step(actions)
    reference = TeamRelativeObs()
    for k, game in enumerate(vec.games):
        state = game.game_state
        for j, agent in enumerate(vec.possible_agents):
            np.testing.assert_array_equal(obs[k, j], reference.build(agent, state))
    vec.close()


@pytest.mark.parametrize("overrides, message", [
    ({"blue_size": 5}, r"blue_size: must be an int in 1\.\.4 \(cars on that side of a match\), got 5"),
    ({"orange_size": 0}, r"orange_size: must be an int in 1\.\.4 .*got 0"),
    ({"team_size": 0}, r"team_size: must be an int in 1\.\.4 .*got 0"),
    ({"blue_size": True}, r"blue_size: must be an int in 1\.\.4 .*got True"),
    ({"orange_size": "2"}, r"orange_size: must be an int in 1\.\.4 .*got '2'"),
])
def test_bad_team_sizes_are_errors_naming_the_field_and_the_allowed_values(overrides, message):
    with pytest.raises(ValueError, match=message):
        rocketdrl_ma.parallel_env("matches/2v2.yaml", **overrides)


def test_sizes_are_config_keys_and_a_league_needs_equal_teams():
    cfg = load_config("matches/2v2.yaml", {"orange_size": 3})
    assert (cfg["team_size"], cfg["blue_size"], cfg["orange_size"]) == (2, None, 3)
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['blue_sizes'\].*'blue_size'"):
        load_config("matches/2v2.yaml", {"blue_sizes": 1})
    league = {"name": "x", "match": "matches/2v2.yaml", "entrants": [{"name": "a", "policy": "scripted:rotator"},
                                                                      {"name": "b", "policy": "scripted:idle"}]}
    with pytest.raises(ValueError, match=r"blue_size/orange_size: a league .* got 2v3"):
        validate_league_config({**league, "overrides": {"orange_size": 3}})
    assert validate_league_config({**league, "overrides": {"blue_size": 3, "orange_size": 3}}).team_size == 3
