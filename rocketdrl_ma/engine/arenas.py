"""Where an engine's games are played: one PyBullet world holding an arena per game."""
from __future__ import annotations

from rocketdrl_ma.physics import Arena, ArenaBatch


def make_arenas(n_games: int, arena_shape: str) -> list[Arena]:
    """``n_games`` arenas of one world. A single game gets a lone ``Arena``, whose world goes with the last
    reference to it (an ``ArenaBatch`` holds its views, so a dropped one waits for the cyclic collector)."""
    if n_games == 1:
        return [Arena(arena_shape=arena_shape)]
    return list(ArenaBatch(n_games, arena_shape=arena_shape).arenas)
