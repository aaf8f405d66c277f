"""A warm start for self-play: behaviour cloning of a scripted bot, then DAgger, before the first PPO update.

From scratch, a 1v1 learner spends millions of steps learning to reach the ball; cloning the
ball-chaser first (as AlphaStar started from supervised play) gives it a competent opponent-level
policy to improve on. The bot plays env matches (``imitate.opponent`` on the other side), its
observations and controls (encoded in the env's action format) are recorded, the observation
normaliser is fitted to them, and the policy is fitted to the bot's actions: the Gaussian mean by
squared error, the lookup table's logits by cross-entropy.

A clone trained only on the bot's own states drifts into states the bot never visits and does not know
what to do there. DAgger (Ross et al., 2011) fixes that: each round the clone drives (the bot takes over
a decision with probability 1/2, 1/4, ... in rounds 1, 2, ...), every state it visits is labelled with
what the bot would have done, and the policy is refitted on everything gathered so far. Only the policy
is cloned; the value function is learned by PPO as usual.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import torch

from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.policies.ppo.config import TrainConfig
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.policies.registry import load_teacher

from .config import ImitateConfig

DAGGER_EPOCHS = 15  # refit passes over the aggregate after each round (it only grows by a fraction)


def collect(config: str, overrides: dict, bot: str, opponent: str, decisions: int, seed: int,
            model: PPOModel | None = None, bot_share: float = 1.0,
            side: str = "alternate") -> tuple[np.ndarray, np.ndarray]:
    """(observations, actions of ``bot``) over ``decisions`` env decisions, the recorded car on alternating
    sides (``side``: always that team, as a learner with ``selfplay.side`` plays). Without ``model`` the bot drives and a mirror match (``opponent == bot``) records both cars;
    with it (DAgger) ``model`` drives greedily, the bot in its stead with probability ``bot_share`` per
    decision, and the bot's action is recorded as the label of every state. A game with one team (a
    minigame's shooter) has no sides: the bot plays, and is recorded for, every car of every episode."""
    env = RocketDRLParallelEnv(config, **overrides)
    player, other = load_teacher(bot), load_teacher(opponent)
    rng = np.random.default_rng(seed)
    one_team = len({agent.rpartition("_")[0] for agent in env.possible_agents}) == 1
    sides = ("blue", "orange") if side == "alternate" else (side,)
    obs_rows, act_rows = [], []
    episode = 0
    obs, _ = env.reset(seed=seed)
    try:
        for _ in range(decisions):
            state = env.game_state
            recorded = sides[episode % len(sides)]
            actions = {}
            for agent in env.agents:
                mine = one_team or agent.startswith(recorded) or (model is None and opponent == bot)
                label = env.action_parser.encode((player if mine else other).controls(agent, state))
                actions[agent] = label
                if mine:
                    obs_rows.append(obs[agent])
                    act_rows.append(label)
                    if model is not None and rng.random() >= bot_share:
                        actions[agent] = model.act_deterministic(obs[agent][None])[0]
            obs, _, _, _, _ = env.step(actions)
            if not env.agents:
                episode += 1
                obs, _ = env.reset()
    finally:
        env.close()
    dtype = np.float32 if np.ndim(act_rows[0]) else np.int64
    return np.asarray(obs_rows, np.float32), np.asarray(act_rows, dtype)


def imitation_loss(model: PPOModel, x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """How far the policy is from the bot's actions ``y`` on normalised inputs ``x``."""
    if model.action["kind"] == "box":
        return torch.nn.functional.mse_loss(model.policy(x)[0], y)
    return torch.nn.functional.cross_entropy(model.policy(x), y)


def clone(model: PPOModel, obs: np.ndarray, actions: np.ndarray, epochs: int, batch_size: int = 512,
          learning_rate: float = 1e-3, seed: int = 0, fit_normaliser: bool = True) -> list[float]:
    """Fit ``model``'s policy (and, unless told not to, its normaliser first) to (obs, actions); the
    mean loss of each epoch (squared error for a Box policy, cross-entropy for a lookup table)."""
    generator = torch.Generator().manual_seed(seed)
    x_raw, y = torch.as_tensor(obs), torch.as_tensor(actions)
    if fit_normaliser:
        model.obs_norm.update(x_raw)
    optimizer = torch.optim.Adam(model.policy.parameters(), lr=learning_rate)
    losses = []
    for _ in range(epochs):
        total, batches = 0.0, 0
        for idx in torch.randperm(len(x_raw), generator=generator).split(batch_size):
            loss = imitation_loss(model, model.obs_norm(x_raw[idx]), y[idx])
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            total, batches = total + loss.item(), batches + 1
        losses.append(total / batches)
    return losses


def disagreement(model: PPOModel, obs: np.ndarray, actions: np.ndarray) -> float:
    """How far the greedy clone is from the bot on these states: the share of differing lookup indices,
    or the mean squared difference of Box actions."""
    greedy = model.act_deterministic(obs)
    if model.action["kind"] == "box":
        return float(np.mean((greedy - actions) ** 2))
    return float(np.mean(greedy != actions))


def warm_start(model: PPOModel, cfg: TrainConfig, log: Callable[[str], None] | None = None,
               spec: ImitateConfig | None = None) -> dict[str, list]:
    """Clone ``spec`` (default ``cfg.selfplay.imitate``) into ``model`` on the training env config, then run its
    DAgger rounds. Returns the first fit's epoch losses and, per round, the clone's disagreement with the bot on
    the states it visited itself (measured before that round's refit)."""
    spec, seed = spec if spec is not None else cfg.selfplay.imitate, cfg.seed
    side = cfg.selfplay.side if cfg.selfplay else "alternate"
    obs, actions = collect(cfg.env, cfg.env_overrides, spec.bot, spec.opponent, spec.decisions, seed, side=side)
    losses = clone(model, obs, actions, spec.epochs, seed=seed)
    if log:
        log(f"imitation: cloned {spec.bot} on {len(obs):,} samples, loss {losses[0]:.3f} -> {losses[-1]:.3f}")
    rounds = []
    for k in range(spec.dagger_rounds):
        bot_share = 0.5 ** (k + 1)
        new_obs, new_actions = collect(cfg.env, cfg.env_overrides, spec.bot, spec.opponent, spec.dagger_decisions,
                                       seed + 1 + k, model, bot_share, side)
        rounds.append(disagreement(model, new_obs, new_actions))
        obs, actions = np.concatenate([obs, new_obs]), np.concatenate([actions, new_actions])
        clone(model, obs, actions, DAGGER_EPOCHS, seed=seed + 1 + k, fit_normaliser=False)
        if log:
            log(f"imitation: DAgger round {k + 1}: disagreement on its own states {rounds[-1]:.3f}, "
                f"refitted on {len(obs):,} samples")
    return {"losses": losses, "dagger_disagreement": rounds}
