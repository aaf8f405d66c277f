"""The sensors and actions of the predecessor project are named for what they are (``general_sensors``,
``barrier_sensors``, ``aerial_sensors``, ``drive``); the old names still load the same thing, with a warning that
names the new one."""
from __future__ import annotations

import json
import logging
import shutil

import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.env import actions, observations, renamed
from rocketdrl_ma.env.actions import DriveActions, make_action_parser
from rocketdrl_ma.env.observations import AerialSensors, BarrierSensors, GeneralSensors, make_obs_builder
from rocketdrl_ma.policies.ppo.checkpoint import CheckpointPolicy, resolve_checkpoint, sidecar


@pytest.fixture(autouse=True)
def _log_every_old_name(monkeypatch):
    monkeypatch.setattr(renamed, "_logged", set())


@pytest.mark.parametrize("old,new,cls", [("seed_sensors", "general_sensors", GeneralSensors),
                                         ("seed_barrier", "barrier_sensors", BarrierSensors),
                                         ("seed_aerial", "aerial_sensors", AerialSensors)])
def test_an_old_observation_name_builds_the_same_sensors_and_logs_the_new_name(caplog, old, new, cls):
    with caplog.at_level(logging.WARNING, logger=renamed.__name__):
        builder = make_obs_builder(old, goal_sensor=False)
    assert type(builder) is cls and builder.size == make_obs_builder(new, goal_sensor=False).size
    assert f"observation: {old!r} is now called {new!r}" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger=renamed.__name__):
        make_obs_builder(new)
        make_obs_builder(old)  # once per process
    assert caplog.text == ""


def test_an_old_action_name_parses_the_same_and_logs_the_new_name(caplog):
    with caplog.at_level(logging.WARNING, logger=renamed.__name__):
        parser = make_action_parser("seed")
    assert type(parser) is DriveActions
    assert "action: 'seed' is now called 'drive'" in caplog.text
    action = [0.5, -0.25, 1.0, -1.0, 1.0]
    assert parser.parse("blue_0", action) == make_action_parser("drive").parse("blue_0", action)


@pytest.mark.parametrize("module,old,new", [(observations, "SeedSensors", "GeneralSensors"),
                                            (observations, "SeedBarrierSensors", "BarrierSensors"),
                                            (observations, "SeedAerialSensors", "AerialSensors"),
                                            (actions, "SeedActions", "DriveActions")])
def test_an_old_class_name_imports_the_new_class_with_a_deprecation_warning(module, old, new):
    with pytest.warns(DeprecationWarning, match=f"{old} is now {new}"):
        assert getattr(module, old) is getattr(module, new)
    with pytest.raises(AttributeError):
        getattr(module, "NoSuchBuilder")


def test_an_env_and_a_checkpoint_with_the_old_names_play_as_with_the_new(tmp_path):
    old = rocketdrl_ma.parallel_env("minigames/penalty.yaml", observation="seed_sensors", action="seed")
    new = rocketdrl_ma.parallel_env("minigames/penalty.yaml")
    try:
        obs_old, _ = old.reset(seed=3)
        obs_new, _ = new.reset(seed=3)
        assert obs_old.keys() == obs_new.keys()
        for agent in obs_new:
            np.testing.assert_array_equal(obs_old[agent], obs_new[agent])
    finally:
        old.close()
        new.close()
    shipped = resolve_checkpoint("policies/checkpoints/penalty_tuned.pt")
    copy = tmp_path / "penalty_old_names.pt"
    shutil.copyfile(shipped, copy)
    meta = json.loads(sidecar(shipped, ".json").read_text())
    assert meta["env"]["resolved"]["observation"] == {"name": "general_sensors"}
    meta["env"]["resolved"]["observation"] = {"name": "seed_sensors"}
    meta["env"]["resolved"]["action"] = {"name": "seed"}
    sidecar(copy, ".json").write_text(json.dumps(meta))
    old_policy, new_policy = CheckpointPolicy(copy), CheckpointPolicy(shipped)
    assert type(old_policy.obs_builder) is type(new_policy.obs_builder) is GeneralSensors
    assert type(old_policy.action_parser) is type(new_policy.action_parser) is DriveActions


def test_the_old_arena_and_lane_names_of_a_vector_env_still_work_with_a_deprecation_warning():
    from rocketdrl_ma.env.vector_env import VectorEnv
    with pytest.warns(DeprecationWarning, match=r"VectorEnv\(n_arenas=...\) is now VectorEnv\(n_games=...\)"):
        vec = VectorEnv("matches/1v1.yaml", n_arenas=2, autoreset=False, kickoff_countdown_s=0.0, max_cycles=1)
    assert vec.n_games == 2
    for old, new in (("n_arenas", "n_games"), ("lanes", "games"), ("reset_arenas", "reset_games")):
        with pytest.warns(DeprecationWarning, match=f"VectorEnv.{old} is now VectorEnv.{new}"):
            assert getattr(vec, old) == getattr(vec, new)
    vec.reset(seed=0)
    vec.step(np.zeros((2, 2, 8), np.float32))
    with pytest.warns(DeprecationWarning):
        obs, infos = vec.reset_arenas(np.array([True, False]))
    assert infos[1] is None and obs.shape[0] == 2
    vec.close()
