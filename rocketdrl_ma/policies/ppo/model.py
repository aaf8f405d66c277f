"""The actor-critic: separate MLPs for the policy and the value, and a running observation normaliser.

A flat ``Box`` action space gets a Gaussian policy with a learned, state-independent standard
deviation (the env receives the sample clipped to [-1, 1], the loss sees the raw sample); a
``Discrete`` one (the lookup table) gets a categorical policy. The model is a plain ``nn.Module``, so
its ``state_dict`` (normaliser statistics included) is the whole exported policy.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import torch
from gymnasium import spaces
from torch import nn

from .features import make_features

if TYPE_CHECKING:
    from torchrl.modules import ProbabilisticActor, ValueOperator

NORM_CLIP = 5.0  # normalised observations are clipped to +-5 standard deviations, as in ML-Agents


def action_spec(space: spaces.Space) -> dict:
    """The JSON-able description of an action space that the model needs."""
    if isinstance(space, spaces.Box) and len(space.shape) == 1:
        return {"kind": "box", "dim": int(space.shape[0])}
    if isinstance(space, spaces.Discrete):
        return {"kind": "discrete", "n": int(space.n)}
    raise ValueError(f"action space: PPO supports a flat Box or a Discrete space, got {space}")


class RunningNorm(nn.Module):
    """The model's input: the raw observation with its fixed ``features`` (``features.py``) appended, then
    normalised by the running mean and variance of that (parallel Welford update; identity when disabled)."""

    def __init__(self, dim: int, enabled: bool, features: nn.Module | None = None):
        super().__init__()
        self.enabled = enabled
        self.features = features
        self.register_buffer("mean", torch.zeros(dim))
        self.register_buffer("var", torch.ones(dim))
        self.register_buffer("count", torch.tensor(1e-4))

    @torch.no_grad()
    def update(self, x: torch.Tensor) -> None:
        if not self.enabled:
            return
        if self.features is not None:
            x = self.features(x)
        batch_mean, batch_var, n = x.mean(0), x.var(0, unbiased=False), x.shape[0]
        delta, total = batch_mean - self.mean, self.count + n
        self.mean += delta * n / total
        self.var.copy_((self.var * self.count + batch_var * n + delta.square() * self.count * n / total) / total)
        self.count.copy_(total)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.features is not None:
            x = self.features(x)
        if not self.enabled:
            return x
        return ((x - self.mean) / torch.sqrt(self.var + 1e-8)).clamp(-NORM_CLIP, NORM_CLIP)


def mlp(n_in: int, n_out: int, hidden_units: int, num_layers: int, out_gain: float) -> nn.Sequential:
    layers: list[nn.Module] = []
    width = n_in
    for _ in range(num_layers):
        layers += [nn.Linear(width, hidden_units), nn.SiLU()]  # Swish, as ML-Agents uses
        width = hidden_units
    layers.append(nn.Linear(width, n_out))
    for layer in layers:
        if isinstance(layer, nn.Linear):  # orthogonal init; a small last layer starts near-uniform
            nn.init.orthogonal_(layer.weight, np.sqrt(2.0))
            nn.init.zeros_(layer.bias)
    nn.init.orthogonal_(layers[-1].weight, out_gain)
    return nn.Sequential(*layers)


class GaussianHead(nn.Module):
    def __init__(self, body: nn.Module, dim: int, init_std: float):
        super().__init__()
        self.body = body
        self.log_std = nn.Parameter(torch.full((dim,), float(np.log(init_std))))

    def forward(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        loc = self.body(obs)
        return loc, self.log_std.exp().expand_as(loc)


class PPOModel(nn.Module):
    def __init__(self, obs_dim: int, action: dict, hidden_units: int, num_layers: int, normalize: bool,
                 init_std: float = 1.0, init_action: np.ndarray | None = None, features: str = "none",
                 critic_inputs: int = 1):
        super().__init__()
        self.action = action
        feature_module, in_dim = make_features(features, obs_dim)
        self.features = features  # by name, for the checkpoint's JSON
        self.input_dim = in_dim  # what the MLPs see: the observation and its features
        self.obs_norm = RunningNorm(in_dim, normalize, feature_module)
        if action["kind"] == "box":
            body = mlp(in_dim, action["dim"], hidden_units, num_layers, 0.01)
            if init_action is not None:  # start from these controls (the idle car: no jump, no boost)
                with torch.no_grad():
                    body[-1].bias.copy_(torch.as_tensor(init_action, dtype=torch.float32))
            self.policy: nn.Module = GaussianHead(body, action["dim"], init_std)
        else:
            self.policy = mlp(in_dim, action["n"], hidden_units, num_layers, 0.01)
        # the value reads ``critic_inputs`` model inputs side by side: 1, the car's own (``critic: local``), or its
        # team's, its own first (``central``, MAPPO; critic.py), given to ClipPPOLoss as "critic_observation"
        self.critic_inputs = critic_inputs
        self.critic_key = "observation" if critic_inputs == 1 else "critic_observation"
        self.value = mlp(in_dim * critic_inputs, 1, hidden_units, num_layers, 1.0)

    def td_modules(self) -> tuple[ProbabilisticActor, ValueOperator]:
        """torchrl views of the policy over normalised ``"observation"`` and of the value over ``critic_key``
        (for ClipPPOLoss). torchrl is imported here, not with the module: playing a checkpoint never needs it."""
        from tensordict.nn import TensorDictModule
        from torchrl.modules import IndependentNormal, ProbabilisticActor, ValueOperator

        if self.action["kind"] == "box":
            actor = ProbabilisticActor(
                TensorDictModule(self.policy, in_keys=["observation"], out_keys=["loc", "scale"]),
                in_keys=["loc", "scale"], out_keys=["action"], distribution_class=IndependentNormal,
                return_log_prob=True)
        else:
            actor = ProbabilisticActor(
                TensorDictModule(self.policy, in_keys=["observation"], out_keys=["logits"]),
                in_keys=["logits"], out_keys=["action"], distribution_class=torch.distributions.Categorical,
                return_log_prob=True)
        return actor, ValueOperator(self.value, in_keys=[self.critic_key])

    @torch.no_grad()
    def act_deterministic(self, obs: np.ndarray) -> np.ndarray:
        """Greedy env actions for a batch of raw observations: the clipped mean, or the most likely index."""
        x = self.obs_norm(torch.as_tensor(np.asarray(obs, np.float32)))
        if self.action["kind"] == "box":
            return self.policy(x)[0].clamp(-1.0, 1.0).numpy()
        return self.policy(x).argmax(-1).numpy()


@torch.no_grad()
def sample_env_actions(model: PPOModel, obs: torch.Tensor | np.ndarray) -> np.ndarray:
    """Env actions sampled from ``model``'s policy for a batch of raw observations (how an opponent plays)."""
    x = model.obs_norm(torch.as_tensor(np.asarray(obs, np.float32)))
    if model.action["kind"] == "box":
        loc, scale = model.policy(x)
        return env_actions(model.action, torch.normal(loc, scale))
    sampled = torch.distributions.Categorical(logits=model.policy(x), validate_args=False).sample()
    return env_actions(model.action, sampled)


def env_actions(action: dict, sampled: torch.Tensor) -> np.ndarray:
    """What the env receives for the policy's samples: Box samples clipped into [-1, 1], indices as ints."""
    if action["kind"] == "box":
        return sampled.clamp(-1.0, 1.0).numpy()
    return sampled.numpy().astype(np.int64)
