"""The self-play games of one rollout worker: the learner drives one team of every env copy, an opponent the other.

The copies are the arenas of one ``VectorEnv``; copy ``i`` is seeded ``seed + i`` and rows are the learner's cars
only. Each episode a copy swaps the learner's side (copies start on alternate sides; with ``selfplay.side`` the
learner keeps that team, as the penalty duel's shooter or keeper) and plays one opponent,
named by its index in the learner's opponent table (``pool.py``: 0 the learner itself, then the scripted bots,
then the snapshot slots). Who that is comes from outside at each episode start (``begin_episodes``), so the
choice (PFSP) stays with the learner; the games compute the scripted opponents' and the kickstart teacher's
actions, which need the game state, and take the network opponents' actions as given.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.engine import float32_controls
from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.policies.ppo.config import TrainConfig
from rocketdrl_ma.policies.ppo.envs import Episode, StepResult
from rocketdrl_ma.policies.ppo.shaping import make_shaping
from rocketdrl_ma.policies.registry import load_teacher
from rocketdrl_ma.policies.scripted import make_scripted
from rocketdrl_ma.rules.events import Goal
from rocketdrl_ma.rules.team_metrics import TEAM_LOG_METRICS, team_log_vector

TEAMS = ("blue", "orange")
SELF = 0  # the opponent index of the learner itself


@dataclass
class EpisodeOutcome:
    """A finished episode of one copy, for the learner's PFSP bookkeeping."""

    copy: int
    opponent: int      # index in the opponent table
    generation: int    # the opponent slot's generation when the episode began (snapshot slots are reused)
    points: float      # the learner's team: 1 win, 0.5 draw, 0 loss
    team: list[float]  # the learner's team's TEAM_LOG_METRICS in this match


