"""What one rollout worker steps: the learner's rows of its env copies, as numpy arrays (``WorkerGames``, which the lean
loop of ``worker_loop.py`` drives) and as a torchrl ``EnvBase`` over them (``RolloutEnv``, for torchrl's collectors).

Every worker owns ``copies`` env copies (the arenas of one ``VectorEnv``: ``EnvPool``, or ``SelfPlayGames`` with
a ``selfplay`` section), copy ``i`` of worker ``w`` being copy ``w * copies + i`` of the run and seeded
``seed + w * copies + i``, so a copy plays the same game whatever the number of workers. A collector (the lean
loop or torchrl's) drives it like any env: the policy writes ``action`` (and, for what the learner decides, a few
more keys, see ``rollout_policy.py``), a step plays one decision, ended copies are reset (a partial reset).

Keys besides ``observation``/``action``/``reward``/``done``/``terminated``/``truncated`` (all ``[rows]``):

- read from the policy's output each step: ``ctl_difficulty`` (a minigame's curriculum level, NaN: leave it),
  ``ctl_kickstart`` (compute the teacher's labels), and in self-play ``opponent_id`` / ``opponent_generation``
  (whom a copy that has just begun an episode plays) and ``opponent_action`` (the network opponents' actions);
- written for the policy: in self-play ``opponent_observation``, ``opponent_id`` (whom each row plays),
  ``episode_start``, ``opponent_draw`` (one uniform number per copy, drawn here with the worker's seeded
  generator, that the policy turns into an opponent), and ``teacher_action`` with a kickstart teacher
  (``selfplay.kickstart``, or a single-team game's top-level ``kickstart``: one scripted teacher per env copy,
  asked here where the game state is, its labels shipped with the trajectory);
- written for the learner's bookkeeping (what a trajectory batch must carry back): ``env_cpu_s`` (the CPU
  seconds the games took to play this decision, spread evenly over the rows: what the env alone would need,
  from which the learner shows the share of the env's speed it keeps), ``shaping`` (the shaping term), ``episode_end``/``episode_return``/``episode_length``/``episode_success`` on the rows whose episode
  ended, and in self-play, on the first row of a copy, ``match_end``/``match_opponent``/``match_generation``/
  ``match_points`` (PFSP's results), ``match_team`` (the learner team's ``TEAM_LOG_METRICS`` in that match) and
  ``goals_for``/``goals_against``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from rocketdrl_ma.rules.team_metrics import TEAM_LOG_METRICS

from .config import TrainConfig
from .envs import EnvPool


def worker_copies(n_envs: int, n_workers: int) -> int:
    """Env copies per worker: ``n_envs`` split evenly, rounded up (every worker the same batch shape)."""
    return math.ceil(n_envs / max(1, n_workers))


def _action_spec(space: spaces.Space, rows: int):
    if isinstance(space, spaces.Discrete):
        return Categorical(n=int(space.n), shape=(rows,), dtype=torch.int64)
    return Unbounded(shape=(rows,) + space.shape, dtype=torch.float32)  # raw Gaussian samples; clipped here


class WorkerGames:
    """The games of one rollout worker as numpy arrays: ``reset`` and ``step`` return the keys of the module
    docstring (``observation`` and the rest, ``[rows, ...]``), the torchrl env below and the lean worker loop
    (``worker_loop.py``) both drive it."""

    def __init__(self, cfg: TrainConfig, copies: int, worker: int = 0):
        self.cfg, self.worker = cfg, worker
        first_copy = worker * copies
        self.selfplay = cfg.selfplay is not None
        # the kickstart teacher: self-play's (its games label the learner's cars), else a single-team game's
        kickstart = cfg.teacher_kickstart
        if self.selfplay:
            from rocketdrl_ma.policies.ppo.selfplay.games import SelfPlayGames
            self.games = SelfPlayGames(cfg, copies, first_copy)
            self.copy_rows = self.games.team_size
            self.copy_teams = ["learner"] * self.copy_rows  # a copy's rows: the learner's team
        else:
            self.games = EnvPool(cfg.env, copies, cfg.seed + first_copy, cfg.env_overrides, cfg.shaping,
                                 autoreset=False, teacher=kickstart.bot if kickstart else None)
            self.copy_rows = len(self.games.agents)
            self.copy_teams = [agent.rpartition("_")[0] for agent in self.games.agents]  # a copy's rows: every car
        self.copies, self.rows = copies, self.games.n_rows
        self.rng = np.random.default_rng([cfg.seed, worker])
        self.discrete = isinstance(self.games.action_space, spaces.Discrete)
        self.kickstart_configured = kickstart is not None
        self.kickstart_on = self.kickstart_configured
        self.difficulty: float | None = None
        # the clock behind env_cpu_s: the thread's CPU time, a system call each time (the lean loop swaps in a wall
        # clock and scales a batch's figures by its CPU share, worker_loop.py)
        self.env_clock_ns = time.thread_time_ns
        self._obs = np.zeros((self.rows,) + self.games.observation_space.shape, np.float32)
        self._episode_start = np.zeros(self.rows, bool)
        self._draw = np.zeros(self.rows, np.float32)
        self._started = False

    @property
    def observation_space(self) -> spaces.Box:
        return self.games.observation_space

    @property
    def action_space(self) -> spaces.Space:
        return self.games.action_space

    def _begin(self, rows: np.ndarray) -> None:
        """Rows whose episode has just begun: the policy picks their opponent from one draw per copy."""
        self._episode_start[:] = rows
        if self.selfplay:
            per_copy = self.rng.random(self.copies).astype(np.float32)
            self._draw[:] = np.repeat(per_copy, self.copy_rows)

    def reset(self, copies: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Every copy's first observation (``copies`` None, or before the first reset), else a new episode for the
        copies flagged in ``copies`` [copies] (the other rows keep their observation)."""
        if copies is None or not self._started:
            self._obs = self.games.reset()
            self._started = True
            self._begin(np.ones(self.rows, bool))
        else:
            self._obs = self.games.reset_copies(copies, self._obs)
            self._begin(np.repeat(copies, self.copy_rows))
        out = self._observation(self._empty_stats())
        false = np.zeros((self.rows, 1), bool)
        out.update({"done": false, "terminated": false.copy(), "truncated": false.copy()})
        return out

    def step(self, action: np.ndarray, opponent_action: np.ndarray | None = None,
             opponent_id: np.ndarray | None = None, opponent_generation: np.ndarray | None = None,
             ctl_difficulty: float = float("nan"), ctl_kickstart: bool | None = None) -> dict[str, np.ndarray]:
        """One decision of every copy: ``action`` [rows, ...] the policy's raw samples (clipped here), in self-play
        the network opponents' actions and the opponent (id, generation) every row plays; the learner's
        controls (``ctl_*``: NaN / None leave them)."""
        actions = action.astype(np.int64) if self.discrete else np.clip(action, -1.0, 1.0)
        self._apply_controls(ctl_difficulty, ctl_kickstart)
        stats = self._empty_stats()
        cpu_start = self.env_clock_ns()  # CPU, not wall time: a busy machine must not shrink the env's capacity
        if self.selfplay:
            starts = np.flatnonzero(self._episode_start[::self.copy_rows])
            if len(starts):
                first_rows = starts * self.copy_rows
                self.games.begin_episodes(starts, opponent_id[first_rows], opponent_generation[first_rows])
            opponent = opponent_action.astype(np.int64) if self.discrete else np.clip(opponent_action, -1.0, 1.0)
            step, results, goals = self.games.step(actions, opponent)
            first = np.arange(self.copies) * self.copy_rows
            stats["goals_for"][first], stats["goals_against"][first] = goals[:, 0], goals[:, 1]
            for result in results:
                row = result.copy * self.copy_rows
                stats["match_end"][row] = True
                stats["match_opponent"][row] = result.opponent
                stats["match_generation"][row] = result.generation
                stats["match_points"][row] = result.points
                stats["match_team"][row] = result.team
        else:
            step = self.games.step(actions)
        stats["env_cpu_s"][:] = (self.env_clock_ns() - cpu_start) * 1e-9 / self.rows
        self._obs = step.obs
        stats["shaping"][:] = step.shaping
        for episode in step.episodes:
            rows = np.arange(episode.copy * self.copy_rows, (episode.copy + 1) * self.copy_rows)
            row = rows[np.flatnonzero(~stats["episode_end"][rows])[0]]  # one row per agent of the copy
            stats["episode_end"][row] = True
            stats["episode_return"][row] = episode.agent_return
            stats["episode_length"][row] = episode.length
            stats["episode_success"][row] = episode.success
        self._begin(np.zeros(self.rows, bool))
        out = self._observation(stats)
        term = np.asarray(step.terminated, bool)[:, None]
        trunc = np.asarray(step.truncated, bool)[:, None]
        out.update({"reward": np.asarray(step.reward, np.float32)[:, None], "done": term | trunc,
                    "terminated": term, "truncated": trunc})
        return out

    def _apply_controls(self, ctl_difficulty: float, ctl_kickstart: bool | None) -> None:
        if not math.isnan(ctl_difficulty) and ctl_difficulty != self.difficulty:
            self.set_difficulty(ctl_difficulty)
        if ctl_kickstart is not None:
            self.kickstart_on = self.kickstart_configured and ctl_kickstart

    def set_difficulty(self, level: float) -> None:
        """A minigame's difficulty in [0, 1], from each copy's next round."""
        if self.selfplay:
            raise ValueError("curriculum: self-play trains on a match, which has no difficulty to set")
        self.games.set_difficulty(level)
        self.difficulty = level

    def _empty_stats(self) -> dict[str, np.ndarray]:
        r = self.rows
        stats = {"shaping": np.zeros(r, np.float32), "env_cpu_s": np.zeros(r, np.float32),
                 "episode_end": np.zeros(r, bool), "episode_return": np.zeros(r, np.float32),
                 "episode_length": np.zeros(r, np.int64), "episode_success": np.zeros(r, bool)}
        if self.selfplay:
            stats.update({"match_end": np.zeros(r, bool), "match_opponent": np.zeros(r, np.int64),
                          "match_generation": np.zeros(r, np.int64), "match_points": np.zeros(r, np.float32),
                          "match_team": np.zeros((r, len(TEAM_LOG_METRICS)), np.float32),
                          "goals_for": np.zeros(r, np.int64), "goals_against": np.zeros(r, np.int64)})
        return stats

    def _observation(self, stats: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        out = {"observation": np.asarray(self._obs, np.float32), **stats}
        if self.kickstart_configured:
            labels = self.games.teacher_actions() if self.kickstart_on else None
            if labels is None:
                shape = (self.rows,) if self.discrete else (self.rows,) + self.games.action_space.shape
                labels = np.zeros(shape, np.int64 if self.discrete else np.float32)
            out["teacher_action"] = labels
        if self.selfplay:
            out["opponent_observation"] = np.asarray(self.games.opponent_obs(), np.float32)
            out["episode_start"] = self._episode_start.copy()
            out["opponent_id"] = np.repeat(self.games.opponent, self.copy_rows).astype(np.int64)
            out["opponent_draw"] = self._draw.copy()
        return out

    def close(self) -> None:
        if self.games is not None:
            self.games.close()
            self.games = None


class RolloutEnv(EnvBase):
    """``WorkerGames`` as a torchrl env (for torchrl's collectors: ``async`` and Ray workers)."""

    def __init__(self, cfg: TrainConfig, copies: int, worker: int = 0):
        self.core = WorkerGames(cfg, copies, worker)
        self.cfg, self.worker = cfg, worker
        self.copies, self.rows, self.copy_rows = copies, self.core.rows, self.core.copy_rows
        self.copy_teams, self.selfplay, self.discrete = self.core.copy_teams, self.core.selfplay, self.core.discrete
        self.kickstart_configured = self.core.kickstart_configured
        super().__init__(batch_size=torch.Size([self.rows]), device="cpu")
        self._build_specs()

    @property
    def games(self):
        return None if self.core is None else self.core.games

    # ------------------------------------------------------------------ specs
    def _build_specs(self) -> None:
        r, dim = self.rows, self.games.observation_space.shape
        f32, i64, flag = torch.float32, torch.int64, torch.bool
        obs = {"observation": Unbounded(shape=(r,) + dim, dtype=f32), "shaping": Unbounded(shape=(r,), dtype=f32),
               "env_cpu_s": Unbounded(shape=(r,), dtype=f32),
               "episode_end": Categorical(2, shape=(r,), dtype=flag), "episode_return": Unbounded(shape=(r,), dtype=f32),
               "episode_length": Unbounded(shape=(r,), dtype=i64),
               "episode_success": Categorical(2, shape=(r,), dtype=flag)}
        if self.kickstart_configured:
            space = self.games.action_space
            obs["teacher_action"] = (Unbounded(shape=(r,), dtype=i64) if self.discrete
                                     else Unbounded(shape=(r,) + space.shape, dtype=f32))
        if self.selfplay:
            obs.update({"opponent_observation": Unbounded(shape=(r,) + dim, dtype=f32),
                        "episode_start": Categorical(2, shape=(r,), dtype=flag),
                        "opponent_id": Unbounded(shape=(r,), dtype=i64),
                        "opponent_draw": Unbounded(shape=(r,), dtype=f32),
                        "match_end": Categorical(2, shape=(r,), dtype=flag),
                        "match_opponent": Unbounded(shape=(r,), dtype=i64),
                        "match_generation": Unbounded(shape=(r,), dtype=i64),
                        "match_points": Unbounded(shape=(r,), dtype=f32),
                        "match_team": Unbounded(shape=(r, len(TEAM_LOG_METRICS)), dtype=f32),
                        "goals_for": Unbounded(shape=(r,), dtype=i64),
                        "goals_against": Unbounded(shape=(r,), dtype=i64)})
        self.full_observation_spec = Composite(obs, shape=(r,))
        self.full_action_spec = Composite(action=_action_spec(self.games.action_space, r), shape=(r,))
        self.full_reward_spec = Composite(reward=Unbounded(shape=(r, 1), dtype=f32), shape=(r,))
        self.full_done_spec = Composite({k: Categorical(2, shape=(r, 1), dtype=flag)
                                         for k in ("done", "terminated", "truncated")}, shape=(r,))

    @property
    def observation_space(self) -> spaces.Box:
        return self.core.observation_space

    @property
    def action_space(self) -> spaces.Space:
        return self.core.action_space

    # ------------------------------------------------------------------ torchrl
    def _set_seed(self, seed: int | None) -> None:
        """Copies are seeded from the training config (copy ``i``: ``seed + i``), not by the collector."""

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        mask = None
        if tensordict is not None and "_reset" in tensordict.keys():
            mask = tensordict.get("_reset").reshape(self.copies, self.copy_rows).any(-1).cpu().numpy()
        return self._tensordict(self.core.reset(mask))

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        keys = tensordict.keys()
        difficulty = float(tensordict.get("ctl_difficulty")[0]) if "ctl_difficulty" in keys else float("nan")
        kickstart = bool(tensordict.get("ctl_kickstart")[0]) if "ctl_kickstart" in keys else None
        opponent = {}
        if self.selfplay:
            opponent = {name: tensordict.get(name).detach().numpy()
                        for name in ("opponent_action", "opponent_id", "opponent_generation")}
        return self._tensordict(self.core.step(tensordict.get("action").detach().numpy(), ctl_difficulty=difficulty,
                                               ctl_kickstart=kickstart, **opponent))

    def _tensordict(self, arrays: dict[str, np.ndarray]) -> TensorDict:
        return TensorDict({key: torch.as_tensor(value) for key, value in arrays.items()}, batch_size=self.batch_size)

    def set_difficulty(self, level: float) -> None:
        self.core.set_difficulty(level)

    def close(self, *, raise_if_closed: bool = True) -> None:
        if getattr(self, "core", None) is not None:
            self.core.close()
            self.core = None
        super().close(raise_if_closed=raise_if_closed)


@dataclass
class RolloutEnvFactory:
    """A picklable ``create_env_fn`` for torchrl's collectors: worker ``worker`` of ``n_workers``.

    In a worker process (``seed_torch``) it also seeds torch, whose generator samples the policy's actions
    there, and keeps torch to one thread: a worker is one core's worth of work."""

    cfg: TrainConfig
    copies: int
    worker: int = 0
    seed_torch: bool = False

    def __call__(self) -> RolloutEnv:
        if self.seed_torch:
            torch.set_num_threads(1)
            torch.manual_seed(self.cfg.seed * 7919 + self.worker)
        return RolloutEnv(self.cfg, self.copies, self.worker)
