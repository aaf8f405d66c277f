"""Training configs as a ``TrainConfig``: one field a key of the training YAML, its meaning in the field's docstring.

The hyperparameters keep ML-Agents' names and meanings (its ``trainer_config``); the rest says what to train on
(``env``), how many env copies and worker processes collect, and the optional sections: ``curriculum``,
``selfplay`` (``selfplay/config.py``), a scripted teacher (``imitate``, ``kickstart``) and reward ``shaping``.

``load_train_config`` reads a YAML, ``validate_train_config`` checks a mapping (each field's annotation says what
it holds, read by ``rocketdrl_ma.validation.load_dataclass``, so every error names the key and what is allowed;
``TrainConfig.check`` ties fields together), and ``TrainConfig.to_mapping`` is
the plain form a checkpoint stores (``checkpoint.py``), which ``validate_train_config`` reads back.
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from rocketdrl_ma.config import load_config, load_yaml_mapping
from rocketdrl_ma.validation import Check, Expect, OneOf, Range, load_dataclass, yaml_key

from rocketdrl_ma.policies.ppo.selfplay.config import (ImitateConfig, KickstartConfig, Positive, SelfPlayConfig,
                                                        check_checkpoint_path)

from .critic import CRITICS
from .features import FEATURES
from .shaping import check_shaping

SCHEDULES = ("linear", "constant")
DEVICES = ("auto", "cpu", "cuda")
Fraction = Annotated[float, Range(0.0, 1.0)]
Above0 = Annotated[float, Range(above=0.0)]


@dataclass(frozen=True)
class CurriculumConfig:
    """ML-Agents' lessons over a minigame's ``difficulty``: start at ``start``; each time the last 100 training
    episodes succeed at least ``threshold`` of the time, raise the difficulty by ``step``, up to 1."""

    start: Fraction = 0.0
    """the difficulty of the first episodes, in [0, 1]"""
    step: Annotated[float, Range(0.0, 1.0, above=0.0)] = 0.1
    """how much the difficulty rises at a time, in (0, 1]"""
    threshold: Fraction = 0.8
    """the success rate over the last 100 episodes that moves the difficulty up, in [0, 1]"""


@dataclass(frozen=True)
class TrainConfig:
    """A PPO training run (``trainer.train``); defaults are ML-Agents' PPO defaults where it has one."""

    env: Annotated[str | dict[str, Any], Check(_check_env_path)]
    """the match or minigame YAML to train on (a path, else the shipped config of that name); the trainer hands
    its rollout workers the resolved env config instead (``trainer.worker_config``), so a worker on another
    machine needs no YAML file"""
    env_overrides: Annotated[dict[str, Any], Expect("a mapping of env keys to values")] = field(
        default_factory=dict)
    """keys of the env config to replace"""
    n_envs: Positive = 8
    """env copies feeding the trainer"""
    seed: int = 0
    """seeds torch and the env copies (copy ``i``: ``seed + i``)"""
    device: Annotated[str, OneOf(DEVICES)] = "auto"
    """where the learner runs: ``auto`` (a GPU if present, else the CPU), ``cpu`` or ``cuda``"""
    batch_size: Positive = 1024
    """experiences per gradient step (minibatch)"""
    buffer_size: Positive = 10240
    """experiences collected per policy update (over every agent of every env copy)"""
    learning_rate: Above0 = 3.0e-4
    """Adam's step size at the start"""
    learning_rate_schedule: Annotated[str, OneOf(SCHEDULES)] = "linear"
    """``linear``: the learning rate decays to 0 at ``max_steps``; ``constant``"""
    beta: Annotated[float, Range(minimum=0.0)] = 5.0e-3
    """entropy bonus coefficient"""
    epsilon: Above0 = 0.2
    """PPO's clip range"""
    lambd: Fraction = 0.95
    """GAE's lambda"""
    num_epoch: Positive = 3
    """passes over the buffer per update"""
    normalize: bool = False
    """running mean/variance normalisation of observations"""
    hidden_units: Positive = 128
    """width of the actor's and the critic's MLP layers"""
    num_layers: Positive = 2
    """hidden layers of each MLP"""
    gamma: Fraction = 0.99
    """discount"""
    strength: float = 1.0
    """scale of the env's reward"""
    time_horizon: Positive = 64
    """experiences of one agent before its trajectory is cut and bootstrapped with the critic's value"""
    max_steps: Positive = 500_000
    """agent steps to train for"""
    summary_freq: Positive = 50_000
    """agent steps between TensorBoard summaries"""
    checkpoint_interval: Positive = 500_000
    """agent steps between periodic checkpoints (``RUN_DIR/checkpoints``)"""
    keep_checkpoints: Positive = 5
    """periodic checkpoints kept"""
    shaping: Annotated[Any, Check(_check_shaping)] = field(default_factory=dict)
    """weights of the trainer's potential-based shaping terms by name (``shaping.py``); empty: none"""
    init_std: Above0 = 1.0
    """the Gaussian policy's initial standard deviation (1, as ML-Agents). Box policies start with their mean at
    the idle car's controls (no jump, boost or drift), so early exploration drives rather than hops"""
    features: Annotated[str, OneOf(FEATURES)] = "none"
    """fixed inputs the model computes from the observation (``features.py``): ``none``, or ``car_local`` (ball
    and other cars in the car's own frame; needs the ``team_relative`` observation)"""
    critic: Annotated[str, OneOf(CRITICS)] = "local"
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
    init_path: Annotated[str, Expect("the path of a checkpoint (.pt with its JSON beside it) or null"),
                         Check(check_checkpoint_path)] | None = None
    """a checkpoint a fresh run starts from (ML-Agents' ``init_path``): its weights and normaliser statistics, the
    statistics then held fixed as after a warm start; one trained on a smaller ``team_relative`` game (a 1v1 policy
    starting a 2v2 run) is grown to this game's teams and plays as before (``transfer.py``); null: fresh weights.
    ``--resume`` continues a run instead; a warm start (``imitate``) is the other way to start, not both"""
    n_workers: Annotated[int, Range(minimum=0)] | None = None
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
    watch_every: Annotated[int, Range(minimum=0)] = 0
    """every that many iterations, play one greedy evaluation episode of the current policy and publish it for
    ``rocketdrl-ma web`` (``rocketdrl_ma/web/training.py``); 0: never"""
    watch_server: Annotated[str, Expect("the match server's name")] = "local"
    """the match server those episodes are published to"""
    watch_connect: Annotated[tuple[str, ...], Expect("a list of Zenoh endpoints")] = (
        "tcp/127.0.0.1:7447",)
    """the Zenoh endpoints it is reached at"""

    @property
    def teacher_imitate(self) -> ImitateConfig | None:
        """The warm start, wherever the YAML put it (``selfplay.imitate`` or ``imitate``)."""
        return self.selfplay.imitate if self.selfplay else self.imitate

    @property
    def teacher_kickstart(self) -> KickstartConfig | None:
        """The kickstart teacher, wherever the YAML put it (``selfplay.kickstart`` or ``kickstart``)."""
        return self.selfplay.kickstart if self.selfplay else self.kickstart

    def check(self) -> None:
        """What ties fields together; the env config is loaded too, so a typo there fails before training starts."""
        if self.batch_size > self.buffer_size:
            raise ValueError(f"batch_size: must be <= buffer_size ({self.buffer_size}), got {self.batch_size}")
        for key in ("imitate", "kickstart"):
            if getattr(self, key) and self.selfplay:
                raise ValueError(f"{key}: with selfplay, the teacher goes under selfplay.{key}")
        if self.init_path is not None and self.teacher_imitate:
            raise ValueError("init_path: a run starts from a checkpoint or from a warm start (imitate), not both")
        if self.selfplay and self.curriculum:
            raise ValueError("selfplay: a curriculum needs a minigame's difficulty; self-play trains on a match")
        load_config(self.env, self.env_overrides)

    def to_mapping(self) -> dict[str, Any]:
        """The plain form, keyed as the YAML is (what a checkpoint's JSON stores; ``validate_train_config`` reads
        it back to an equal config)."""
        values = dataclasses.asdict(self)
        return {yaml_key(f): values[f.name] for f in dataclasses.fields(self)}


def validate_train_config(raw: Mapping[str, Any]) -> TrainConfig:
    """The ``TrainConfig`` of a training YAML's mapping (or a checkpoint's stored one): defaults filled in, every
    value checked, the env config validated too; ValueError names the bad key and what is allowed."""
    if not isinstance(raw, Mapping):
        raise ValueError(f"training config: expected a mapping of keys to values, got {type(raw).__name__}")
    return load_dataclass(TrainConfig, raw, "training config")


def _check_shaping(_: str, weights: object) -> dict[str, float]:
    return check_shaping(weights)  # names the field itself


def _check_env_path(field_name: str, env: object) -> str:
    if not isinstance(env, str):
        raise ValueError(f"{field_name}: expected the path of a match or minigame YAML, got {env!r}")
    return env


def load_train_config(path: str | Path, overrides: Mapping[str, Any] | None = None) -> TrainConfig:
    """A training YAML (resolved like env configs: as given, else the shipped one), ``overrides`` replacing its
    top-level keys."""
    return validate_train_config(load_yaml_mapping(path, "training config", overrides))
