"""The policy heads of several networks of one shape in one batched forward: every row played by its own network.

A self-play worker plays the learner itself and up to ``pool_size`` snapshots as opponents; one forward per network
costs a Python round of small matrix products each. Here the networks' weights are stacked once
(``StackedPolicies``, rebuilt when the weights change) and every row's input goes through its network's weights in
one ``baddbmm`` per layer, rows padded per network to the largest group. The outputs equal each network's own
forward up to float rounding (the batched kernels sum in another order; ``tests/policies/test_worker_loop.py``
states the tolerance).
"""
from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import nn

from .model import NORM_CLIP, GaussianHead, PPOModel


def _policy_layers(model: PPOModel) -> list[nn.Linear]:
    body = model.policy.body if isinstance(model.policy, GaussianHead) else model.policy
    return [layer for layer in body if isinstance(layer, nn.Linear)]


class StackedPolicies:
    """The policy outputs of ``models`` (one shape, one feature set) for rows each played by one of them."""

    def __init__(self, models: Sequence[PPOModel]):
        first = models[0]
        self.box = first.action["kind"] == "box"
        self.features = first.obs_norm.features
        self.normalize = first.obs_norm.enabled
        self.mean = torch.stack([m.obs_norm.mean for m in models])
        self.std = torch.stack([torch.sqrt(m.obs_norm.var + 1e-8) for m in models])
        layers = [_policy_layers(m) for m in models]
        self.weights = [torch.stack([per_model[k].weight.T for per_model in layers]) for k in range(len(layers[0]))]
        self.biases = [torch.stack([per_model[k].bias for per_model in layers]).unsqueeze(1)
                       for k in range(len(layers[0]))]
        self.log_std = torch.stack([m.policy.log_std for m in models]) if self.box else None

    @torch.no_grad()
    def __call__(self, obs: torch.Tensor, which: torch.Tensor) -> torch.Tensor | tuple[torch.Tensor, torch.Tensor]:
        """Logits (discrete) or ``(loc, scale)`` (Box) for every row of ``obs`` [n, obs_dim], row ``i`` by network
        ``which[i]`` (an index into the models)."""
        x = self.features(obs) if self.features is not None else obs
        if self.normalize:
            x = ((x - self.mean[which]) / self.std[which]).clamp(-NORM_CLIP, NORM_CLIP)
        order = torch.argsort(which, stable=True)
        sorted_which = which[order]
        counts = torch.bincount(sorted_which, minlength=len(self.mean))
        starts = torch.cumsum(counts, 0) - counts
        position = torch.arange(len(which)) - starts[sorted_which]
        padded = x.new_zeros((len(self.mean), int(counts.max()), x.shape[1]))
        padded[sorted_which, position] = x[order]
        last = len(self.weights) - 1
        for k, (weight, bias) in enumerate(zip(self.weights, self.biases)):
            padded = torch.baddbmm(bias, padded, weight)
            if k < last:
                padded = nn.functional.silu(padded)
        out = torch.empty((len(which), padded.shape[2]), dtype=padded.dtype)
        out[order] = padded[sorted_which, position]
        if self.box:
            return out, self.log_std[which].exp()
        return out
