"""The deterministic match schedule: the same config always gives the same matches, keys and seeds.

Every scheduled match has a ``match_key`` (``<league>/<round>/<blue>-vs-<orange>/<game>``); a league
plays only the keys its results store does not hold yet, so an interrupted league resumes where it
stopped, and the store's unique keys make a finished match impossible to record twice.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass
from itertools import combinations

from .config import LeagueConfig


@dataclass(frozen=True)
class ScheduledMatch:
    index: int        # position in the schedule: the order results are rated in
    key: str
    blue: str         # entrant names
    orange: str
    seed: int


def match_seed(seed: int, key: str) -> int:
    """The env seed of a match: from its key, so adding entrants to a league keeps every seed (and the
    stored results stay those of the schedule)."""
    return (seed + zlib.crc32(key.encode())) % 2**31


def schedule(cfg: LeagueConfig) -> list[ScheduledMatch]:
    """Round robin: every pair once per round, sides swapping each round; per pair: ``matches_per_pair``
    games of every pair, sides alternating."""
    pairs = list(combinations([e.name for e in cfg.entrants], 2))
    out: list[ScheduledMatch] = []
    if cfg.format == "round_robin":
        games = [(r, 0, a, b) if r % 2 == 0 else (r, 0, b, a) for r in range(cfg.rounds) for a, b in pairs]
    else:
        games = [(0, g, a, b) if g % 2 == 0 else (0, g, b, a) for a, b in pairs for g in range(cfg.matches_per_pair)]
    for index, (rnd, game, blue, orange) in enumerate(games):
        key = f"{cfg.name}/{rnd}/{blue}-vs-{orange}/{game}"
        out.append(ScheduledMatch(index, key, blue, orange, match_seed(cfg.seed, key)))
    return out
