"""Training configs: the ML-Agents PPO keys with their ML-Agents meanings, plus the env to train on.

A config is a flat YAML mapping. Hyperparameters (as in ML-Agents' ``trainer_config``):

- ``batch_size``: experiences per gradient step (minibatch); ``buffer_size``: experiences collected
  per policy update (over every agent of every env copy); ``num_epoch``: passes over the buffer.
- ``learning_rate`` and ``learning_rate_schedule`` (``linear``: decays to 0 at ``max_steps``; ``constant``).
- ``beta``: entropy bonus coefficient; ``epsilon``: PPO clip range; ``lambd``: GAE lambda;
  ``gamma``: discount; ``strength``: scale of the env reward.
- ``normalize``: running mean/variance normalisation of observations; ``hidden_units``, ``num_layers``:
  the MLPs of the actor and the critic.
- ``time_horizon``: experiences of one agent before its trajectory is cut and bootstrapped with the
  critic's value; ``max_steps``: agent steps to train for; ``summary_freq``: agent steps between
  TensorBoard summaries; ``checkpoint_interval`` and ``keep_checkpoints``: periodic checkpoints.

And the rest: ``env`` (a match or minigame YAML), ``env_overrides`` (its keys to replace), ``n_envs``
(env copies feeding the trainer), ``seed``, ``device`` (``auto``: GPU if present, else CPU), and
``shaping`` (weights of the trainer's potential-based shaping terms, ``shaping.py``; empty: none), and
``init_std``: the Gaussian policy's initial standard deviation (1, as ML-Agents). Box policies start with
their mean at the idle car's controls (no jump, boost or drift), so early exploration drives rather than
hops. ``curriculum`` (as ML-Agents' lessons, over a minigame's ``difficulty``): start at ``start``, and
each time the last 100 training episodes succeed at least ``threshold`` of the time, raise the
difficulty by ``step`` up to 1; empty: train at the env config's difficulty throughout.
``selfplay``: train one team against an opponent pool (``policies/ppo/selfplay/config.py``); empty: none.
``imitate`` and ``kickstart``: a scripted teacher for a game without self-play (a minigame's shooter), with the
meaning and keys of ``selfplay.imitate`` (clone the bot, then DAgger, before the first update) and
``selfplay.kickstart`` (a fading distillation term towards the bot on the learner's own states); with
``selfplay`` they go under it.
``features``: fixed inputs the model computes from the observation (``features.py``): ``none``, or
``car_local`` (ball and other cars in the car's own frame; needs the ``team_relative`` observation).
``n_workers``: rollout worker processes, each stepping ``ceil(n_envs / n_workers)`` env copies with its own copy
of the policy (``workers.py``); ``null`` (the default): one per core of the machine, 0: the env copies run in the
trainer's own process; ``--workers`` overrides it. ``async``: the learner updates on each worker's batch as it
arrives while the others go on collecting (the policy lag, in updates, goes to TensorBoard); false: every
iteration waits for all workers, and a seed and worker count give the same run.
``watch_every``: every that many iterations, play one greedy evaluation episode of the current policy and
publish it for ``rocketdrl-ma web`` (``rocketdrl_ma/web/training.py``) to the match server ``watch_server``
reached at ``watch_connect``; 0: never.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from rocketdrl_ma.config import load_config, load_yaml_file, optional_section, resolve_shipped_path
from rocketdrl_ma.validation import check_bool, check_choice, check_int, check_number, reject_unknown

from rocketdrl_ma.policies.ppo.selfplay.config import check_selfplay
from rocketdrl_ma.policies.ppo.selfplay.imitation import check_imitate
from rocketdrl_ma.policies.ppo.selfplay.kickstart import check_kickstart

from .features import FEATURES
from .shaping import check_shaping

#: every key a training config may hold, with its default (ML-Agents' PPO defaults where it has one)
TRAIN_DEFAULTS: dict[str, Any] = {
    "env": None,
    "env_overrides": {},
    "n_envs": 8,
    "seed": 0,
    "device": "auto",
    "batch_size": 1024,
    "buffer_size": 10240,
    "learning_rate": 3.0e-4,
    "learning_rate_schedule": "linear",
    "beta": 5.0e-3,
    "epsilon": 0.2,
    "lambd": 0.95,
    "num_epoch": 3,
    "normalize": False,
    "hidden_units": 128,
    "num_layers": 2,
    "gamma": 0.99,
    "strength": 1.0,
    "time_horizon": 64,
    "max_steps": 500_000,
    "summary_freq": 50_000,
    "checkpoint_interval": 500_000,
    "keep_checkpoints": 5,
    "shaping": {},
    "init_std": 1.0,
    "features": "none",
    "curriculum": {},
    "selfplay": {},
    "imitate": {},
    "kickstart": {},
    "n_workers": None,
    "async": False,
    "watch_every": 0,
    "watch_server": "local",
    "watch_connect": ["tcp/127.0.0.1:7447"],
}
CURRICULUM_KEYS = {"start": 0.0, "step": 0.1, "threshold": 0.8}
SCHEDULES = ("linear", "constant")
DEVICES = ("auto", "cpu", "cuda")
POSITIVE_INTS = ("n_envs", "batch_size", "buffer_size", "num_epoch", "hidden_units", "num_layers", "time_horizon",
                 "max_steps", "summary_freq", "checkpoint_interval", "keep_checkpoints")
UNIT_INTERVAL = ("lambd", "gamma")


def validate_train_config(raw: dict[str, Any]) -> dict[str, Any]:
    """Defaults filled in and every value checked; ValueError names the bad key and the allowed ones."""
    if not isinstance(raw, dict):
        raise ValueError(f"training config: expected a mapping of keys to values, got {type(raw).__name__}")
    reject_unknown("training config", raw, TRAIN_DEFAULTS)
    cfg = {**TRAIN_DEFAULTS, **raw}
    if not isinstance(cfg["env"], str):
        raise ValueError(f"env: expected the path of a match or minigame YAML, got {cfg['env']!r}")
    if not isinstance(cfg["env_overrides"], dict):
        raise ValueError(f"env_overrides: expected a mapping of env keys to values, got {cfg['env_overrides']!r}")
    for key in POSITIVE_INTS:
        check_int(key, cfg[key], minimum=1)
    check_int("seed", cfg["seed"])
    for key in UNIT_INTERVAL:
        cfg[key] = check_number(key, cfg[key], 0.0, 1.0)
    for key in ("learning_rate", "epsilon", "init_std"):
        cfg[key] = check_number(key, cfg[key], above=0.0)
    cfg["beta"] = check_number("beta", cfg["beta"], minimum=0.0)
    cfg["strength"] = check_number("strength", cfg["strength"])
    check_choice("learning_rate_schedule", cfg["learning_rate_schedule"], SCHEDULES)
    check_choice("device", cfg["device"], DEVICES)
    check_choice("features", cfg["features"], FEATURES)
    check_bool("normalize", cfg["normalize"])
    if cfg["n_workers"] is not None:  # 0: no worker processes; null: one per core
        check_int("n_workers", cfg["n_workers"], minimum=0)
    check_bool("async", cfg["async"])
    check_int("watch_every", cfg["watch_every"], minimum=0)  # 0: no evaluation episodes to watch
    if not (isinstance(cfg["watch_connect"], list) and all(isinstance(e, str) for e in cfg["watch_connect"])):
        raise ValueError(f"watch_connect: expected a list of Zenoh endpoints, got {cfg['watch_connect']!r}")
    if not isinstance(cfg["watch_server"], str):
        raise ValueError(f"watch_server: expected the match server's name, got {cfg['watch_server']!r}")
    if cfg["batch_size"] > cfg["buffer_size"]:
        raise ValueError(f"batch_size: must be <= buffer_size ({cfg['buffer_size']}), got {cfg['batch_size']}")
    cfg["shaping"] = check_shaping(cfg["shaping"])
    cfg["curriculum"] = _check_curriculum(cfg["curriculum"])
    cfg["selfplay"] = check_selfplay(cfg["selfplay"])
    cfg["imitate"] = check_imitate(cfg["imitate"], "imitate")
    cfg["kickstart"] = check_kickstart(cfg["kickstart"], "kickstart")
    for key in ("imitate", "kickstart"):
        if cfg[key] and cfg["selfplay"]:
            raise ValueError(f"{key}: with selfplay, the teacher goes under selfplay.{key}")
    if cfg["selfplay"] and cfg["curriculum"]:
        raise ValueError("selfplay: a curriculum needs a minigame's difficulty; self-play trains on a match")
    # The env config is validated now, so a typo there fails before any training starts.
    load_config(cfg["env"], cfg["env_overrides"])
    return cfg


def _check_curriculum(curriculum: object) -> dict[str, float]:
    out = optional_section("curriculum", curriculum, CURRICULUM_KEYS)
    if not out:
        return out
    for key, value in out.items():
        out[key] = check_number(f"curriculum.{key}", value, 0.0, 1.0)
    check_number("curriculum.step", out["step"], above=0.0)
    return out


def load_train_config(path: str | Path, overrides: dict[str, Any] | None = None) -> dict[str, Any]:
    """A training YAML (resolved like env configs: as given, else the shipped one)."""
    raw = load_yaml_file(resolve_shipped_path(path, "training config"), "training config") or {}
    if not isinstance(raw, dict):
        raise ValueError(f"training config: {path} must hold a mapping of keys to values")
    return validate_train_config({**raw, **(overrides or {})})
