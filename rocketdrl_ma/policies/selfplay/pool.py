"""The self-play env pool: the learner drives one team of every env copy, an opponent the other.

It has the interface of ``ppo.envs.EnvPool`` (rows are the learner's cars only), so the PPO trainer
runs unchanged; the copies are the arenas of one ``VectorEnv``, copy ``i`` seeded with ``seed + i``. At
each episode start a copy swaps the learner's side and draws its opponent: the current policy itself
with probability ``self_play``, else PFSP over the pool (scripted bots and the newest ``pool_size``
snapshots). Opponent policies sample from their Gaussian (or categorical) like the
learner does, so past snapshots are played as the stochastic policies they were.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch
from gymnasium import spaces

from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.policies.ppo.envs import Episode, StepResult
from rocketdrl_ma.policies.ppo.model import PPOModel, env_actions
from rocketdrl_ma.policies.ppo.shaping import potential
from rocketdrl_ma.policies.scripted import make_scripted

from .pfsp import PFSP

SELF = "self"
TEAMS = ("blue", "orange")


@torch.no_grad()
def sample_actions(model: PPOModel, obs: np.ndarray) -> np.ndarray:
    """Env actions sampled from ``model``'s policy for a batch of raw observations."""
    x = model.obs_norm(torch.as_tensor(np.asarray(obs, np.float32)))
    if model.action["kind"] == "box":
        loc, scale = model.policy(x)
        return env_actions(model.action, torch.normal(loc, scale))
    return env_actions(model.action, torch.distributions.Categorical(logits=model.policy(x)).sample())


