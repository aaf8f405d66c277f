"""Many local matches at once in one process: every decision, the cars of all live matches that one checkpoint drives
go through one forward of it (``policies.ppo.batched``), scripted bots keep one instance per car, and each match
steps its own env. A finished match hands its place to the next one of the schedule.

Each match keeps its own PyBullet world (a lone env's, as ``play_local`` plays it): the games of one ``VectorEnv``
share a world and match a lone arena only up to float rounding, so a match's result there would depend on its
neighbours. Here it does not: every match comes out bit for bit as ``play_local`` plays it alone.
"""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Callable

from rocketdrl_ma.policies.base import Policy
from rocketdrl_ma.results import MatchResult

from .config import LeagueConfig
from .play import LocalMatch, slot_players
from .schedule import ScheduledMatch

#: local matches a league process plays at once unless told (``--at-once``)
DEFAULT_AT_ONCE = 8


def play_local_at_once(cfg: LeagueConfig, matches: Iterable[ScheduledMatch],
                       at_once: int = DEFAULT_AT_ONCE) -> Iterator[tuple[ScheduledMatch, MatchResult]]:
    """Every match of ``matches`` (taken from it only when a place is free), ``at_once`` at a time in this process;
    each result as soon as its match ends."""
    import torch

    from rocketdrl_ma.policies.ppo.batched import cars_controls, seat_factory

    if isinstance(at_once, bool) or not isinstance(at_once, int) or at_once < 1:
        raise ValueError(f"at_once: expected an int >= 1 (matches played at once), got {at_once!r}")
    makers: dict[str, Callable[[], Policy]] = {}

    def start(match: ScheduledMatch) -> LocalMatch:
        policies = {}
        for slot, (_, spec) in slot_players(cfg, match).items():
            if spec not in makers:
                makers[spec] = seat_factory(spec)
            policies[slot] = makers[spec]()
        return LocalMatch(cfg, match, policies)

    pending = iter(matches)
    live: list[LocalMatch] = []
    threads = torch.get_num_threads()
    # a forward of a few dozen rows gains nothing from more threads, and on a busy machine they wait on each other
    torch.set_num_threads(1)
    try:
        while True:
            while len(live) < at_once and (match := next(pending, None)) is not None:
                live.append(start(match))
            if not live:
                return
            cars = [game.cars() for game in live]
            controls = cars_controls([car for game_cars in cars for car in game_cars])
            at = 0
            for game, game_cars in zip(live, cars):
                game.step(controls[at:at + len(game_cars)])
                at += len(game_cars)
            for game in [g for g in live if g.over]:
                live.remove(game)
                try:
                    result = game.result()
                finally:
                    game.close()
                yield game.match, result
    finally:
        torch.set_num_threads(threads)
        for game in live:
            game.close()
