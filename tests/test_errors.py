"""Bad input gets a ValueError naming the field and what is allowed, and loses nothing: the env, config or file
it was given to is as it was."""
from __future__ import annotations

import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.config import load_config, resolve_shipped_path
from rocketdrl_ma.env.vector_env import VectorEnv


@pytest.fixture
def env():
    e = rocketdrl_ma.parallel_env("matches/1v1.yaml", kickoff_countdown_s=0.0)
    e.reset(seed=0)
    yield e
    e.close()


def zeros(env) -> dict:
    return {agent: np.zeros(8, np.float32) for agent in env.agents}


@pytest.mark.parametrize("actions,message", [
    ([np.zeros(8), np.zeros(8)], "actions: expected a dict of agent -> action for the live agents "
                                 "['blue_0', 'orange_0'], got list"),
    (np.zeros((2, 8)), "actions: expected a dict of agent -> action"),
    ({"blue_0": None, "orange_0": np.zeros(8)}, "action for blue_0: expected 8 numbers in [-1, 1], got None"),
    ({"blue_0": np.zeros(8)}, "actions: no action for live agent(s) ['orange_0']"),
    ({"blue_0": np.zeros(8), "orange_0": np.zeros(8), "blue_7": np.zeros(8)}, "actions: unknown agent 'blue_7'"),
    ({"blue_0": np.zeros(7), "orange_0": np.zeros(8)}, "action for blue_0: expected shape (8,), got (7,)"),
    ({"blue_0": np.full(8, np.nan), "orange_0": np.zeros(8)}, "action for blue_0: must be finite"),
])
def test_bad_actions_name_the_agent_and_lose_nothing(env, actions, message):
    before = env.state()
    with pytest.raises(ValueError) as e:
        env.step(actions)
    assert message in str(e.value)
    np.testing.assert_array_equal(env.state(), before)  # nothing stepped
    env.step(zeros(env))  # and the env goes on


def test_a_lookup_env_names_none_and_floats(env):
    lookup = rocketdrl_ma.parallel_env("matches/1v1.yaml", action="lookup")
    lookup.reset(seed=0)
    for bad in (None, 1.5, [1, 2]):
        with pytest.raises(ValueError, match=r"action for blue_0: expected one integer index"):
            lookup.step({"blue_0": bad, "orange_0": 0})
    lookup.step({"blue_0": 3, "orange_0": 0})
    lookup.close()


@pytest.mark.parametrize("seed", [-1, 1.5, "7", True, np.float64(2.0), [1, 2]])
def test_reset_seeds_must_be_ints_from_zero(env, seed):
    refused = r"^seed: (expected an int, got|must be >= 0, got) "
    with pytest.raises(ValueError, match=refused):
        env.reset(seed=seed)
    with pytest.raises(ValueError, match=refused):
        VectorEnv("matches/1v1.yaml", n_games=1).reset(seed=seed)
    env.step(zeros(env))  # the episode under way goes on


def test_reset_accepts_numpy_ints_and_refuses_non_dict_options(env):
    obs_np, _ = env.reset(seed=np.int64(4))
    obs_int, _ = env.reset(seed=4)
    np.testing.assert_array_equal(obs_np["blue_0"], obs_int["blue_0"])
    with pytest.raises(ValueError, match=r"^options: expected a dict or None, got list"):
        env.reset(options=[1])


@pytest.mark.parametrize("overrides,message", [
    ({"team_size": 5}, "team_size: must be an int in 1..4 (cars on that side of a match), got 5"),
    ({"team_size": 0}, "team_size: must be an int in 1..4 (cars on that side of a match), got 0"),
    ({"orange_size": 7}, "orange_size: must be an int in 1..4 (cars on that side of a match), got 7"),
    ({"team_size": 2.0}, "team_size: expected int, got float 2.0"),
    ({"car_preset": "batmobile"}, "car_preset: unknown car preset 'batmobile'; allowed: ['breakout', 'dominus', "
                                  "'hybrid', 'merc', 'octane', 'plank', 'psyclops']"),
    ({"clock_s": float("inf")}, "clock_s: expected a finite number, got inf"),
    ({"clock_s": float("nan")}, "clock_s: expected a finite number, got nan"),
    ({"overtime_limit_s": float("inf")}, "overtime_limit_s: expected a finite number, got inf"),
    ({"kickoff_countdown_s": "3"}, "kickoff_countdown_s: expected float, got str '3'"),
    ({"colour": "red"}, "config (mode 'match'): unknown key(s) ['colour']; allowed: "),
])
def test_bad_config_values_are_refused_when_loaded(overrides, message):
    with pytest.raises(ValueError) as e:
        load_config("matches/1v1.yaml", overrides)  # at load time: before any env, arena or reset
    assert message in str(e.value)
    with pytest.raises(ValueError):
        rocketdrl_ma.parallel_env("matches/1v1.yaml", **overrides)


