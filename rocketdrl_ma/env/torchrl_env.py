"""torchrl's face of the vectorised env: an ``EnvBase`` whose batch is the games of one ``VectorEnv``.

Keys (``n`` games, ``m`` agents in ``possible_agents`` order, all in one group ``agents``):
``("agents", "observation")`` ``[n, m, obs_dim]``, ``("agents", "action")`` ``[n, m, *action_shape]``,
``("next", "agents", "reward")`` ``[n, m, 1]``, ``state`` ``[n, state_dim]`` (the global vector for a
centralised critic), and ``done`` / ``terminated`` / ``truncated`` ``[n, 1]``: every agent of a game ends
together. A game that ended is reset by torchrl's partial reset (``_reset`` mask), as collectors do.

The env pickles (its ``VectorEnv`` copies in its state), so a multi-process collector may be given env objects as
well as factories: each worker steps its own copy.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from .parallel_env import check_seed
from .renamed import renamed_keyword
from .vector_env import VectorEnv

GROUP = "agents"


def _action_spec(space: spaces.Space, shape: tuple[int, int]):
    if isinstance(space, spaces.Box):
        return Bounded(low=torch.as_tensor(np.broadcast_to(space.low, shape + space.shape).copy()),
                       high=torch.as_tensor(np.broadcast_to(space.high, shape + space.shape).copy()),
                       shape=shape + space.shape, dtype=torch.float32)
    if isinstance(space, spaces.Discrete):
        return Categorical(n=int(space.n), shape=shape, dtype=torch.int64)
    raise ValueError(f"action space: {type(space).__name__} has no torchrl spec here; use a Box or Discrete action")


class RocketDRLTorchEnv(EnvBase):
    """``RocketDRLTorchEnv("matches/2v2.yaml", n_games=16, kickoff_countdown_s=0.0)``; keyword overrides as in
    ``rocketdrl_ma.parallel_env`` (``n_arenas``, the old name of ``n_games``, still works with a warning)."""

    def __init__(self, config: str | Path | dict | None = "matches/1v1.yaml", n_games: int = 16,
                 device: str | torch.device = "cpu", **overrides: Any):
        n_games = renamed_keyword("RocketDRLTorchEnv", overrides, "n_arenas", "n_games", n_games)
        self.vec = VectorEnv(config, n_games=n_games, autoreset=False, **overrides)
        super().__init__(batch_size=torch.Size([n_games]), device=device)
        n, m = n_games, self.vec.n_agents
        self.possible_agents = self.vec.possible_agents
        obs_space = self.vec.observation_space
        state_dim = self.vec.games[0].state_space.shape[0]
        self.full_observation_spec = Composite(
            {GROUP: Composite(observation=Bounded(
                low=torch.as_tensor(np.broadcast_to(obs_space.low, (n, m) + obs_space.shape).copy()),
                high=torch.as_tensor(np.broadcast_to(obs_space.high, (n, m) + obs_space.shape).copy()),
                shape=(n, m) + obs_space.shape, dtype=torch.float32), shape=(n, m)),
             "state": Bounded(low=-1.0, high=1.0, shape=(n, state_dim), dtype=torch.float32)},
            shape=(n,))
        self.full_action_spec = Composite(
            {GROUP: Composite(action=_action_spec(self.vec.action_space, (n, m)), shape=(n, m))}, shape=(n,))
        self.full_reward_spec = Composite(
            {GROUP: Composite(reward=Unbounded(shape=(n, m, 1), dtype=torch.float32), shape=(n, m))}, shape=(n,))
        self.full_done_spec = Composite(
            {key: Categorical(n=2, shape=(n, 1), dtype=torch.bool) for key in ("done", "terminated", "truncated")},
            shape=(n,))
        self._next_seed: int | None = None
        self._started = False

    def _set_seed(self, seed: int | None) -> None:
        self._next_seed = check_seed(seed)
        self._started = False  # the next reset restarts every game from this seed

    def _observation(self, obs: np.ndarray) -> dict:
        agents = TensorDict({"observation": torch.as_tensor(obs, device=self.device)}, batch_size=obs.shape[:2],
                            device=self.device)
        return {GROUP: agents, "state": torch.as_tensor(self.vec.state(), device=self.device)}

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        mask = None
        if tensordict is not None and "_reset" in tensordict.keys() and self._started:
            mask = tensordict.get("_reset").reshape(self.batch_size).cpu().numpy()
        if mask is None:
            obs, _ = self.vec.reset(seed=self._next_seed)
            self._next_seed, self._started = None, True
        else:
            obs, _ = self.vec.reset_games(mask)
        n = self.batch_size[0]
        false = torch.zeros((n, 1), dtype=torch.bool, device=self.device)
        return TensorDict({**self._observation(obs), "done": false, "terminated": false.clone(),
                           "truncated": false.clone()}, batch_size=self.batch_size, device=self.device)

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        actions = tensordict.get((GROUP, "action")).detach().cpu().numpy()
        obs, rewards, terminated, truncated, _ = self.vec.step(actions)
        term = torch.as_tensor(terminated, device=self.device).unsqueeze(-1)
        trunc = torch.as_tensor(truncated, device=self.device).unsqueeze(-1)
        out = self._observation(obs)
        out[GROUP].set("reward", torch.as_tensor(rewards, device=self.device).unsqueeze(-1))
        return TensorDict({**out, "done": term | trunc, "terminated": term, "truncated": trunc},
                          batch_size=self.batch_size, device=self.device)

    def close(self, *, raise_if_closed: bool = True) -> None:
        if getattr(self, "vec", None) is not None:
            self.vec.close()
            self.vec = None
        super().close(raise_if_closed=raise_if_closed)
