"""Checkpoints: ``NAME.pt`` is the model's plain state dict, ``NAME.json`` what it was trained on.

The JSON carries the resolved env config (mode, observation builder, action parser and their options),
the network's shape, the training config and the agent-step count, so a checkpoint alone rebuilds a
playing policy: ``load_policy("checkpoint:policies/checkpoints/penalty.pt")``. ``NAME.optim.pt``
(optimizer state) sits next to it only so training can resume; playing never needs it.
No pickled code anywhere: every file loads with ``torch.load(weights_only=True)`` or ``json``.
"""
from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
import torch

from rocketdrl_ma.config import load_config, resolve_shipped_path
from rocketdrl_ma.env.actions import make_action_parser
from rocketdrl_ma.env.observations import make_obs_builder
from rocketdrl_ma.policies.base import ObservingPolicy

from .config import TrainConfig
from .model import PPOModel

FORMAT = "rocketdrl_ma.ppo/1"


def sidecar(path: str | Path, suffix: str) -> Path:
    """``runs/x/step_100.pt`` -> ``runs/x/step_100<suffix>``."""
    p = Path(path)
    return p.with_name(p.name[:-3] + suffix if p.name.endswith(".pt") else p.name + suffix)


def checkpoint_meta(cfg: TrainConfig, model: PPOModel, obs_dim: int, agent_steps: int,
                    metrics: dict[str, float], difficulty: float | None = None) -> dict[str, Any]:
    """The JSON beside a checkpoint: the network's shape, the env it plays, the training config (its plain form,
    ``TrainConfig.to_mapping``), its step count."""
    net = {"obs_dim": obs_dim, "action": model.action, "hidden_units": cfg.hidden_units,
           "num_layers": cfg.num_layers, "normalize": cfg.normalize, "features": model.features,
           "critic": cfg.critic, "critic_inputs": model.critic_inputs}
    env = {"config": cfg.env, "overrides": cfg.env_overrides, "resolved": load_config(cfg.env, cfg.env_overrides)}
    return {"agent_steps": agent_steps, "network": net, "env": env, "train": cfg.to_mapping(), "metrics": metrics,
            "difficulty": difficulty}


def save_checkpoint(path: str | Path, model: PPOModel, meta: dict[str, Any],
                    optimizer: torch.optim.Optimizer | None = None) -> Path:
    """Write ``path`` (state dict), its ``.json`` and, given an optimizer, its ``.optim.pt``."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    torch.save(model.state_dict(), p)
    sidecar(p, ".json").write_text(json.dumps({"format": FORMAT, **meta}, indent=2, sort_keys=True) + "\n")
    if optimizer is not None:
        torch.save(optimizer.state_dict(), sidecar(p, ".optim.pt"))
    return p


def resolve_checkpoint(path: str | Path) -> Path:
    """A checkpoint path as given, else the shipped checkpoint of that name (``policies/checkpoints/...``)."""
    return resolve_shipped_path(path, "checkpoint")


def read_meta(path: str | Path) -> dict[str, Any]:
    p = resolve_checkpoint(path)
    meta_path = sidecar(p, ".json")
    if not meta_path.is_file():
        raise ValueError(f"checkpoint: {p} has no {meta_path.name} next to it (its config)")
    meta = json.loads(meta_path.read_text())
    if meta.get("format") != FORMAT:
        raise ValueError(f"checkpoint: {meta_path} has format {meta.get('format')!r}, expected {FORMAT!r}")
    return meta


def load_model(path: str | Path) -> tuple[PPOModel, dict[str, Any]]:
    """The model with its weights and the checkpoint's metadata."""
    p = resolve_checkpoint(path)
    meta = read_meta(p)
    net = meta["network"]
    model = PPOModel(net["obs_dim"], net["action"], net["hidden_units"], net["num_layers"], net["normalize"],
                     # checkpoints from before features and the central critic: none, local
                     features=net.get("features", "none"), critic_inputs=net.get("critic_inputs", 1))
    model.load_state_dict(torch.load(p, map_location="cpu", weights_only=True))
    model.eval()
    return model, meta


class ModelPolicy(ObservingPolicy):
    """A PPO model playing greedily through the observation builder and action parser of the resolved env
    config it learns on (the trainer hands a frozen copy of its model to ``watch_every``'s episodes)."""

    def __init__(self, model: PPOModel, env_config: dict[str, Any], name: str = "training policy"):
        obs_spec, act_spec = dict(env_config["observation"]), dict(env_config["action"])
        super().__init__(make_obs_builder(obs_spec.pop("name"), **obs_spec),
                         make_action_parser(act_spec.pop("name"), **act_spec))
        self.model = copy.deepcopy(model).eval()  # a trainer goes on changing its own weights
        self.name = name

    def act(self, obs: np.ndarray) -> np.ndarray | int:
        action = self.model.act_deterministic(obs[None])[0]
        return int(action) if self.model.action["kind"] == "discrete" else action


class CheckpointPolicy(ModelPolicy):
    """A trained PPO policy playing greedily through the observation builder and action parser it learned with."""

    def __init__(self, path: str | Path):
        model, self.meta = load_model(path)
        super().__init__(model, self.meta["env"]["resolved"], f"checkpoint:{path}")


def load_checkpoint_policy(path: str) -> CheckpointPolicy:
    """The registry's loader for ``checkpoint:PATH``."""
    return CheckpointPolicy(path)
