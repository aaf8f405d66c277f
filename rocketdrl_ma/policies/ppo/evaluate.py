"""Greedy evaluation of a checkpoint on the env config it was trained on, alone or against an opponent policy."""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np
import torch

from rocketdrl_ma.engine import float32_controls
from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.policies.base import Policy

from .batched import cars_controls, seat, seat_factory
from .checkpoint import ModelPolicy, load_model
from .envs import EnvPool, episode_outcomes

TEAMS = ("blue", "orange")


@dataclass
class EvalResult:
    episodes: int
    success_rate: float
    mean_return: float
    mean_length: float
    #: how the episodes ended, most frequent first: a minigame's rounds (``goal`` or the miss reason), a match's
    #: ``win`` / ``draw`` / ``loss`` (the evaluated team's, against an opponent)
    outcomes: dict[str, int] = field(default_factory=dict)

    def outcomes_text(self) -> str:
        """``goal 116, wide 39, timeout 27`` (empty without outcomes)."""
        return ", ".join(f"{name} {count}" for name, count in self.outcomes.items())


def count_outcomes(outcomes: Iterable[tuple[str, ...]]) -> dict[str, int]:
    """Counts of an iterable of outcome tuples, most frequent first (ties by name)."""
    counts = Counter(name for episode in outcomes for name in episode)
    return dict(sorted(counts.items(), key=lambda item: (-item[1], item[0])))


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
                      float(np.mean([e.length for e in finished])), count_outcomes(e.outcomes for e in finished))


def evaluate_against(checkpoint: str | Path, opponent: str, episodes: int, seed: int = 10_000, n_envs: int = 4,
                     side: str | None = None, overrides: dict | None = None) -> EvalResult:
    """Greedy episodes of the checkpoint's env with the checkpoint on ``side`` and ``opponent`` (a policy spec,
    ``scripted:goalie`` or ``checkpoint:PATH``) on the other team; success is the checkpoint's team winning (the
    shooter's goal, the keeper's save). ``side`` defaults to the team the checkpoint trained on
    (``selfplay.side``), else blue. The episodes are those ``evaluate`` plays with the same seed and ``n_envs``."""
    if episodes < 1:
        raise ValueError(f"episodes: must be >= 1, got {episodes}")
    torch.set_num_threads(1)
    model, meta = load_model(checkpoint)
    trained_side = (meta["train"].get("selfplay") or {}).get("side")
    side = side or (trained_side if trained_side in TEAMS else "blue")
    env_meta = meta["env"]
    template = ModelPolicy(model, env_meta["resolved"], f"checkpoint:{checkpoint}")
    return play_against(env_meta["config"], {**env_meta["overrides"], **(overrides or {})}, side,
                        lambda: seat(template), seat_factory(opponent), episodes, seed, n_envs)


def evaluate_policy(policy: str, config: str, episodes: int, seed: int = 10_000, n_envs: int = 4,
                    opponent: str | None = None, side: str = "blue", overrides: dict | None = None) -> EvalResult:
    """``policy`` (a spec: ``scripted:aerial_shooter``, ``checkpoint:PATH``) played on ``config``'s env: how a scripted
    bot, which carries no env of its own as a checkpoint does, is scored (a teacher's own figure). The episodes are
    those ``evaluate`` plays with the same seed and ``n_envs``; ``opponent`` (a spec) drives the other team's cars,
    if the env has one."""
    player = seat_factory(policy)  # a bad spec fails here, before any env is built
    return play_against(config, overrides or {}, side, player, None if opponent is None else seat_factory(opponent),
                        episodes, seed, n_envs)


def play_against(config: str | dict, overrides: dict, side: str, player: Callable[[], Policy],
                 opponent: Callable[[], Policy] | None, episodes: int, seed: int = 10_000,
                 n_envs: int = 4) -> EvalResult:
    """Episodes with ``player()`` driving every car of ``side`` and ``opponent()`` the others (one instance per
    car; None for a game with one team, as the shooting minigames without a keeper); success is ``side``
    winning (a minigame's: more goals than misses), the return that of ``side``'s cars.

    Every car is a ``Policy`` acting through its own observation builder and action parser, as in a league match,
    and its controls go to the game as they are (at float32 resolution, ``engine.float32_controls``), so a policy
    trained with other sensors or actions (the seed's) plays as it learned. The cars of policies sharing one model
    (``batched.seat``) go through one forward of it per decision, each with the action its own forward gives. Each of the ``n_envs``
    copies (seeded ``seed + i``) plays a fixed quota of its first episodes, so short episodes are not favoured."""
    if side not in TEAMS:
        raise ValueError(f"side: expected one of {list(TEAMS)}, got {side!r}")
    if episodes < 1:
        raise ValueError(f"episodes: must be >= 1, got {episodes}")
    vec = VectorEnv(config, n_games=n_envs, autoreset=False,
                    **{**overrides, "info_format": "full"})
    try:
        mine = [a for a in vec.possible_agents if a.startswith(side)]
        theirs = [a for a in vec.possible_agents if a not in mine]
        if not mine:
            raise ValueError(f"side: {config} has no {side} cars ({vec.possible_agents})")
        if not theirs and opponent is not None:
            raise ValueError(f"opponent: {config} has no team but {side}'s ({vec.possible_agents}): "
                             "nobody for the opponent to play")
        if theirs and opponent is None:
            raise ValueError(f"opponent: {config} has cars on the other team ({theirs}): name a policy to drive them")
        players: list[dict[str, Policy]] = [{**{a: player() for a in mine}, **{a: opponent() for a in theirs}}
                                            for _ in range(n_envs)]
        quota = [episodes // n_envs + (copy < episodes % n_envs) for copy in range(n_envs)]
        finished: list[tuple[bool, float, int]] = []
        outcomes: list[tuple[str, ...]] = []
        vec.reset(seed=seed)
        _begin(vec, players, range(n_envs))
        returns, lengths = np.zeros(n_envs), np.zeros(n_envs, np.int64)
        columns = [vec.possible_agents.index(a) for a in mine]
        while any(quota):
            controls = cars_controls([(players[k][a], a, lane.game_state) for k, lane in enumerate(vec.games)
                                      for a in vec.possible_agents])
            n_agents = len(vec.possible_agents)
            _, rewards, terminated, truncated, infos = vec.step(None, [
                float32_controls(dict(zip(vec.possible_agents, controls[k * n_agents:(k + 1) * n_agents])))
                for k in range(n_envs)])
            returns += rewards[:, columns].mean(axis=1)
            lengths += 1
            ended = terminated | truncated
            for k in np.flatnonzero(ended):
                if quota[k]:
                    quota[k] -= 1
                    winner = infos[k][mine[0]].get("summary", {}).get("winner")
                    finished.append((winner == side, float(returns[k]), int(lengths[k])))
                    outcomes.append(episode_outcomes(mine[0], infos[k][mine[0]]))
            if ended.any():
                vec.reset_games(ended)
                _begin(vec, players, np.flatnonzero(ended))
                returns[ended], lengths[ended] = 0.0, 0
    finally:
        vec.close()
    success, ret, length = (np.array(column, float) for column in zip(*finished))
    return EvalResult(len(finished), float(success.mean()), float(ret.mean()), float(length.mean()),
                      count_outcomes(outcomes))


def _begin(vec: VectorEnv, players: list[dict[str, Policy]], copies) -> None:
    for k in copies:
        state = vec.games[int(k)].game_state
        for policy in players[int(k)].values():
            policy.reset(state)
