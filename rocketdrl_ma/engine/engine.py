"""``GameEngine``: the one loop that plays games. Controls in, ``GameState`` out, for N games at once."""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rocketdrl_ma.config import make_rules
from rocketdrl_ma.physics import Arena, CarControls
from rocketdrl_ma.rules import GameState, Rules, StateMutator
from rocketdrl_ma.validation import check_int

from .arenas import make_arenas
from .controls import N_CONTROLS, controls_from_rows

_NEUTRAL_ROW = CarControls().as_array()


class GameEngine:
    """``games``: one ``Rules`` per game, all of one game mode, team sizes and arena shape, played in one PyBullet
    world (made at the first reset) and stepped by one physics step per tick for all of them.

    ``reset_game(game, seed)`` starts a game's episode from its own random stream (``seed`` restarts it, None goes
    on), ``step(controls, ticks)`` plays every game for ``ticks`` physics ticks with the rules' logic after each and
    returns each game's ``GameState``. A game's random draws depend on its own stream only: game ``k`` of a batch
    seeded ``s`` plays what a lone engine's game seeded ``s`` plays.
    """

    def __init__(self, games: Sequence[Rules], tick_skip: int = 8):
        games = list(games)
        if not games or not all(isinstance(rules, Rules) for rules in games):
            raise ValueError(f"games: expected a non-empty list of Rules, got {games!r}")
        first = games[0]
        for rules in games[1:]:
            if rules.possible_agents != first.possible_agents or rules.arena_shape != first.arena_shape:
                raise ValueError("games: every game of an engine has the same agents and arena shape")
        self.games = games
        self.n_games = len(games)
        self.tick_skip = check_int("tick_skip", tick_skip, minimum=1)
        self.possible_agents: list[str] = list(first.possible_agents)
        self.arena_shape = first.arena_shape
        self.arenas: list[Arena] = []
        self.rngs: list[np.random.Generator | None] = [None] * self.n_games
        self.states: list[GameState | None] = [None] * self.n_games
        # Per game: the batch rows of its cars, this decision's control rows, and whether the rows written are the
        # neutral ones of a frozen game (None: nothing written this decision)
        self._rows: list[np.ndarray] = [np.zeros(0, np.int64)] * self.n_games
        self._controls: list[np.ndarray] = [np.zeros((0, N_CONTROLS))] * self.n_games
        self._neutral = np.tile(_NEUTRAL_ROW, (len(self.possible_agents), 1))
        self._frozen: list[bool | None] = [None] * self.n_games

    @classmethod
    def from_config(cls, config: Mapping[str, Any], n_games: int = 1) -> "GameEngine":
        """``n_games`` games of a loaded config (``config.load_config``)."""
        check_int("n_games", n_games, minimum=1)
        return cls([make_rules(dict(config)) for _ in range(n_games)], tick_skip=config["tick_skip"])

    # ------------------------------------------------------------------ the world
    @property
    def world(self):
        """The PyBullet world of every game (a ``PhysicsWorld``; None before the first reset)."""
        return self.arenas[0].batch if self.arenas else None

    def _arena(self, game: int) -> Arena:
        if not self.arenas:
            self.arenas = make_arenas(self.n_games, self.arena_shape)
        return self.arenas[game]

    def renew_world(self) -> None:
        """A new PyBullet world with every car where it is (``PhysicsWorld.renew_bullet_world``), after seeded
        resets: a used engine then plays what a new one plays from the same seeds."""
        if self.arenas:
            self.world.renew_bullet_world()

    # ------------------------------------------------------------------ episodes
    def _game_index(self, game: int) -> int:
        if isinstance(game, bool) or not isinstance(game, (int, np.integer)) or not 0 <= game < self.n_games:
            raise ValueError(f"game: must be an index in 0..{self.n_games - 1}, got {game!r}")
        return int(game)

    def reset_game(self, game: int, seed: int | None = None) -> GameState:
        """Start game ``game``'s next episode; ``seed`` restarts its random stream (None: the stream goes on, or a
        fresh unseeded one the first time)."""
        game = self._game_index(game)
        if seed is not None or self.rngs[game] is None:
            self.rngs[game] = np.random.default_rng(seed)
        rules = self.games[game]
        if rules.arena is None:
            rules.build(self._arena(game))
            # a car added to the world may move every car's batch row
            self._rows = [np.array([car.batch_row for car in other.cars.values()], dtype=np.int64)
                          for other in self.games]
        rules.reset(self.rngs[game])
        state = self.states[game] = rules.game_state()
        return state

    def set_state(self, game: int, mutator: StateMutator) -> GameState:
        """Put game ``game``'s cars and ball as ``mutator`` says (``rules.FixedStateMutator`` for exact states),
        drawing from the game's own random stream, between decisions of an episode; returns the game's state."""
        game = self._game_index(game)
        rules = self.games[game]
        if rules.arena is None:
            raise ValueError(f"set_state: game {game} was never reset; call reset_game({game}) first")
        if not isinstance(mutator, StateMutator):
            raise ValueError(f"mutator: expected a rules.StateMutator, got {type(mutator).__name__}")
        mutator.apply(rules.arena, rules.cars, self.rngs[game])
        state = self.states[game] = rules.game_state()
        return state

    def is_used(self, game: int) -> bool:
        """Has ``game`` been reset before (its arena holds an earlier episode's physics)?"""
        return self.games[self._game_index(game)].arena is not None

    # ------------------------------------------------------------------ decisions
    def step(self, controls: Sequence[Mapping[str, CarControls]] | np.ndarray,
             ticks: int | None = None) -> list[GameState]:
        """Every game plays ``ticks`` physics ticks (default ``tick_skip``) with its ``controls``: per game a dict
        agent -> ``CarControls`` (cars not named keep their last controls), or an array ``[games, cars, 8]`` in
        ``possible_agents`` order. Returns every game's state after the ticks, its ``events`` those of these ticks."""
        if isinstance(controls, np.ndarray):
            controls = self._controls_of_array(controls)
        if len(controls) != self.n_games:
            raise ValueError(f"controls: expected one entry per game ({self.n_games}), got {len(controls)}")
        ticks = self.tick_skip if ticks is None else check_int("ticks", ticks, minimum=0)
        for game, (rules, given) in enumerate(zip(self.games, controls)):
            if rules.arena is None:
                raise ValueError(f"step: game {game} was never reset; call reset_game({game}) first")
            unknown = [agent for agent in given if agent not in rules.cars]
            if unknown:
                raise ValueError(f"controls: unknown agent(s) {unknown} in game {game}; agents are {list(rules.cars)}")
            for agent, car_controls in given.items():
                if not isinstance(car_controls, CarControls):
                    raise ValueError(f"controls for {agent}: expected CarControls, got {type(car_controls).__name__}")
            rules.begin_decision(dict(given))
            last = rules.last_controls
            self._controls[game] = np.array([last[agent].as_array() for agent in rules.cars]).reshape(
                len(rules.cars), N_CONTROLS)
            self._frozen[game] = None
        self._run_ticks(ticks)
        self.states = [rules.game_state() for rules in self.games]
        return list(self.states)

    def _controls_of_array(self, controls: np.ndarray) -> list[dict[str, CarControls]]:
        expected = (self.n_games, len(self.possible_agents), N_CONTROLS)
        if controls.shape != expected:
            raise ValueError(f"controls: expected shape {expected} (games, cars, controls), got {controls.shape}")
        return [controls_from_rows(rows, self.possible_agents) for rows in controls]

    def _run_ticks(self, ticks: int) -> None:
        games, arenas = self.games, self.arenas
        world = self.world
        for _ in range(ticks):
            for game, rules in enumerate(games):
                frozen = rules.controls_frozen()
                # Nothing else writes a game's rows during a decision, so they need writing only when they change.
                if frozen != self._frozen[game]:
                    world.controls[self._rows[game]] = self._neutral if frozen else self._controls[game]
                    self._frozen[game] = frozen
            world.step(1)
            for rules, arena in zip(games, arenas):
                rules.end_tick(arena.drain_events())

    # ------------------------------------------------------------------ the rest
    def close(self) -> None:
        for rules in self.games:
            rules.close()
        if self.arenas:
            self.world.close()
        self.arenas = []
