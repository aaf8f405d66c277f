"""Run a league: play every scheduled match the results store does not hold yet, one at a time.

Each finished match is appended (and committed) before the next one starts, so killing the league at
any moment loses at most the match in progress, which the next run plays again from the start.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from rocketdrl_ma.results import MatchResult, ResultsStore

from .config import LeagueConfig
from .play import play_local, play_on_server
from .schedule import ScheduledMatch, schedule


@dataclass
class LeagueRun:
    scheduled: int
    already_stored: int
    played: int


def needs_server(cfg: LeagueConfig, match: ScheduledMatch) -> bool:
    return cfg.entrant(match.blue).remote or cfg.entrant(match.orange).remote


def run_league(cfg: LeagueConfig, max_matches: int | None = None,
               on_result: Callable[[ScheduledMatch, MatchResult], None] | None = None) -> LeagueRun:
    """Play the missing matches of ``cfg``'s schedule (at most ``max_matches`` of them) into its store."""
    planned = schedule(cfg)
    session = None
    with ResultsStore(cfg.results) as store:
        stored = store.keys()
        todo = [m for m in planned if m.key not in stored]
        if max_matches is not None:
            todo = todo[:max_matches]
        played = 0
        try:
            for match in todo:
                if needs_server(cfg, match):
                    if session is None:
                        from rocketdrl_ma.server.settings import ZenohSettings
                        session = ZenohSettings(mode="client", connect=cfg.server.connect).open()
                    result = play_on_server(cfg, match, session)
                else:
                    result = play_local(cfg, match)
                if store.append(result):
                    played += 1
                if on_result is not None:
                    on_result(match, result)
        finally:
            if session is not None:
                session.close()
    return LeagueRun(len(planned), sum(m.key in stored for m in planned), played)
