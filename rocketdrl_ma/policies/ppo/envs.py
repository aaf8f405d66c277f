"""Many env copies as one batch of rows for the trainer: every agent of every copy is a row.

The copies are the arenas of one ``VectorEnv`` (one PyBullet world stepped once per tick for all of them); each is
the PettingZoo env's own game, copy ``i`` seeded with ``seed + i``.

All agents share one policy (for a match that is self-play against itself). ``step`` reports the finished
episodes (return, length, success) and the final observation of every row whose episode ended; with
``autoreset`` (the default) a copy that ends is reset at once and its rows carry the next episode's first
observation, without it the rows keep their final observation until ``reset_copies`` (what a torchrl env's
partial reset needs, ``rollout.py``). With ``shaping`` weights the pool also returns the potential-based
shaping term of each row (``shaping.py``); with a ``teacher`` (a scripted bot or a policy spec), ``teacher_actions``
labels every row's current state with the bot's action (kickstarting, ``policies/ppo/selfplay/kickstart.py``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.env.learner_game import LearnerGame
from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.policies.registry import load_teacher
from rocketdrl_ma.rules.state import TEAM_NAMES, agent_team

from .shaping import make_shaping


@dataclass
class Episode:
    """One agent's finished episode."""

    agent_return: float
    length: int
    success: bool
    copy: int  # the env copy that played it
    outcomes: tuple[str, ...] = ()  # how it ended (``episode_outcomes``); empty where only the numbers travel


def episode_success(agent: str, info: dict) -> bool:
    """A minigame's ``is_success``; in a match, the agent's team won."""
    summary = info.get("summary", {})
    if "is_success" in summary:
        return bool(summary["is_success"])
    if "is_success" in info:
        return bool(info["is_success"])
    return summary.get("winner") == TEAM_NAMES[agent_team(agent)]


def episode_outcomes(agent: str, info: dict) -> tuple[str, ...]:
    """How an episode ended, for counting: a minigame's rounds in order, each ``goal`` or its miss reason
    (``wide``, ``timeout``, ``ball_on_ground``...); a match's ``win``, ``loss`` or ``draw`` for ``agent``'s team;
    ``unfinished`` when the final info has no summary (an episode cut off before its rules ended it)."""
    summary = info.get("summary")
    if not summary:
        return ("unfinished",)
    if "results" in summary:
        return tuple(r["reason"] or r["outcome"] for r in summary["results"]) or ("unfinished",)
    winner = summary.get("winner")
    return ("draw",) if winner is None else ("win",) if winner == TEAM_NAMES[agent_team(agent)] else ("loss",)


@dataclass
class StepResult:
    obs: np.ndarray            # [rows, obs_dim] observations to act on next (after any reset)
    reward: np.ndarray         # [rows] the env's reward
    shaping: np.ndarray        # [rows] phi(s') - phi(s); zeros without shaping weights
    terminated: np.ndarray     # [rows] bool: the episode reached its end (no bootstrap)
    truncated: np.ndarray      # [rows] bool: cut off by a time limit (bootstrap from final_obs)
    final_obs: np.ndarray      # [rows, obs_dim]: the last observation of rows that ended, else obs
    episodes: list[Episode]