class SelfPlayGames:
    def __init__(self, cfg: TrainConfig, n_copies: int, first_copy: int = 0):
        self.cfg, self.sp = cfg, cfg.selfplay
        overrides = {**cfg.env_overrides, "info_format": "full"}
        self.vec = VectorEnv(cfg.env, n_games=n_copies, autoreset=False, **overrides)
        self.envs = self.vec.games
        first = self.envs[0]
        self.agents = list(self.vec.possible_agents)
        self.team_agents = {t: [a for a in self.agents if a.startswith(t)] for t in TEAMS}
        if not self.team_agents["blue"] or len(self.team_agents["blue"]) != len(self.team_agents["orange"]):
            self.vec.close()
            raise ValueError("selfplay: needs a game with two teams of the same size (a match, the penalty duel), "
                             f"got mode {first.config.get('mode')!r} with agents {self.agents}")
        self.team_columns = {t: np.array([self.agents.index(a) for a in self.team_agents[t]]) for t in TEAMS}
        self.team_size = len(self.team_agents["blue"])
        self.n_rows = n_copies * self.team_size
        self.observation_space: spaces.Box = first.observation_space(first.possible_agents[0])
        self.action_space: spaces.Space = first.action_space(first.possible_agents[0])
        self.seed = cfg.seed + first_copy
        self.first_copy = first_copy
        self.shaping = [make_shaping(cfg.shaping) for _ in self.envs] if cfg.shaping else []
        # one bot object per copy and name: a bot may remember the game it is playing
        self.scripted = [[make_scripted(bot) for bot in self.sp.scripted] for _ in self.envs]
        kickstart = self.sp.kickstart
        self.teachers = [load_teacher(kickstart.bot) for _ in self.envs] if kickstart else []
        self.learner_team = ["blue"] * len(self.envs)
        self.opponent = [SELF] * len(self.envs)
        self.generation = [0] * len(self.envs)
        self._episodes = [0] * len(self.envs)
        self._obs = np.zeros((len(self.envs), len(self.agents)) + self.observation_space.shape, np.float32)
        self._returns = np.zeros(self.n_rows)
        self._lengths = np.zeros(self.n_rows, dtype=np.int64)

    # ------------------------------------------------------------------ rows and sides
    def rows(self, i: int) -> slice:
        return slice(i * self.team_size, (i + 1) * self.team_size)

    def learners(self, i: int) -> list[str]:
        return self.team_agents[self.learner_team[i]]

    def opponent_team(self, i: int) -> str:
        return TEAMS[1 - TEAMS.index(self.learner_team[i])]

    def learner_obs(self) -> np.ndarray:
        """[rows, obs_dim]: every learner car's observation."""
        return self._team_obs(learner=True)

    def opponent_obs(self) -> np.ndarray:
        """[rows, obs_dim]: the opponent cars' observations, row ``r`` the opponent paired with learner row ``r``."""
        return self._team_obs(learner=False)

    def _team_obs(self, learner: bool) -> np.ndarray:
        # one gather for every copy: each copy's columns of the learner's (or the opponent's) team
        orange = np.fromiter((team == "orange" for team in self.learner_team), bool, len(self.envs)) == learner
        columns = np.where(orange[:, None], self.team_columns["orange"], self.team_columns["blue"])
        return self._obs[np.arange(len(self.envs))[:, None], columns].reshape(self.n_rows, -1)

    def _start_episode(self, i: int) -> None:
        self._episodes[i] += 1
        side = self.sp.side
        self.learner_team[i] = TEAMS[(self.first_copy + i + self._episodes[i]) % 2] if side == "alternate" else side
        self.opponent[i] = SELF
        if self.shaping:
            self.shaping[i].reset(self.learners(i), self.envs[i].game_state)

    def begin_episodes(self, copies: np.ndarray, opponents: np.ndarray, generations: np.ndarray) -> None:
        """The opponent (index, slot generation) each of ``copies`` plays in the episode it has just begun."""
        for i, opponent, generation in zip(copies, opponents, generations):
            self.opponent[int(i)], self.generation[int(i)] = int(opponent), int(generation)

    # ------------------------------------------------------------------ stepping
    def reset(self) -> np.ndarray:
        self._obs[:], _ = self.vec.reset(seed=self.seed)
        self._returns[:] = 0.0
        self._lengths[:] = 0
        for i in range(len(self.envs)):
            self._start_episode(i)
        return self.learner_obs()

    def reset_copies(self, ended: np.ndarray, obs: np.ndarray | None = None) -> np.ndarray:
        """Start the next episode of the copies flagged in ``ended``; every learner row's observation (``obs``,
        the rows' last observations, is not needed: the games hold every car's)."""
        new_obs, _ = self.vec.reset_games(np.asarray(ended, bool))
        for i in np.flatnonzero(ended):
            self._obs[i] = new_obs[i]
            self._start_episode(int(i))
        return self.learner_obs()

    def teacher_actions(self) -> np.ndarray:
        """The kickstart teacher's action (env format) for every learner row in its current state."""
        labels = []
        for i, env in enumerate(self.envs):
            state = env.game_state
            labels += [env.action_parser.encode(self.teachers[i].controls(agent, state)) for agent in self.learners(i)]
        return np.asarray(labels)

    def step(self, learner_actions: np.ndarray,
             opponent_actions: np.ndarray) -> tuple[StepResult, list[EpisodeOutcome], np.ndarray]:
        """One decision. ``opponent_actions`` [rows, ...] are used for copies whose opponent is a network (the
        learner itself or a snapshot); scripted opponents act here. Ended copies keep their final observation
        until ``reset_copies``. Also returns [copies, 2]: goals for and against the learner's team."""
        learner_actions = np.asarray(learner_actions)
        full = np.zeros((len(self.envs), len(self.agents)) + learner_actions.shape[1:], learner_actions.dtype)
        scripted_controls: list[dict] = [{} for _ in self.envs]
        n_scripted = len(self.sp.scripted)
        for i, env in enumerate(self.envs):
            rows, side = self.rows(i), self.opponent_team(i)
            full[i, self.team_columns[self.learner_team[i]]] = learner_actions[rows]
            scripted = self.opponent[i] - 1
            if 0 <= scripted < n_scripted:  # the bot's controls go to the game, at the learner's resolution
                bot, state = self.scripted[i][scripted], env.game_state
                scripted_controls[i] = float32_controls({agent: bot.controls(agent, state)
                                                         for agent in self.team_agents[side]})
            else:
                full[i, self.team_columns[side]] = opponent_actions[rows]
        obs_all, rewards, term, trunc, infos = self.vec.step(full, scripted_controls)
        self._obs[:] = obs_all
        reward = np.zeros(self.n_rows, np.float32)
        shaping = np.zeros(self.n_rows, np.float32)
        episodes: list[Episode] = []
        results: list[EpisodeOutcome] = []
        goals = np.zeros((len(self.envs), 2), np.int64)
        ended = term | trunc
        for i in range(len(self.envs)):
            rows, team = self.rows(i), self.learner_team[i]
            reward[rows] = rewards[i, self.team_columns[team]]
            for event in infos[i][self.learners(i)[0]].get("events", ()):
                if isinstance(event, Goal):
                    goals[i, 0 if event.team == team else 1] += 1
            if self.shaping:
                state = self.envs[i].game_state
                shaping[rows] = [self.shaping[i].get(agent, state)[0] for agent in self.learners(i)]
            if ended[i]:
                summary = infos[i][self.learners(i)[0]].get("summary", {})
                winner = summary.get("winner")
                points = 0.5 if winner is None else float(winner == team)
                metrics = (team_log_vector(summary["team"][team]) if "team" in summary
                           else [float("nan")] * len(TEAM_LOG_METRICS))
                results.append(EpisodeOutcome(i, self.opponent[i], self.generation[i], points, metrics))
                for k in range(self.team_size):
                    row = rows.start + k
                    episodes.append(Episode(float(self._returns[row] + reward[row]), int(self._lengths[row] + 1),
                                            winner == team, i))
        terminated = np.repeat(term, self.team_size)  # both teams' cars end together
        truncated = np.repeat(trunc & ~term, self.team_size)
        obs = self.learner_obs()
        done = terminated | truncated
        self._returns = np.where(done, 0.0, self._returns + reward)
        self._lengths = np.where(done, 0, self._lengths + 1)
        return StepResult(obs, reward, shaping, terminated, truncated, obs, episodes), results, goals

    def close(self) -> None:
        self.vec.close()
