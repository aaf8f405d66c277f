"""Run a league: play every scheduled match the results store does not hold yet.

Each finished match is appended (and committed) as soon as it is known, so killing the league at any moment
loses at most the matches in progress, which the next run plays again from the start. Matches between local
entrants are played several at once in one process (``batch_play``: one forward per checkpoint for all its cars),
in each of ``workers`` processes on this machine, or as tasks on a Ray cluster: each is a pure function of the
config and its scheduled seed, so the stored results, and the ratings computed from them in schedule order, are
those of a sequential run; this process stays the only writer of the store.
Matches with a remote entrant are played on the match server, one at a time, from this process.
"""
from __future__ import annotations

import multiprocessing
import queue
import traceback
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from rocketdrl_ma.results import MatchResult, ResultsStore

from .config import LeagueConfig
from .batch_play import DEFAULT_AT_ONCE, play_local_at_once
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
                       ray: str | None = None,
                       at_once: int = DEFAULT_AT_ONCE) -> Iterator[tuple[ScheduledMatch, MatchResult]]:
    """Every match of ``matches`` on local envs, each result as soon as it is known: ``at_once`` matches at a time
    in this process (``workers`` 0) or in each of ``workers`` processes sharing the schedule, or one match per task
    on the Ray cluster at ``ray`` (``auto``: the one this machine belongs to)."""
    if ray is not None:
        yield from _play_on_ray(cfg, matches, ray)
    elif workers <= 0 or len(matches) <= 1:
        yield from play_local_at_once(cfg, matches, at_once)
    else:
        yield from _play_in_processes(cfg, matches, workers, at_once)


def _play_in_processes(cfg: LeagueConfig, matches: list[ScheduledMatch], workers: int,
                       at_once: int) -> Iterator[tuple[ScheduledMatch, MatchResult]]:
    """``workers`` processes, each playing matches at once and taking the next one of a shared queue as one ends."""
    context = multiprocessing.get_context("spawn")
    tasks, results = context.Queue(), context.Queue()
    for match in matches:
        tasks.put(match)
    workers = min(workers, len(matches))
    for _ in range(workers):
        tasks.put(None)
    # a process fills its places from the queue: at most its share at first, so the others get theirs
    places = min(at_once, -(-len(matches) // workers))
    processes = [context.Process(target=_worker, args=(cfg, tasks, results, places), daemon=True)
                 for _ in range(workers)]
    for process in processes:
        process.start()
    try:
        running = workers
        while running:
            try:
                kind, match, payload = results.get(timeout=10.0)
            except queue.Empty:
                if any(p.exitcode not in (None, 0) for p in processes):
                    raise RuntimeError("a league process died without a word (killed, or out of memory)") from None
                continue
            if kind == "error":
                raise RuntimeError(f"a league process failed: {payload}")
            if kind == "done":
                running -= 1
            else:
                yield match, payload
    finally:
        for process in processes:
            if process.is_alive():
                process.terminate()
            process.join()


def _worker(cfg: LeagueConfig, tasks, results, at_once: int) -> None:
    try:
        for match, result in play_local_at_once(cfg, iter(tasks.get, None), at_once):
            results.put(("result", match, result))
    except BaseException:  # the league process reports it; a worker has no one else to tell
        results.put(("error", None, traceback.format_exc()))
    else:
        results.put(("done", None, None))


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
               workers: int = 0, ray: str | None = None, at_once: int = DEFAULT_AT_ONCE, client=None) -> LeagueRun:
    """Play the missing matches of ``cfg``'s schedule (at most ``max_matches`` of them) into its store; local
    matches ``at_once`` at a time in this process or in each of ``workers`` processes (or on Ray), then the server
    matches one by one. ``client``: how this process reaches, authenticates to and trusts the match server (a
    ``ClientSettings``; default: the server link's endpoints, with the password and key in the server's folder when
    it runs on this machine)."""
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
            for match, result in play_local_matches(cfg, [m for m in todo if not needs_server(cfg, m)],
                                                    workers, ray, at_once):
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
