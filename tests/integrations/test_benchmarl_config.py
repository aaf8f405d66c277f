"""The BenchMARL face without BenchMARL: the module imports, its task config builds and checks the env, and the task
classes say what to install."""
from __future__ import annotations

import subprocess
import sys

import pytest

from rocketdrl_ma.config import resolve_config_path
from rocketdrl_ma.integrations.benchmarl import SHIPPED_GAMES, RocketDRLTaskConfig

SHORT = {"max_cycles": 5, "overrides": {"kickoff_countdown_s": 0.0}}


def test_importing_the_package_and_the_module_loads_no_trainer():
    code = ("import sys, rocketdrl_ma, rocketdrl_ma.integrations.benchmarl; "
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'benchmarl', 'torchrl', 'tensordict', 'torch'}))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


@pytest.mark.parametrize("name", ["RocketDRLTask", "RocketDRLTaskClass"])
def test_the_task_classes_without_benchmarl_name_it_and_the_make_target(monkeypatch, name):
    monkeypatch.setitem(sys.modules, "benchmarl", None)  # as if not installed, whatever this venv holds
    monkeypatch.delitem(sys.modules, "rocketdrl_ma.integrations.benchmarl_task", raising=False)
    import rocketdrl_ma.integrations.benchmarl as face
    with pytest.raises(ModuleNotFoundError, match=r"needs the package 'benchmarl'.*make benchmarl-venv"):
        getattr(face, name)
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        face.Nope


def test_every_member_names_a_shipped_game():
    for member, game in SHIPPED_GAMES.items():
        assert resolve_config_path(game).exists(), member


def test_the_env_is_the_game_with_the_task_overrides():
    env = RocketDRLTaskConfig(config="matches/2v2.yaml", **SHORT).make_env()
    try:
        assert env.possible_agents == ["blue_0", "blue_1", "orange_0", "orange_1"]
        assert env.max_cycles == 5 and env.info_format == "numeric"  # BenchMARL logs the infos as tensors
        assert env.config["kickoff_countdown_s"] == 0.0
        _, infos = env.reset(seed=0)
        assert all(isinstance(v, float) for v in infos["blue_0"].values())
        assert env.state_space.contains(env.state())
        steps = 0
        while env.agents:
            env.step({a: env.action_space(a).sample() for a in env.agents})
            steps += 1
        assert steps == 5
    finally:
        env.close()


def test_an_opponent_leaves_only_the_blue_team_to_learn():
    env = RocketDRLTaskConfig(config="matches/2v2.yaml", opponent="scripted:ball_chaser", **SHORT).make_env()
    try:
        assert env.possible_agents == ["blue_0", "blue_1"]
        obs, _ = env.reset(seed=0)
        assert sorted(obs) == ["blue_0", "blue_1"]
        assert env.state().shape == env.state_space.shape  # the whole game's state, opponents included
    finally:
        env.close()


def test_the_action_space_is_the_configs():
    assert RocketDRLTaskConfig(**SHORT).action_space().shape == (8,)
    lookup = RocketDRLTaskConfig(max_cycles=5, overrides={"action": "lookup"}).action_space()
    assert lookup.n == 90


@pytest.mark.parametrize("values, message", [
    ({"max_cycle": 5}, r"task: unknown key\(s\) \['max_cycle'\]; allowed: \['config', 'max_cycles', 'opponent', "
                       r"'overrides'\]"),
    ({"max_cycles": 0}, "task max_cycles: must be >= 1"),
    ({"max_cycles": 2.5}, "task max_cycles: expected an int"),
    ({"overrides": {"max_cycles": 5}}, "'max_cycles' is set by the task"),
    ({"overrides": {"info_format": "full"}}, "'info_format' is set by the task"),
    ({"overrides": {"team_sise": 2}}, r"unknown key\(s\) \['team_sise'\]"),
    ({"overrides": {"action": "joystick"}}, "action: unknown action parser 'joystick'"),
    ({"overrides": {"observation": "sonar"}}, "sonar"),
    ({"overrides": [1]}, "task overrides: expected a mapping"),
    ({"config": 3}, "task config: expected a match or minigame YAML path"),
    ({"config": "matches/9v9.yaml"}, "9v9"),
    ({"opponent": 7}, "task opponent: expected a policy"),
])
def test_a_bad_task_config_names_the_key(values, message):
    with pytest.raises(ValueError, match=message):
        RocketDRLTaskConfig.from_dict(values)


def test_an_unknown_opponent_or_a_game_without_orange_is_refused():
    with pytest.raises(ValueError, match="unknown scripted bot 'nobody'"):
        RocketDRLTaskConfig(opponent="scripted:nobody", **SHORT).make_env()
    with pytest.raises(ValueError, match="no orange cars"):
        RocketDRLTaskConfig(config="minigames/penalty.yaml", opponent="scripted:ball_chaser", max_cycles=5).make_env()


def test_a_task_yaml_gives_its_keys(tmp_path):
    path = tmp_path / "task.yaml"
    path.write_text("config: matches/3v3.yaml\nmax_cycles: 100\noverrides:\n  clock_s: 60.0\n")
    assert RocketDRLTaskConfig.read_yaml(path) == {"config": "matches/3v3.yaml", "max_cycles": 100,
                                                   "overrides": {"clock_s": 60.0}}
    path.write_text("max_cycles: 100\nseed: 3\n")
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['seed'\]"):
        RocketDRLTaskConfig.read_yaml(path)
