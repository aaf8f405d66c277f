"""The typed training config: every shipped training YAML loads into a ``TrainConfig``, round-trips through the plain
form a checkpoint stores, crosses a process boundary, and the configs stored in the shipped checkpoints load too."""
import dataclasses
import json
import pickle
from pathlib import Path

import pytest

from rocketdrl_ma.policies.ppo import TrainConfig, load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.checkpoint import read_meta
from rocketdrl_ma.policies.ppo.config import CurriculumConfig
from rocketdrl_ma.policies.ppo.selfplay.config import KickstartConfig, SelfPlayConfig

ROOT = Path(__file__).resolve().parents[2]
YAMLS = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "policies").glob("*.yaml"))
CHECKPOINTS = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "policies" / "checkpoints").glob("*.pt"))


@pytest.mark.parametrize("path", YAMLS)
def test_every_shipped_training_yaml_round_trips_through_the_checkpoint_form(path):
    cfg = load_train_config(path)
    assert isinstance(cfg, TrainConfig)
    stored = json.loads(json.dumps(cfg.to_mapping()))  # what a checkpoint's JSON holds
    assert validate_train_config(stored) == cfg
    assert pickle.loads(pickle.dumps(cfg)) == cfg  # rollout workers get it in other processes
    assert set(stored) == {"async" if f.name == "asynchronous" else f.name for f in dataclasses.fields(TrainConfig)}


@pytest.mark.parametrize("path", CHECKPOINTS)
def test_the_config_stored_in_every_shipped_checkpoint_loads(path):
    """Stored before the config was typed (empty sections as {}, keys added since missing): still a TrainConfig."""
    stored = read_meta(path)["train"]
    cfg = validate_train_config(stored)
    assert cfg.max_steps == stored["max_steps"] and cfg.env == stored["env"]
    assert (cfg.selfplay is None) == (not stored.get("selfplay"))


def test_sections_are_typed_with_defaults_and_empty_means_off():
    cfg = load_train_config("policies/selfplay_1v1.yaml")
    assert isinstance(cfg.selfplay, SelfPlayConfig) and isinstance(cfg.selfplay.kickstart, KickstartConfig)
    assert cfg.teacher_kickstart is cfg.selfplay.kickstart and cfg.kickstart is None and cfg.curriculum is None
    plain = validate_train_config({"env": "minigames/penalty.yaml", "selfplay": {}, "curriculum": {"step": 0.2},
                                   "async": True})
    assert plain.selfplay is None and plain.teacher_kickstart is None and plain.asynchronous is True
    assert plain.curriculum == CurriculumConfig(start=0.0, step=0.2, threshold=0.8)
    assert validate_train_config({**plain.to_mapping(), "curriculum": None}).curriculum is None
    with pytest.raises(dataclasses.FrozenInstanceError):
        plain.seed = 1  # noqa: the config of a run does not change under it


@pytest.mark.parametrize("raw, message", [
    ({}, r"^training config: 'env' is required"),
    ({"env": "minigames/penalty.yaml", "asynchronous": True},
     r"^training config: unknown key\(s\) \['asynchronous'\]; allowed: \[.*'async'"),
    ({"env": "minigames/penalty.yaml", "async": "yes"}, r"^async: expected true or false, got 'yes'"),
    ({"env": "minigames/penalty.yaml", "n_envs": 0}, r"^n_envs: must be >= 1, got 0"),
    ({"env": "minigames/penalty.yaml", "curriculum": [0.1]}, r"^curriculum: expected a mapping with \['start', "),
    ({"env": "matches/1v1.yaml", "selfplay": {"scripted": ["striker"]}},
     r"^selfplay.scripted: 'striker' is not one of \['aerial_shooter', 'ball_chaser', "),
    ({"env": "matches/1v1.yaml", "selfplay": {"kickstart": {"decay_steps": 0}}},
     r"^selfplay.kickstart.decay_steps: must be >= 1, got 0"),
    ({"env": "minigames/penalty.yaml", "watch_connect": "tcp/127.0.0.1:7447"}, r"^watch_connect: expected a list"),
])
def test_bad_values_name_the_key_and_what_is_allowed(raw, message):
    with pytest.raises(ValueError, match=message):
        validate_train_config(raw)
