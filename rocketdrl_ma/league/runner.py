"""Run a league: play every scheduled match the results store does not hold yet.

Each finished match is appended (and committed) as soon as it is known, so killing the league at any moment
loses at most the matches in progress, which the next run plays again from the start. Matches between local
entrants can be played several at once (``workers`` processes on this machine, or tasks on a Ray cluster):
each is a pure function of the config and its scheduled seed, so the stored results, and the ratings computed
from them in schedule order, are those of a sequential run; this process stays the only writer of the store.
Matches with a remote entrant are played on the match server, one at a time, from this process.
"""
from __future__ import annotations

import multiprocessing
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
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


def play_local_matches(cfg: LeagueConfig, matches: list[ScheduledMatch], workers: int = 0,
                       ray: str | None = None) -> Iterator[tuple[ScheduledMatch, MatchResult]]:
    """Every match of ``matches`` on local envs, each result as soon as it is known: in this process (``workers``
    0, schedule order), in ``workers`` processes, or as tasks on the Ray cluster at ``ray`` (``auto``: the one
    this machine belongs to)."""
    if ray is not None:
        yield from _play_on_ray(cfg, matches, ray)
    elif workers <= 0 or len(matches) <= 1:
        for match in matches:
            yield match, play_local(cfg, match)
    else:
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = {pool.submit(play_local, cfg, match): match for match in matches}
            try:
                for future in as_completed(futures):
                    yield futures[future], future.result()
            finally:
                for future in futures:
                    future.cancel()


def _play_on_ray(cfg: LeagueConfig, matches: list[ScheduledMatch], address: str):
    import ray

    import rocketdrl_ma

    package = str(Path(rocketdrl_ma.__file__).resolve().parent)
    # the workers import this package, shipped by Ray to nodes that lack it
    ray.init(address=None if address == "auto" else address, runtime_env={"py_modules": [package]},
             log_to_driver=False, ignore_reinit_error=True)
    pending: dict = {}
    try:
        remote_play = ray.remote(num_cpus=1)(play_local)
        pending = {remote_play.remote(cfg, match): match for match in matches}
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                yield pending.pop(ref), ray.get(ref)
    finally:
        for ref in pending:
            ray.cancel(ref, force=True)
        ray.shutdown()


def run_league(cfg: LeagueConfig, max_matches: int | None = None,
               on_result: Callable[[ScheduledMatch, MatchResult], None] | None = None,
               workers: int = 0, ray: str | None = None, client=None) -> LeagueRun:
    """Play the missing matches of ``cfg``'s schedule (at most ``max_matches`` of them) into its store; local
    matches ``workers`` at a time (or on Ray), server matches one by one. ``client``: how this process reaches,
    authenticates to and trusts the match server (a ``ClientSettings``; default: the server link's endpoints,
    with the password and key in the server's folder when it runs on this machine)."""
    planned = schedule(cfg)
    client = server_client(cfg, client)
    session = None
    with ResultsStore(cfg.results) as store:
        stored = store.keys()
        todo = [m for m in planned if m.key not in stored]
        if max_matches is not None:
            todo = todo[:max_matches]
        played = 0

        def record(match: ScheduledMatch, result: MatchResult) -> None:
            nonlocal played
            if store.append(result):
                played += 1
            if on_result is not None:
                on_result(match, result)

        try:
            if workers <= 0 and ray is None:  # one at a time in schedule order, server matches among them
                for match in todo:
                    if needs_server(cfg, match):
                        session = session or client.zenoh.open()
                        record(match, play_on_server(cfg, match, session, client))
                    else:
                        record(match, play_local(cfg, match))
            else:
                for match, result in play_local_matches(cfg, [m for m in todo if not needs_server(cfg, m)],
                                                        workers, ray):
                    record(match, result)
                for match in (m for m in todo if needs_server(cfg, m)):
                    session = session or client.zenoh.open()
                    record(match, play_on_server(cfg, match, session, client))
        finally:
            if session is not None:
                session.close()
    return LeagueRun(len(planned), sum(m.key in stored for m in planned), played)


def server_client(cfg: LeagueConfig, client=None):
    """``client`` if given, else a client of the link's server at its endpoints (with the password and key in
    the server's folder when the server runs on this machine)."""
    from rocketdrl_ma.server.settings import ClientSettings, ZenohSettings
    if client is not None:
        return client
    return ClientSettings.from_dict({"server": cfg.server.name,
                                     "zenoh": ZenohSettings(mode="client", connect=tuple(cfg.server.connect))})
