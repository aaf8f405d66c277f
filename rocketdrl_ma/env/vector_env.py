"""Many games in one process: every arena of one ``ArenaBatch`` stepped by one PyBullet step per tick.

Each arena is a lane: a ``RocketDRLParallelEnv`` whose rules were handed that arena of the batch, so the rules,
observations, actions, rewards and infos are the PettingZoo env's own code. Per decision the lanes parse their
actions and start the decision, then for every tick each lane sets its controls, the batch steps once, the batch's
events go to the lanes of their arenas, and each lane runs its per-tick logic; the lanes then build what a
PettingZoo step returns, stacked here into arrays ``[n_arenas, n_agents, ...]``.

Lane ``k`` reset with ``seed`` plays exactly the game a lone env reset with ``seed + k`` plays given the same
actions (same random draws); the physics of an arena in a batch matches a lone arena up to float rounding.
"""
from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.physics import Arena, ArenaBatch

from .observations import TeamRelativeObs
from .parallel_env import RocketDRLParallelEnv, check_seed


class VectorEnv:
    """``n_arenas`` games of one config, batched arrays in and out.

    ``step(actions)`` takes ``[n_arenas, n_agents, *action_shape]`` (agents in ``possible_agents`` order) and returns
    ``obs [n_arenas, n_agents, obs_dim]`` float32, ``rewards [n_arenas, n_agents]`` float32, ``terminated`` and
    ``truncated`` ``[n_arenas]`` bool, and ``infos``: a list with each arena's per-agent infos of this decision.
    With ``autoreset`` (the default) an arena whose game ended is reset at once: its row of ``obs`` is the new
    game's first observation, and ``final_obs`` keeps the last one of the ended game (``obs`` elsewhere). Without
    it an ended arena waits for ``reset_arenas`` and may not be stepped until then.

    ``copy.deepcopy`` and pickling give an independent copy of every arena in its state (one new PyBullet world for
    the copy's batch), as for ``RocketDRLParallelEnv``.
    """

    def __init__(self, config: str | Path | dict | None = "matches/1v1.yaml", n_arenas: int = 16,
                 autoreset: bool = True, **overrides: Any):
        if not isinstance(n_arenas, int) or n_arenas < 1:
            raise ValueError(f"n_arenas: must be an int >= 1, got {n_arenas!r}")
        self.n_arenas = n_arenas
        self.autoreset = autoreset
        self.lanes = [RocketDRLParallelEnv(config, **overrides) for _ in range(n_arenas)]
        self.batch = ArenaBatch(n_arenas, arena_shape=self.lanes[0].rules.arena_shape)
        for k, lane in enumerate(self.lanes):
            # A partial of a bound method, not a lambda: the env pickles (copies share nothing with the original)
            lane.rules.arena_factory = functools.partial(self._hand_out_arena, k)
        first = self.lanes[0]
        self.config = first.config
        self.tick_skip = first.tick_skip
        self.possible_agents: list[str] = list(first.possible_agents)
        self.n_agents = len(self.possible_agents)
        self.observation_space: spaces.Box = first.observation_space(self.possible_agents[0])
        self.action_space: spaces.Space = first.action_space(self.possible_agents[0])
        self._obs = np.zeros((n_arenas, self.n_agents) + self.observation_space.shape, np.float32)
        # The team-relative observation (the common one) is built for every lane at once from the batch arrays.
        self._batched_obs = None
        if type(first.obs_builder) is TeamRelativeObs:
            self._batched_obs = first.obs_builder.for_batch(self.possible_agents, first.rules.blue_size,
                                                            first.rules.orange_size)
        self._live = np.zeros(n_arenas, dtype=bool)
        self.final_obs = self._obs.copy()

    def _hand_out_arena(self, k: int, seed: int) -> Arena:
        # The seed a lone env's rules would give ``Arena(seed=...)`` seeds this arena's own random stream.
        self.batch.arena_rngs[k] = np.random.default_rng(seed)
        return self.batch.arenas[k]

    # ------------------------------------------------------------------ episodes
    def reset(self, seed: int | None = None) -> tuple[np.ndarray, list[dict]]:
        """Reset every arena (arena ``k`` with ``seed + k``); returns observations and each arena's infos."""
        seed = check_seed(seed)
        infos = [self._reset_lane(k, None if seed is None else seed + k) for k in range(self.n_arenas)]
        if seed is not None:
            # The lanes have put every car for the new episodes: a new PyBullet world with them (and none of the
            # old one's contact caches) makes a used VectorEnv replay what a new one plays from this seed.
            self.batch.renew_bullet_world()
        return self._obs.copy(), infos

    def reset_arenas(self, mask: np.ndarray, seed: int | None = None) -> tuple[np.ndarray, list[dict | None]]:
        """Reset the arenas where ``mask`` ([n_arenas] bool) is set; returns all observations and the reset
        arenas' infos (None for the others)."""
        seed = check_seed(seed)
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != (self.n_arenas,):
            raise ValueError(f"mask: expected shape ({self.n_arenas},), got {mask.shape}")
        infos = [self._reset_lane(k, None if seed is None else seed + k) if mask[k] else None
                 for k in range(self.n_arenas)]
        return self._obs.copy(), infos

    def _reset_lane(self, k: int, seed: int | None) -> dict:
        obs, infos = self.lanes[k].reset(seed=seed)
        self._obs[k] = [obs[agent] for agent in self.possible_agents]
        self._live[k] = True
        return infos

    def step(self, actions: np.ndarray):
        actions = np.asarray(actions)
        expected = (self.n_arenas, self.n_agents) + self.action_space.shape
        if actions.shape != expected:
            raise ValueError(f"actions: expected shape {expected} (arenas, agents, action), got {actions.shape}")
        if not self._live.all():
            raise ValueError(f"step: the games of arenas {np.flatnonzero(~self._live).tolist()} are over; "
                             "call reset_arenas() for them")
        for k, lane in enumerate(self.lanes):
            row = actions[k]
            controls = lane.decision_controls({agent: row[j] for j, agent in enumerate(self.possible_agents)})
            lane.rules.begin_decision(controls)
        self._run_ticks()
        rewards = np.zeros((self.n_arenas, self.n_agents), np.float32)
        terminated = np.zeros(self.n_arenas, dtype=bool)
        truncated = np.zeros(self.n_arenas, dtype=bool)
        infos = []
        observe = self._batched_obs is None
        for k, lane in enumerate(self.lanes):
            obs, rew, term, trunc, info = lane.end_decision(observe=observe)
            for j, agent in enumerate(self.possible_agents):
                if observe:
                    self._obs[k, j] = obs[agent]
                rewards[k, j] = rew[agent]
            first = self.possible_agents[0]
            terminated[k], truncated[k] = term[first], trunc[first]
            infos.append(info)
        if not observe:
            self._obs[:] = self._all_observations()
        final_obs = self._obs.copy()
        done = terminated | truncated
        self._live &= ~done
        if self.autoreset:
            for k in np.flatnonzero(done):
                self._reset_lane(int(k), None)
        self.final_obs = final_obs
        return self._obs.copy(), rewards, terminated, truncated, infos

    def _all_observations(self) -> np.ndarray:
        """Every lane's observations of its state after this decision, built at once from the batch arrays."""
        states = [lane.game_state for lane in self.lanes]
        car_rows = np.array([[lane.rules.cars[agent].batch_row for agent in self.possible_agents]
                             for lane in self.lanes])
        batched = self._batched_obs.build(self.batch, car_rows, states)
        if batched is None:  # a car is missing from a state: the reference builder, agent by agent
            batched = [[lane.obs_builder.build(agent, state) for agent in self.possible_agents]
                       for lane, state in zip(self.lanes, states)]
        return batched

    def _run_ticks(self) -> None:
        batch, lanes = self.batch, self.lanes
        for _ in range(self.tick_skip):
            for lane in lanes:
                lane.rules.apply_controls()
            batch.step(1)
            for k, lane in enumerate(lanes):
                lane.rules.end_tick(batch.drain_events(k))

    # ------------------------------------------------------------------ the rest
    def state(self) -> np.ndarray:
        """``[n_arenas, state_dim]``: each arena's global state vector (``RocketDRLParallelEnv.state``)."""
        return np.stack([lane.state() for lane in self.lanes])

    def close(self) -> None:
        for lane in self.lanes:
            lane.rules.arena = None  # the batch below owns the PyBullet client
            lane.close()
        self.batch.close()
