"""Many games in one process: a ``GameEngine`` of ``n_games`` games, with the learner's side of each.

Each game's learner side (``LearnerGame``, the code a ``RocketDRLParallelEnv`` runs) parses its actions and,
once the engine has played every game's ticks with one physics step per tick, builds what a PettingZoo step
returns, stacked here into arrays ``[n_games, n_agents, ...]``.

Game ``k`` reset with ``seed`` plays exactly the game a lone env reset with ``seed + k`` plays given the same
actions (same random draws); the physics of a game in a batch matches a lone game up to float rounding (each game
has its own arena of one shared PyBullet world).
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
from .renamed import renamed_attribute, renamed_keyword


class VectorEnv:
    """``n_games`` games of one config, batched arrays in and out; ``games[k]`` is game ``k``'s ``LearnerGame``.

    ``step(actions)`` takes ``[n_games, n_agents, *action_shape]`` (agents in ``possible_agents`` order) and returns
    ``obs [n_games, n_agents, obs_dim]`` float32, ``rewards [n_games, n_agents]`` float32, ``terminated`` and
    ``truncated`` ``[n_games]`` bool, and ``infos``: a list with each game's per-agent infos of this decision.
    ``step(actions, controls)`` lets the cars named in ``controls[k]`` (scripted bots) drive with those
    ``CarControls`` directly; their rows of ``actions`` are not read. With ``autoreset`` (the default) a game
    that ended is reset at once: its row of ``obs`` is the new game's first observation, and ``final_obs``
    keeps the last one of the ended game (``obs`` elsewhere). Without it an ended game waits for ``reset_games``
    and may not be stepped until then. (``n_arenas``, ``lanes`` and ``reset_arenas``, the old names, still work
    with a DeprecationWarning.)

    ``copy.deepcopy`` and pickling give an independent copy of every game in its state (one new PyBullet world for
    the copy's batch), as for ``RocketDRLParallelEnv``.
    """

    def __init__(self, config: str | Path | dict | None = "matches/1v1.yaml", n_games: int = 16,
                 autoreset: bool = True, **overrides: Any):
        n_games = renamed_keyword("VectorEnv", overrides, "n_arenas", "n_games", n_games)
        if not isinstance(n_games, int) or n_games < 1:
            raise ValueError(f"n_games: must be an int >= 1, got {n_games!r}")
        self.n_games = n_games
        self.autoreset = autoreset
        self.config = load_config(config, overrides)
        self.engine = GameEngine.from_config(self.config, n_games=n_games)
        self.games = [LearnerGame(self.config, rules) for rules in self.engine.games]
        first = self.games[0]
        self.tick_skip = first.tick_skip
        self.possible_agents: list[str] = list(first.possible_agents)
        self.n_agents = len(self.possible_agents)
        self.observation_space: spaces.Box = first.observation_space(self.possible_agents[0])
        self.action_space: spaces.Space = first.action_space(self.possible_agents[0])
        self._obs = np.zeros((n_games, self.n_agents) + self.observation_space.shape, np.float32)
        # The team-relative observation (the common one) is built for every game at once from the batch arrays.
        self._batched_obs = None
        if type(first.obs_builder) is TeamRelativeObs:
            self._batched_obs = first.obs_builder.for_batch(self.possible_agents, first.rules.blue_size,
                                                            first.rules.orange_size)
        self._live = np.zeros(n_games, dtype=bool)
        self.final_obs = self._obs.copy()

    lanes = renamed_attribute("VectorEnv", "lanes", "games")
    n_arenas = renamed_attribute("VectorEnv", "n_arenas", "n_games")
    reset_arenas = renamed_attribute("VectorEnv", "reset_arenas", "reset_games")

    @property
    def batch(self):
        """The PyBullet world of every game (the engine's; None before the first reset)."""
        return self.engine.world

    # ------------------------------------------------------------------ episodes
    def reset(self, seed: int | None = None) -> tuple[np.ndarray, list[dict]]:
        """Reset every game (game ``k`` with ``seed + k``); returns observations and each game's infos."""
        seed = check_seed(seed)
        infos = [self._reset_game(k, None if seed is None else seed + k) for k in range(self.n_games)]
        if seed is not None:
            # The games have put every car for the new episodes: a new PyBullet world with them (and none of the
            # old one's contact caches) makes a used VectorEnv replay what a new one plays from this seed.
            self.engine.renew_world()
        return self._obs.copy(), infos

    def reset_games(self, mask: np.ndarray, seed: int | None = None) -> tuple[np.ndarray, list[dict | None]]:
        """Reset the games where ``mask`` ([n_games] bool) is set; returns all observations and the reset
        games' infos (None for the others)."""
        seed = check_seed(seed)
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != (self.n_games,):
            raise ValueError(f"mask: expected shape ({self.n_games},), got {mask.shape}")
        infos = [self._reset_game(k, None if seed is None else seed + k) if mask[k] else None
                 for k in range(self.n_games)]
        return self._obs.copy(), infos

    def _reset_game(self, k: int, seed: int | None) -> dict:
        game = self.games[k]
        if seed is not None or self.engine.rngs[k] is None:
            game.action_space(self.possible_agents[0]).seed(seed)
        obs, infos = game.start(self.engine.reset_game(k, seed))
        self._obs[k] = [obs[agent] for agent in self.possible_agents]
        self._live[k] = True
        return infos

    def step(self, actions: np.ndarray | None, controls: Sequence[Mapping[str, CarControls]] | None = None):
        if controls is not None and len(controls) != self.n_games:
            raise ValueError(f"controls: expected one dict per game ({self.n_games}), got {len(controls)}")
        if actions is not None:
            actions = np.asarray(actions)
            expected = (self.n_games, self.n_agents) + self.action_space.shape
            if actions.shape != expected:
                raise ValueError(f"actions: expected shape {expected} (games, agents, action), got {actions.shape}")
        if not self._live.all():
            raise ValueError(f"step: the games {np.flatnonzero(~self._live).tolist()} are over; "
                             "call reset_games() for them")
        given = controls or [{}] * self.n_games
        played = []
        for k, game in enumerate(self.games):
            row = None if actions is None else {agent: actions[k, j] for j, agent in enumerate(self.possible_agents)
                                                if agent not in given[k]}
            played.append(game.controls(row, given[k]))
        states = self.engine.step(played)
        rewards = np.zeros((self.n_games, self.n_agents), np.float32)
        terminated = np.zeros(self.n_games, dtype=bool)
        truncated = np.zeros(self.n_games, dtype=bool)
        infos = []
        observe = self._batched_obs is None
        for k, game in enumerate(self.games):
            obs, rew, term, trunc, info = game.finish(states[k], observe=observe)
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
                self._reset_game(int(k), None)
        self.final_obs = final_obs
        return self._obs.copy(), rewards, terminated, truncated, infos

    def _all_observations(self) -> np.ndarray:
        """Every game's observations of its state after this decision, built at once from the batch arrays."""
        states = [game.game_state for game in self.games]
        car_rows = np.array([[game.rules.cars[agent].batch_row for agent in self.possible_agents]
                             for game in self.games])
        batched = self._batched_obs.build(self.batch, car_rows, states)
        if batched is None:  # a car is missing from a state: the reference builder, agent by agent
            batched = [[game.obs_builder.build(agent, state) for agent in self.possible_agents]
                       for game, state in zip(self.games, states)]
        return batched

    # ------------------------------------------------------------------ the rest
    def state(self) -> np.ndarray:
        """``[n_games, state_dim]``: each game's global state vector (``RocketDRLParallelEnv.state``)."""
        return np.stack([game.state() for game in self.games])

    def close(self) -> None:
        self.engine.close()
