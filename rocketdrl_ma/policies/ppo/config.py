"""Training configs as a ``TrainConfig``: one field a key of the training YAML, its meaning in the field's docstring.

The hyperparameters keep ML-Agents' names and meanings (its ``trainer_config``); the rest says what to train on
(``env``), how many env copies and worker processes collect, and the optional sections: ``curriculum``,
``selfplay`` (``selfplay/config.py``), a scripted teacher (``imitate``, ``kickstart``) and reward ``shaping``.

``load_train_config`` reads a YAML, ``validate_train_config`` checks a mapping (with the shared checks of
``rocketdrl_ma.validation``, so every error names the key and what is allowed), and ``TrainConfig.to_mapping`` is
the plain form a checkpoint stores (``checkpoint.py``), which ``validate_train_config`` reads back.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rocketdrl_ma.config import load_config, load_yaml_file, resolve_shipped_path
from rocketdrl_ma.validation import (check_bool, check_choice, check_int, check_number, section_values,
                                     yaml_key)

from rocketdrl_ma.policies.ppo.selfplay.config import (ImitateConfig, KickstartConfig, SelfPlayConfig,
                                                        check_checkpoint_path, check_imitate, check_kickstart,
                                                        check_selfplay)

from .critic import CRITICS
from .features import FEATURES
from .shaping import check_shaping

SCHEDULES = ("linear", "constant")
DEVICES = ("auto", "cpu", "cuda")


@dataclass(frozen=True)
class CurriculumConfig:
    """ML-Agents' lessons over a minigame's ``difficulty``: start at ``start``; each time the last 100 training
    episodes succeed at least ``threshold`` of the time, raise the difficulty by ``step``, up to 1."""

    start: float = 0.0
    """the difficulty of the first episodes, in [0, 1]"""
    step: float = 0.1
    """how much the difficulty rises at a time, in (0, 1]"""
    threshold: float = 0.8
    """the success rate over the last 100 episodes that moves the difficulty up, in [0, 1]"""


@dataclass(frozen=True)
class TrainConfig:
    """A PPO training run (``trainer.train``); defaults are ML-Agents' PPO defaults where it has one."""

    env: str | dict[str, Any]
    """the match or minigame YAML to train on (a path, else the shipped config of that name); the trainer hands
    its rollout workers the resolved env config instead (``trainer.worker_config``), so a worker on another
    machine needs no YAML file"""
    env_overrides: dict[str, Any] = field(default_factory=dict)
    """keys of the env config to replace"""
    n_envs: int = 8
    """env copies feeding the trainer"""
    seed: int = 0
    """seeds torch and the env copies (copy ``i``: ``seed + i``)"""
    device: str = "auto"
    """where the learner runs: ``auto`` (a GPU if present, else the CPU), ``cpu`` or ``cuda``"""
    batch_size: int = 1024
    """experiences per gradient step (minibatch)"""
    buffer_size: int = 10240
    """experiences collected per policy update (over every agent of every env copy)"""
    learning_rate: float = 3.0e-4
    """Adam's step size at the start"""
    learning_rate_schedule: str = "linear"
    """``linear``: the learning rate decays to 0 at ``max_steps``; ``constant``"""
    beta: float = 5.0e-3
    """entropy bonus coefficient"""
    epsilon: float = 0.2
    """PPO's clip range"""
    lambd: float = 0.95
    """GAE's lambda"""
    num_epoch: int = 3
    """passes over the buffer per update"""
    normalize: bool = False
    """running mean/variance normalisation of observations"""
    hidden_units: int = 128
    """width of the actor's and the critic's MLP layers"""
    num_layers: int = 2
    """hidden layers of each MLP"""
    gamma: float = 0.99
    """discount"""
    strength: float = 1.0
    """scale of the env's reward"""
    time_horizon: int = 64
    """experiences of one agent before its trajectory is cut and bootstrapped with the critic's value"""
    max_steps: int = 500_000
    """agent steps to train for"""
    summary_freq: int = 50_000
    """agent steps between TensorBoard summaries"""
    checkpoint_interval: int = 500_000
    """agent steps between periodic checkpoints (``RUN_DIR/checkpoints``)"""
    keep_checkpoints: int = 5
    """periodic checkpoints kept"""
    shaping: dict[str, float] = field(default_factory=dict)
    """weights of the trainer's potential-based shaping terms by name (``shaping.py``); empty: none"""
    init_std: float = 1.0
    """the Gaussian policy's initial standard deviation (1, as ML-Agents). Box policies start with their mean at
    the idle car's controls (no jump, boost or drift), so early exploration drives rather than hops"""
    features: str = "none"
    """fixed inputs the model computes from the observation (``features.py``): ``none``, or ``car_local`` (ball
    and other cars in the car's own frame; needs the ``team_relative`` observation)"""
    critic: str = "local"
    """what the value network reads (``critic.py``): ``local``, the car's own observation (independent PPO), or
    ``central``, its whole team's observations, its own first (MAPPO's centralised critic); the actor acts on the
    car's own observation either way, so a checkpoint plays the same"""
    curriculum: CurriculumConfig | None = None
    """raise a minigame's difficulty as the learner succeeds; null: the env config's difficulty throughout"""
    selfplay: SelfPlayConfig | None = None
    """train one team against an opponent pool (``selfplay/config.py``); null: every agent is the learner"""
    imitate: ImitateConfig | None = None
    """for a game without self-play (a minigame's shooter): clone a scripted bot, then DAgger, before the first
    update, as ``selfplay.imitate`` does (with ``selfplay`` it goes there)"""
    kickstart: KickstartConfig | None = None
    """for a game without self-play: a fading distillation term towards a scripted bot on the learner's own
    states, as ``selfplay.kickstart`` (with ``selfplay`` it goes there)"""
    init_path: str | None = None
    """a checkpoint a fresh run starts from (ML-Agents' ``init_path``): its weights and normaliser statistics, the
    statistics then held fixed as after a warm start; one trained on a smaller ``team_relative`` game (a 1v1 policy
    starting a 2v2 run) is grown to this game's teams and plays as before (``transfer.py``); null: fresh weights.
    ``--resume`` continues a run instead; a warm start (``imitate``) is the other way to start, not both"""
    n_workers: int | None = None
    """rollout worker processes, each stepping ``ceil(n_envs / n_workers)`` env copies with its own copy of the
    policy (``workers.py``); null: one per core of the machine; 0: the env copies run in the trainer's own
    process. ``--workers`` overrides it"""
    asynchronous: bool = field(default=False, metadata={"key": "async"})
    """(YAML key ``async``) the learner updates on each worker's batch as it arrives while the others go on
    collecting (the policy lag, in updates, goes to TensorBoard); false: every iteration waits for all workers,
    and a seed and worker count give the same run"""
    overlap: bool = True
    """with worker processes and without ``async``: the workers collect the next batch, with the weights of the
    update before, while the learner updates on this one, so no core waits; every batch is then exactly one
    update old (policy lag 1, corrected by PPO's importance ratio) and a seed and worker count still give the same
    run; false: the workers wait while the learner updates (lag 0)"""
    watch_every: int = 0
    """every that many iterations, play one greedy evaluation episode of the current policy and publish it for
    ``rocketdrl-ma web`` (``rocketdrl_ma/web/training.py``); 0: never"""
    watch_server: str = "local"
    """the match server those episodes are published to"""
    watch_connect: tuple[str, ...] = ("tcp/127.0.0.1:7447",)
    """the Zenoh endpoints it is reached at"""

    @property
    def teacher_imitate(self) -> ImitateConfig | None:
        """The warm start, wherever the YAML put it (``selfplay.imitate`` or ``imitate``)."""
        return self.selfplay.imitate if self.selfplay else self.imitate

    @property
    def teacher_kickstart(self) -> KickstartConfig | None:
        """The kickstart teacher, wherever the YAML put it (``selfplay.kickstart`` or ``kickstart``)."""
        return self.selfplay.kickstart if self.selfplay else self.kickstart

    def to_mapping(self) -> dict[str, Any]:
        """The plain form, keyed as the YAML is (what a checkpoint's JSON stores; ``validate_train_config`` reads
        it back to an equal config)."""
        values = dataclasses.asdict(self)
        return {yaml_key(f): values[f.name] for f in dataclasses.fields(self)}


