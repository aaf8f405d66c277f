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
    finished = []
    obs = pool.reset()
    while len(finished) < episodes:
        step = pool.step(model.act_deterministic(obs))
        obs = step.obs
        finished.extend(step.episodes)
    pool.close()
    finished = finished[:episodes]
    return EvalResult(len(finished), float(np.mean([e.success for e in finished])),
                      float(np.mean([e.agent_return for e in finished])),
                      float(np.mean([e.length for e in finished])))
