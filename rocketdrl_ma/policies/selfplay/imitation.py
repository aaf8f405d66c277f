"""A warm start for self-play: behaviour cloning of a scripted bot before the first PPO update.

From scratch, a 1v1 learner spends millions of steps learning to reach the ball; cloning the
ball-chaser first (as AlphaStar started from supervised play) gives it a competent opponent-level
policy to improve on. The bot plays env matches (``imitate.opponent`` on the other side), its
observations and controls (encoded in the env's action format) are recorded, the observation
normaliser is fitted to them, and the policy mean is regressed onto the bot's actions. Only the
policy is cloned; the value function is learned by PPO as usual. Box action spaces only.
"""
from __future__ import annotations

from typing import Any

import numpy as np
import torch

from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.policies.scripted import make_scripted

IMITATE_KEYS = {"bot": "ball_chaser", "opponent": "ball_chaser", "decisions": 30_000, "epochs": 20}


def check_imitate(section: object) -> dict[str, Any]:
    """The ``selfplay.imitate`` mapping with defaults; empty: no warm start."""
    from rocketdrl_ma.policies.scripted import SCRIPTED_BOTS

    if not isinstance(section, dict):
        raise ValueError(f"selfplay.imitate: expected a mapping with {sorted(IMITATE_KEYS)}, got {section!r}")
    if not section:
        return {}
    unknown = sorted(set(section) - set(IMITATE_KEYS))
    if unknown:
        raise ValueError(f"selfplay.imitate: unknown key(s) {unknown}; allowed: {sorted(IMITATE_KEYS)}")
    out = {**IMITATE_KEYS, **section}
    for key in ("bot", "opponent"):
        if out[key] not in SCRIPTED_BOTS:
            raise ValueError(f"selfplay.imitate.{key}: {out[key]!r} is not one of {sorted(SCRIPTED_BOTS)}")
    for key in ("decisions", "epochs"):
        if isinstance(out[key], bool) or not isinstance(out[key], int) or out[key] < 1:
            raise ValueError(f"selfplay.imitate.{key}: expected an int >= 1, got {out[key]!r}")
    return out


def collect(config: str, overrides: dict, bot: str, opponent: str, decisions: int,
            seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(observations, actions) of ``bot`` over ``decisions`` env decisions, playing both sides in turn
    (one sample per decision, two in a mirror match)."""
    env = RocketDRLParallelEnv(config, **overrides)
    player, other = make_scripted(bot), make_scripted(opponent)
    obs_rows, act_rows = [], []
    episode = 0
    obs, _ = env.reset(seed=seed)
    try:
        for _ in range(decisions):
            state = env.game_state
            side = ("blue", "orange")[episode % 2]
            actions = {}
            for agent in env.agents:
                mine = agent.startswith(side) or opponent == bot  # a mirror match records both cars
                act = env.action_parser.encode((player if mine else other).act(agent, state))
                actions[agent] = act
                if mine:
                    obs_rows.append(obs[agent])
                    act_rows.append(act)
            obs, _, _, _, _ = env.step(actions)
            if not env.agents:
                episode += 1
                obs, _ = env.reset()
    finally:
        env.close()
    return np.asarray(obs_rows, np.float32), np.asarray(act_rows, np.float32)


def clone(model: PPOModel, obs: np.ndarray, actions: np.ndarray, epochs: int, batch_size: int = 512,
          learning_rate: float = 1e-3, seed: int = 0) -> list[float]:
    """Fit ``model``'s normaliser and policy mean to (obs, actions); the mean squared error of each epoch."""
    if model.action["kind"] != "box":
        raise ValueError("selfplay.imitate: behaviour cloning needs a Box action space (the continuous parser)")
    generator = torch.Generator().manual_seed(seed)
    x_raw, y = torch.as_tensor(obs), torch.as_tensor(actions)
    model.obs_norm.update(x_raw)
    optimizer = torch.optim.Adam(model.policy.parameters(), lr=learning_rate)
    losses = []
    for _ in range(epochs):
        total, batches = 0.0, 0
        for idx in torch.randperm(len(x_raw), generator=generator).split(batch_size):
            loc, _ = model.policy(model.obs_norm(x_raw[idx]))
            loss = torch.nn.functional.mse_loss(loc, y[idx])
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total, batches = total + loss.item(), batches + 1
        losses.append(total / batches)
    return losses


def warm_start(model: PPOModel, cfg: dict[str, Any]) -> list[float]:
    """Clone ``cfg["selfplay"]["imitate"]`` into ``model`` on the training env config."""
    spec = cfg["selfplay"]["imitate"]
    obs, actions = collect(cfg["env"], cfg["env_overrides"], spec["bot"], spec["opponent"], spec["decisions"],
                           cfg["seed"])
    return clone(model, obs, actions, spec["epochs"], seed=cfg["seed"])