POSITIVE_INTS = ("n_envs", "batch_size", "buffer_size", "num_epoch", "hidden_units", "num_layers", "time_horizon",
                 "max_steps", "summary_freq", "checkpoint_interval", "keep_checkpoints")


def validate_train_config(raw: Mapping[str, Any]) -> TrainConfig:
    """The ``TrainConfig`` of a training YAML's mapping (or a checkpoint's stored one): defaults filled in, every
    value checked, the env config validated too; ValueError names the bad key and what is allowed."""
    if not isinstance(raw, Mapping):
        raise ValueError(f"training config: expected a mapping of keys to values, got {type(raw).__name__}")
    values = section_values("training config", raw, TrainConfig)
    if not isinstance(values["env"], str):
        raise ValueError(f"env: expected the path of a match or minigame YAML, got {values['env']!r}")
    if not isinstance(values["env_overrides"], Mapping):
        raise ValueError(f"env_overrides: expected a mapping of env keys to values, got {values['env_overrides']!r}")
    values["env_overrides"] = dict(values["env_overrides"])
    for key in POSITIVE_INTS:
        check_int(key, values[key], minimum=1)
    check_int("seed", values["seed"])
    for key in ("lambd", "gamma"):
        values[key] = check_number(key, values[key], 0.0, 1.0)
    for key in ("learning_rate", "epsilon", "init_std"):
        values[key] = check_number(key, values[key], above=0.0)
    values["beta"] = check_number("beta", values["beta"], minimum=0.0)
    values["strength"] = check_number("strength", values["strength"])
    check_choice("learning_rate_schedule", values["learning_rate_schedule"], SCHEDULES)
    check_choice("device", values["device"], DEVICES)
    check_choice("features", values["features"], FEATURES)
    check_choice("critic", values["critic"], CRITICS)
    check_bool("normalize", values["normalize"])
    if values["n_workers"] is not None:  # 0: no worker processes; null: one per core
        check_int("n_workers", values["n_workers"], minimum=0)
    check_bool("async", values["asynchronous"])
    check_bool("overlap", values["overlap"])
    check_int("watch_every", values["watch_every"], minimum=0)  # 0: no evaluation episodes to watch
    connect = values["watch_connect"]
    if not (isinstance(connect, (list, tuple)) and all(isinstance(e, str) for e in connect)):
        raise ValueError(f"watch_connect: expected a list of Zenoh endpoints, got {connect!r}")
    values["watch_connect"] = tuple(connect)
    if not isinstance(values["watch_server"], str):
        raise ValueError(f"watch_server: expected the match server's name, got {values['watch_server']!r}")
    if values["batch_size"] > values["buffer_size"]:
        raise ValueError(f"batch_size: must be <= buffer_size ({values['buffer_size']}), got {values['batch_size']}")
    values["shaping"] = check_shaping(values["shaping"])
    values["curriculum"] = _check_curriculum(values["curriculum"])
    values["selfplay"] = check_selfplay(values["selfplay"])
    values["imitate"] = check_imitate(values["imitate"], "imitate")
    values["kickstart"] = check_kickstart(values["kickstart"], "kickstart")
    for key in ("imitate", "kickstart"):
        if values[key] and values["selfplay"]:
            raise ValueError(f"{key}: with selfplay, the teacher goes under selfplay.{key}")
    if values["init_path"] is not None:
        if not isinstance(values["init_path"], str):
            raise ValueError(f"init_path: expected the path of a checkpoint (.pt with its JSON beside it) or null, "
                             f"got {values['init_path']!r}")
        check_checkpoint_path("init_path", values["init_path"])
        if values["imitate"] or (values["selfplay"] and values["selfplay"].imitate):
            raise ValueError("init_path: a run starts from a checkpoint or from a warm start (imitate), not both")
    if values["selfplay"] and values["curriculum"]:
        raise ValueError("selfplay: a curriculum needs a minigame's difficulty; self-play trains on a match")
    # The env config is validated now, so a typo there fails before any training starts.
    load_config(values["env"], values["env_overrides"])
    return TrainConfig(**values)


def _check_curriculum(section: object) -> CurriculumConfig | None:
    values = section_values("curriculum", section, CurriculumConfig)
    if not section:
        return None
    for key, value in values.items():
        values[key] = check_number(f"curriculum.{key}", value, 0.0, 1.0)
    check_number("curriculum.step", values["step"], above=0.0)
    return CurriculumConfig(**values)


def load_train_config(path: str | Path, overrides: Mapping[str, Any] | None = None) -> TrainConfig:
    """A training YAML (resolved like env configs: as given, else the shipped one), ``overrides`` replacing its
    top-level keys."""
    raw = load_yaml_file(resolve_shipped_path(path, "training config"), "training config") or {}
    if not isinstance(raw, dict):
        raise ValueError(f"training config: {path} must hold a mapping of keys to values")
    return validate_train_config({**raw, **(overrides or {})})
