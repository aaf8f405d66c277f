"""PPO training with torch and torchrl on any env config, with the ML-Agents hyperparameter names.

``config.py`` is the training YAML as a typed ``TrainConfig``, ``envs.py`` batches env copies into rows, ``model.py`` is the
actor-critic, ``trainer.py`` the loop, ``checkpoint.py`` the state dict + JSON format and the playing
policy the registry loads as ``checkpoint:PATH``, ``evaluate.py`` greedy evaluation (alone or against an
opponent policy).

``train`` and ``TrainResult`` are imported on first use (PEP 562): the trainer needs torchrl and tensordict, and a
process that only plays or evaluates a checkpoint (a league worker, a bot) does not load them, about 3 s less at
start-up.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .checkpoint import CheckpointPolicy, load_checkpoint_policy, load_model, save_checkpoint
from .config import TrainConfig, load_train_config, validate_train_config
from .evaluate import EvalResult, evaluate, evaluate_against, evaluate_policy

if TYPE_CHECKING:
    from .trainer import TrainResult, train

__all__ = ["CheckpointPolicy", "EvalResult", "TrainConfig", "TrainResult", "evaluate", "evaluate_against",
           "evaluate_policy", "load_checkpoint_policy", "load_model", "load_train_config", "save_checkpoint", "train",
           "validate_train_config"]


def __getattr__(name: str) -> Any:
    if name in ("train", "TrainResult"):
        from . import trainer
        return getattr(trainer, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