class SelfPlayPool:
    def __init__(self, cfg: dict[str, Any], run_dir: str | Path):
        self.cfg, self.sp = cfg, cfg["selfplay"]
        overrides = {**cfg["env_overrides"], "info_format": "full"}
        self.vec = VectorEnv(cfg["env"], n_arenas=cfg["n_envs"], autoreset=False, **overrides)
        self.envs = self.vec.lanes
        first = self.envs[0]
        if first.config.get("mode") != "match":
            self.vec.close()
            raise ValueError(f"selfplay: needs a match config with two teams, got mode {first.config.get('mode')!r}")
        self.agents = list(self.vec.possible_agents)
        self.team_agents = {t: [a for a in self.agents if a.startswith(t)] for t in TEAMS}
        # column indices into the VectorEnv's agent axis, per team
        self.team_columns = {t: np.array([self.agents.index(a) for a in self.team_agents[t]]) for t in TEAMS}
        self.team_size = len(self.team_agents["blue"])
        self.n_rows = len(self.envs) * self.team_size
        self.observation_space: spaces.Box = first.observation_space(first.possible_agents[0])
        self.action_space: spaces.Space = first.action_space(first.possible_agents[0])
        self.seed = cfg["seed"]
        self.rng = np.random.default_rng(cfg["seed"])
        self.shaping = dict(cfg["shaping"])
        self.snapshot_dir = Path(run_dir) / "snapshots"
        self.pfsp = PFSP(self.sp["weighting"], self.sp["p"], self.sp["window"])
        self.opponents: dict[str, Any] = {}       # name -> PPOModel or scripted bot
        for bot in self.sp["scripted"]:
            self._add(f"scripted:{bot}", make_scripted(bot))
        kickstart = self.sp["kickstart"]
        # one teacher per copy: a bot may remember the game it is playing
        self.teachers = [make_scripted(kickstart["bot"]) for _ in self.envs] if kickstart else []
        self.learner: PPOModel | None = None
        self.imitation: dict[str, list] = {}  # the warm start's report (imitation.warm_start)
        self.next_snapshot = self.sp["snapshot_interval"]
        self.picks: dict[str, int] = {}
        self._learner_team = ["blue"] * len(self.envs)
        self._opponent = [SELF] * len(self.envs)
        self._playing: list[Any] = [None] * len(self.envs)
        self._obs = np.zeros((len(self.envs), len(self.agents)) + self.observation_space.shape, np.float32)
        self._returns = np.zeros(self.n_rows)
        self._lengths = np.zeros(self.n_rows, dtype=np.int64)
        self._phi = np.zeros(self.n_rows)
        self._episodes = [0] * len(self.envs)

    # ------------------------------------------------------------------ trainer hooks
    def attach(self, model: PPOModel, agent_steps: int) -> None:
        """The learner (also the ``self`` opponent); reloads the newest snapshots of a resumed run, or
        clones the ``imitate`` bot into a fresh learner."""
        self.learner = model
        if agent_steps == 0 and self.sp["imitate"]:  # a fresh run: start from the cloned bot
            from .imitation import warm_start
            self.imitation = warm_start(model, self.cfg, log=print)
        interval = self.sp["snapshot_interval"]
        self.next_snapshot = (agent_steps // interval + 1) * interval
        for path in self.snapshots()[-self.sp["pool_size"]:]:
            self._add_snapshot(path)

    def on_update(self, model: PPOModel, agent_steps: int, writer) -> None:
        """After each PPO update: snapshot the learner when due; log the pool's win rates and picks."""
        if agent_steps >= self.next_snapshot:
            self.snapshot(model, agent_steps)
            self.next_snapshot += self.sp["snapshot_interval"]
        if writer is not None:
            for name, weight in self.pfsp.weights().items():
                writer.add_scalar(f"selfplay/pfsp_weight/{name}", weight, agent_steps)
                writer.add_scalar(f"selfplay/win_rate/{name}", self.pfsp.win_rate(name), agent_steps)
            writer.add_scalar("selfplay/pool_size", len(self.opponents), agent_steps)

    def snapshot(self, model: PPOModel, agent_steps: int) -> Path:
        """Save the learner as a playable checkpoint and put a frozen copy into the pool."""
        from rocketdrl_ma.policies.ppo.checkpoint import save_checkpoint
        from rocketdrl_ma.policies.ppo.trainer import checkpoint_meta

        meta = checkpoint_meta(self.cfg, model, self.observation_space.shape[0], agent_steps, {"snapshot": True})
        path = save_checkpoint(self.snapshot_dir / f"step_{agent_steps}.pt", model, meta)
        self._add_snapshot(path)
        return path

    def snapshots(self) -> list[Path]:
        """Snapshot files of this run, oldest first."""
        return sorted(self.snapshot_dir.glob("step_*[0-9].pt"), key=lambda p: int(p.stem.split("_")[1]))

    # ------------------------------------------------------------------ the opponent pool
    def _add(self, name: str, opponent: Any) -> None:
        self.opponents[name] = opponent
        self.pfsp.add_opponent(name)

    def _add_snapshot(self, path: Path) -> None:
        from rocketdrl_ma.policies.ppo.checkpoint import load_model

        name = f"snapshot:{path.stem.split('_')[1]}"
        if name in self.opponents:
            return
        self._add(name, load_model(path)[0])
        snapshots = [n for n in self.opponents if n.startswith("snapshot:")]
        for old in snapshots[:-self.sp["pool_size"]]:
            del self.opponents[old]
            self.pfsp.remove_opponent(old)

    def pick_opponent(self) -> str:
        if not self.opponents or self.rng.random() < self.sp["self_play"]:
            return SELF
        return self.pfsp.sample(self.rng)

    # ------------------------------------------------------------------ EnvPool interface
    def _rows(self, i: int) -> slice:
        return slice(i * self.team_size, (i + 1) * self.team_size)

    def _learners(self, i: int) -> list[str]:
        return self.team_agents[self._learner_team[i]]

    def _opponent_team(self, i: int) -> str:
        return TEAMS[1 - TEAMS.index(self._learner_team[i])]

    def _start_episode(self, i: int) -> np.ndarray:
        self._episodes[i] += 1  # sides swap every episode of a copy, copies start on alternate sides
        self._learner_team[i] = TEAMS[(i + self._episodes[i]) % 2]
        name = self.pick_opponent()
        self._opponent[i] = name
        # held per copy: a snapshot that leaves the pool mid-episode still finishes the episode
        self._playing[i] = None if name == SELF else self.opponents[name]
        self.picks[name] = self.picks.get(name, 0) + 1
        self._phi[self._rows(i)] = self._potentials(i)
        return self._obs[i, self.team_columns[self._learner_team[i]]]

    def reset(self) -> np.ndarray:
        self._obs[:], _ = self.vec.reset(seed=self.seed)
        self._returns[:] = 0.0
        self._lengths[:] = 0
        return np.concatenate([self._start_episode(i) for i in range(len(self.envs))])

    def _opponent_actions(self, actions: np.ndarray) -> None:
        """Fill the opponents' columns of ``actions`` [copies, agents, ...]: one batched forward per policy."""
        by_model: dict[int, tuple[PPOModel, list[int]]] = {}
        for i, env in enumerate(self.envs):
            opponent = self.learner if self._opponent[i] == SELF else self._playing[i]
            if isinstance(opponent, PPOModel):
                by_model.setdefault(id(opponent), (opponent, []))[1].append(i)
            else:
                side, state = self._opponent_team(i), env.game_state
                for col, agent in zip(self.team_columns[side], self.team_agents[side]):
                    actions[i, col] = env.action_parser.encode(opponent.act(agent, state))
        for model, copies in by_model.values():
            cols = [self.team_columns[self._opponent_team(i)] for i in copies]
            obs = np.concatenate([self._obs[i, c] for i, c in zip(copies, cols)])
            acts = sample_actions(model, obs)
            for n, (i, c) in enumerate(zip(copies, cols)):
                actions[i, c] = acts[n * self.team_size:(n + 1) * self.team_size]

    def teacher_actions(self) -> np.ndarray:
        """The kickstart teacher's action (in the env's action format) for every learner row in its current
        state: the labels of the distillation term (``kickstart.py``)."""
        labels = []
        for i, env in enumerate(self.envs):
            state = env.game_state
            labels += [env.action_parser.encode(self.teachers[i].act(agent, state)) for agent in self._learners(i)]
        return np.asarray(labels)

    def step(self, actions: np.ndarray) -> StepResult:
        learner_actions = np.asarray(actions)
        full = np.zeros((len(self.envs), len(self.agents)) + learner_actions.shape[1:], learner_actions.dtype)
        for i in range(len(self.envs)):
            full[i, self.team_columns[self._learner_team[i]]] = learner_actions[self._rows(i)]
        self._opponent_actions(full)
        obs_all, rewards, term, trunc, infos = self.vec.step(full)
        self._obs[:] = obs_all
        dim = self.observation_space.shape[0]
        obs = np.zeros((self.n_rows, dim), np.float32)
        reward = np.zeros(self.n_rows, np.float32)
        shaping = np.zeros(self.n_rows, np.float32)
        episodes: list[Episode] = []
        ended = term | trunc
        for i in range(len(self.envs)):
            rows, team = self._rows(i), self._learner_team[i]
            obs[rows] = obs_all[i, self.team_columns[team]]
            reward[rows] = rewards[i, self.team_columns[team]]
            if self.shaping:
                phi = np.asarray(self._potentials(i))
                shaping[rows] = phi - self._phi[rows]
                self._phi[rows] = phi
            if ended[i]:
                learners = self._learners(i)
                winner = infos[i][learners[0]].get("summary", {}).get("winner")
                self.pfsp.record(self._opponent[i], 0.5 if winner is None else float(winner == team))
                for k in range(self.team_size):
                    row = rows.start + k
                    episodes.append(Episode(float(self._returns[row] + reward[row]), int(self._lengths[row] + 1),
                                            winner == team, i))
        terminated = np.repeat(term, self.team_size)  # both teams' cars end together
        truncated = np.repeat(trunc & ~term, self.team_size)
        final_obs = obs.copy()
        if ended.any():
            self._obs[:], _ = self.vec.reset_arenas(ended)
            for i in np.flatnonzero(ended):
                obs[self._rows(int(i))] = self._start_episode(int(i))
        done = terminated | truncated
        self._returns = np.where(done, 0.0, self._returns + reward)
        self._lengths = np.where(done, 0, self._lengths + 1)
        return StepResult(obs, reward, shaping, terminated, truncated, final_obs, episodes)

    def _potentials(self, i: int) -> list[float]:
        if not self.shaping:
            return [0.0] * self.team_size
        state = self.envs[i].game_state
        return [potential(agent, state, self.shaping) for agent in self._learners(i)]

    def set_difficulty(self, difficulty: float) -> None:
        raise ValueError("curriculum: self-play trains on a match, which has no difficulty to set")

    def close(self) -> None:
        self.vec.close()