def test_minigame_configs_check_their_preset_and_clocks_when_loaded():
    with pytest.raises(ValueError, match=r"^car_preset: unknown car preset 'x'; allowed: \["):
        load_config("minigames/penalty.yaml", {"car_preset": "x"})
    with pytest.raises(ValueError, match=r"^timeout_s: expected a finite number, got inf"):
        load_config("minigames/barrier.yaml", {"timeout_s": float("inf")})


def test_the_config_argument_itself(tmp_path):
    with pytest.raises(ValueError, match=r"^config: expected a YAML path \(e\.g\. 'matches/1v1\.yaml'\), a dict or "
                                         r"None, got int 5"):
        rocketdrl_ma.parallel_env(5)
    with pytest.raises(ValueError, match=r"^config: no such file 'matches/9v9\.yaml' in the working directory or "
                                         r"among the shipped files \(`rocketdrl-ma configs` lists them\)"):
        rocketdrl_ma.parallel_env("matches/9v9.yaml")
    (tmp_path / "list.yaml").write_text("- mode: match\n")
    with pytest.raises(ValueError, match=r"must hold a mapping of keys to values"):
        load_config(tmp_path / "list.yaml")


def test_an_infinite_clock_in_a_yaml_file_is_refused(tmp_path):
    (tmp_path / "endless.yaml").write_text("mode: match\nclock_s: .inf\n")
    with pytest.raises(ValueError, match=r"^clock_s: expected a finite number, got inf"):
        rocketdrl_ma.parallel_env(str(tmp_path / "endless.yaml"))


BROKEN = "mode: match\nteam_size: 2\nrewards: {goal: 1.0, touch: [0.1\nclock_s: 60\n"


def test_a_yaml_syntax_error_names_the_file_and_line_in_every_kind_of_config(tmp_path):
    from rocketdrl_ma.league.config import load_league_config
    from rocketdrl_ma.policies.ppo.config import load_train_config
    from rocketdrl_ma.server.settings import ClientSettings, ServerSettings
    path = tmp_path / "broken.yaml"
    path.write_text(BROKEN)
    for what, load in (("config", lambda: rocketdrl_ma.parallel_env(str(path))),
                       ("training config", lambda: load_train_config(path)),
                       ("league config", lambda: load_league_config(path)),
                       ("server config", lambda: ServerSettings.load(path)),
                       ("client config", lambda: ClientSettings.load(path))):
        with pytest.raises(ValueError) as e:
            load()
        text = str(e.value)
        assert text.startswith(f"{what}: YAML syntax error in {path}, line 4, column 8: "), text
        assert "yaml" not in type(e.value).__module__


def test_a_path_that_exists_wins_over_the_shipped_config_of_that_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "matches").mkdir()
    (tmp_path / "matches" / "1v1.yaml").write_text("mode: match\nteam_size: 3\n")
    assert rocketdrl_ma.parallel_env("matches/1v1.yaml").possible_agents == [
        "blue_0", "blue_1", "blue_2", "orange_0", "orange_1", "orange_2"]
    assert resolve_shipped_path("matches/2v2.yaml").is_file()  # none here: the shipped one
    with pytest.raises(ValueError, match=r"^checkpoint: no such file '\.\./\.\./x\.pt'"):
        resolve_shipped_path("../../x.pt", "checkpoint")  # nothing outside the shipped folders