class EnvPool:
    """``n_envs`` copies of a PettingZoo env, stepped together as the arenas of one ``VectorEnv``."""

    def __init__(self, config: str | dict, n_envs: int, seed: int, overrides: dict | None = None,
                 shaping: dict[str, float] | None = None, autoreset: bool = True, teacher: str | None = None):
        overrides = {**(overrides or {}), "info_format": "full"}
        self.vec = VectorEnv(config, n_games=n_envs, autoreset=False, **overrides)
        self.envs: list[LearnerGame] = self.vec.games
        first = self.envs[0]
        self.agents = list(first.possible_agents)
        self.n_rows = n_envs * len(self.agents)
        self.observation_space: spaces.Box = first.observation_space(self.agents[0])
        self.action_space: spaces.Space = first.action_space(self.agents[0])
        self.seed = seed
        self._returns = np.zeros(self.n_rows)
        self._lengths = np.zeros(self.n_rows, dtype=np.int64)
        self.shaping = [make_shaping(shaping) for _ in self.envs] if shaping else []
        self.autoreset = autoreset
        # one teacher per copy: a bot may remember the game it is playing
        self.teachers = [load_teacher(teacher) for _ in self.envs] if teacher else []

    def _rows(self, i: int) -> slice:
        return slice(i * len(self.agents), (i + 1) * len(self.agents))

    def reset(self) -> np.ndarray:
        obs, _ = self.vec.reset(seed=self.seed)
        for i in range(len(self.envs)):
            self._reset_shaping(i)
        self._returns[:] = 0.0
        self._lengths[:] = 0
        return obs.reshape(self.n_rows, -1)

    def step(self, actions: np.ndarray) -> StepResult:
        n_agents = len(self.agents)
        actions = np.asarray(actions)
        obs, reward, term, trunc, infos = self.vec.step(
            actions.reshape((len(self.envs), n_agents) + actions.shape[1:]))
        obs = obs.reshape(self.n_rows, -1)
        reward = reward.reshape(-1)
        terminated = np.repeat(term, n_agents)  # every agent of a copy ends together
        truncated = np.repeat(trunc & ~term, n_agents)
        final_obs = np.zeros_like(obs)
        shaping = np.zeros(self.n_rows, np.float32)
        for i, terms in enumerate(self.shaping):
            state = self.envs[i].game_state
            shaping[self._rows(i)] = [terms.get(agent, state)[0] for agent in self.agents]
        episodes: list[Episode] = []
        ended = term | trunc
        for i in np.flatnonzero(ended):
            rows = self._rows(int(i))
            final_obs[rows] = obs[rows]
            for k, agent in enumerate(self.agents):
                row = rows.start + k
                episodes.append(Episode(float(self._returns[row] + reward[row]), int(self._lengths[row] + 1),
                                        episode_success(agent, infos[i][agent]), int(i),
                                        episode_outcomes(agent, infos[i][agent])))
        if self.autoreset and ended.any():
            obs = self._reset_ended(obs, ended)
        done = terminated | truncated
        self._returns = np.where(done, 0.0, self._returns + reward)
        self._lengths = np.where(done, 0, self._lengths + 1)
        return StepResult(obs, reward, shaping, terminated, truncated, final_obs, episodes)

    def reset_copies(self, ended: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """Start the next episode of the copies flagged in ``ended`` [copies]; ``obs`` [rows, obs_dim] with
        those copies' rows replaced by their first observation."""
        return self._reset_ended(np.array(obs, copy=True), np.asarray(ended, bool))

    def _reset_ended(self, obs: np.ndarray, ended: np.ndarray) -> np.ndarray:
        new_obs, _ = self.vec.reset_games(ended)
        for i in np.flatnonzero(ended):
            rows = self._rows(int(i))
            obs[rows] = new_obs[i]
            self._reset_shaping(int(i))
        return obs

    def _reset_shaping(self, i: int) -> None:
        if self.shaping:
            self.shaping[i].reset(self.agents, self.envs[i].game_state)

    def teacher_actions(self) -> np.ndarray:
        """The teacher's action (in the env's action format) for every row in its current state."""
        return np.asarray([env.action_parser.encode(self.teachers[i].controls(agent, env.game_state))
                           for i, env in enumerate(self.envs) for agent in self.agents])

    def set_difficulty(self, difficulty: float) -> None:
        """A minigame's difficulty knob in [0, 1] (from each copy's next round)."""
        for env in self.envs:
            if not hasattr(env.rules, "set_difficulty"):
                raise ValueError(f"curriculum: game mode {env.config['mode']!r} has no difficulty to set")
            env.rules.set_difficulty(difficulty)

    def close(self) -> None:
        self.vec.close()
