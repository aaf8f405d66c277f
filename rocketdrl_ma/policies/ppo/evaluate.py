"""Greedy evaluation of a checkpoint on the env config it was trained on."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from .checkpoint import load_model
from .envs import EnvPool


@dataclass
class EvalResult:
    episodes: int
    success_rate: float
    mean_return: float
    mean_length: float


def evaluate(checkpoint: str | Path, episodes: int, seed: int = 10_000, n_envs: int = 4,
             overrides: dict | None = None) -> EvalResult:
    """Play greedy episodes of every agent until ``episodes`` have finished (seeds apart from training's)."""
    if episodes < 1:
        raise ValueError(f"episodes: must be >= 1, got {episodes}")
    torch.set_num_threads(1)
    model, meta = load_model(checkpoint)
    env = meta["env"]
    pool = EnvPool(env["config"], n_envs, seed, {**env["overrides"], **(overrides or {})})
    # Each copy plays a fixed quota of its first episodes: keeping whichever episodes end first would favour
    # short ones, and in a minigame a goal ends an episode sooner than a timeout.
    quota = [episodes // n_envs + (copy < episodes % n_envs) for copy in range(n_envs)]
    finished: list = []
    obs = pool.reset()
    while any(quota):
        step = pool.step(model.act_deterministic(obs))
        obs = step.obs
        for episode in step.episodes:
            if quota[episode.copy]:
                quota[episode.copy] -= 1
                finished.append(episode)
    pool.close()
    return EvalResult(len(finished), float(np.mean([e.success for e in finished])),
                      float(np.mean([e.agent_return for e in finished])),
                      float(np.mean([e.length for e in finished])))
