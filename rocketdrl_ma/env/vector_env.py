"""Many games in one process: a ``GameEngine`` of ``n_arenas`` games, with the learner's side of each.

Each game's learner side (a lane: ``LearnerGame``, the code a ``RocketDRLParallelEnv`` runs) parses its actions and,
once the engine has played every game's ticks with one physics step per tick, builds what a PettingZoo step
returns, stacked here into arrays ``[n_arenas, n_agents, ...]``.

Lane ``k`` reset with ``seed`` plays exactly the game a lone env reset with ``seed + k`` plays given the same
actions (same random draws); the physics of an arena in a batch matches a lone arena up to float rounding.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.config import load_config
from rocketdrl_ma.engine import GameEngine
from rocketdrl_ma.physics import CarControls

from .learner_game import LearnerGame, check_seed
from .observations import TeamRelativeObs


class VectorEnv:
    """``n_arenas`` games of one config, batched arrays in and out.

    ``step(actions)`` takes ``[n_arenas, n_agents, *action_shape]`` (agents in ``possible_agents`` order) and returns
    ``obs [n_arenas, n_agents, obs_dim]`` float32, ``rewards [n_arenas, n_agents]`` float32, ``terminated`` and
    ``truncated`` ``[n_arenas]`` bool, and ``infos``: a list with each arena's per-agent infos of this decision.
    ``step(actions, controls)`` lets the cars named in ``controls[k]`` (scripted bots) drive with those
    ``CarControls`` directly; their rows of ``actions`` are not read. With ``autoreset`` (the default) an arena
    whose game ended is reset at once: its row of ``obs`` is the new game's first observation, and ``final_obs``
    keeps the last one of the ended game (``obs`` elsewhere). Without it an ended arena waits for ``reset_arenas``
    and may not be stepped until then.

    ``copy.deepcopy`` and pickling give an independent copy of every arena in its state (one new PyBullet world for
    the copy's batch), as for ``RocketDRLParallelEnv``.
    """

    def __init__(self, config: str | Path | dict | None = "matches/1v1.yaml", n_arenas: int = 16,
                 autoreset: bool = True, **overrides: Any):
        if not isinstance(n_arenas, int) or n_arenas < 1:
            raise ValueError(f"n_arenas: must be an int >= 1, got {n_arenas!r}")
        self.n_arenas = n_arenas
        self.autoreset = autoreset
        self.config = load_config(config, overrides)
        self.engine = GameEngine.from_config(self.config, n_games=n_arenas)
        self.lanes = [LearnerGame(self.config, rules) for rules in self.engine.games]
        first = self.lanes[0]
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

    @property
    def batch(self):
        """The PyBullet world of every arena (the engine's; None before the first reset)."""
        return self.engine.world

    # ------------------------------------------------------------------ episodes
    def reset(self, seed: int | None = None) -> tuple[np.ndarray, list[dict]]:
        """Reset every arena (arena ``k`` with ``seed + k``); returns observations and each arena's infos."""
        seed = check_seed(seed)
        infos = [self._reset_lane(k, None if seed is None else seed + k) for k in range(self.n_arenas)]
        if seed is not None:
            # The lanes have put every car for the new episodes: a new PyBullet world with them (and none of the
            # old one's contact caches) makes a used VectorEnv replay what a new one plays from this seed.
            self.engine.renew_world()
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
        lane = self.lanes[k]
        if seed is not None or self.engine.rngs[k] is None:
            lane.action_space(self.possible_agents[0]).seed(seed)
        obs, infos = lane.start(self.engine.reset_game(k, seed))
        self._obs[k] = [obs[agent] for agent in self.possible_agents]
        self._live[k] = True
        return infos

    def step(self, actions: np.ndarray | None, controls: Sequence[Mapping[str, CarControls]] | None = None):
        if controls is not None and len(controls) != self.n_arenas:
            raise ValueError(f"controls: expected one dict per arena ({self.n_arenas}), got {len(controls)}")
        if actions is not None:
            actions = np.asarray(actions)
            expected = (self.n_arenas, self.n_agents) + self.action_space.shape
            if actions.shape != expected:
                raise ValueError(f"actions: expected shape {expected} (arenas, agents, action), got {actions.shape}")
        if not self._live.all():
            raise ValueError(f"step: the games of arenas {np.flatnonzero(~self._live).tolist()} are over; "
                             "call reset_arenas() for them")
        given = controls or [{}] * self.n_arenas
        played = []
        for k, lane in enumerate(self.lanes):
            row = None if actions is None else {agent: actions[k, j] for j, agent in enumerate(self.possible_agents)
                                                if agent not in given[k]}
            played.append(lane.controls(row, given[k]))
        states = self.engine.step(played)
        rewards = np.zeros((self.n_arenas, self.n_agents), np.float32)
        terminated = np.zeros(self.n_arenas, dtype=bool)
        truncated = np.zeros(self.n_arenas, dtype=bool)
        infos = []
        observe = self._batched_obs is None
        for k, lane in enumerate(self.lanes):
            obs, rew, term, trunc, info = lane.finish(states[k], observe=observe)
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

    # ------------------------------------------------------------------ the rest
    def state(self) -> np.ndarray:
        """``[n_arenas, state_dim]``: each arena's global state vector (``RocketDRLParallelEnv.state``)."""
        return np.stack([lane.state() for lane in self.lanes])

    def close(self) -> None:
        self.engine.close()
