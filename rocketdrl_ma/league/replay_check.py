"""Bit-identical replays of a league: its stored matches written down as records, and a check that plays every
recorded match again and compares.

A record is one JSON line per match, in schedule order: ``key``, ``seed``, ``blue``/``orange`` (entrants),
``score`` ([blue, orange]), ``ticks``, ``events`` and the sha256 digests of the final physics state and of the event
list (``digest.py``); the last line holds the ratings those results give (``{"ratings": {player: [mu, sigma]}}``).
``rocketdrl-ma league CONFIG --record FILE`` writes the records of the stored results, ``--verify FILE`` replays
them (``verify_records``) and names every field that differs. A local match is a pure function of the config and
its seed, so on the same code every field is equal, bit for bit.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rocketdrl_ma.config import resolve_shipped_path
from rocketdrl_ma.results import MatchResult

from .config import LeagueConfig
from .batch_play import DEFAULT_AT_ONCE
from .ratings import rate
from .runner import play_local_matches
from .schedule import ScheduledMatch, schedule

DIGEST_FIELDS = ("ticks", "events", "state_sha256", "events_sha256")


def match_record(match: ScheduledMatch, result: MatchResult) -> dict[str, Any]:
    """What a replay of ``match`` must reproduce; ValueError for a result stored without digests (a server match,
    or one played before matches were fingerprinted)."""
    missing = [name for name in DIGEST_FIELDS if name not in result.details]
    if missing:
        raise ValueError(f"{match.key}: the stored result has no {missing}; only local matches played by this "
                         "version are fingerprinted (play the league into a fresh results store)")
    return {"key": match.key, "seed": result.seed, "blue": match.blue, "orange": match.orange,
            "score": [result.score_blue, result.score_orange],
            **{name: result.details[name] for name in DIGEST_FIELDS}}


def ratings_record(cfg: LeagueConfig, planned: list[ScheduledMatch], results: list[MatchResult]) -> dict[str, Any]:
    return {"ratings": {r.name: [r.mu, r.sigma] for r in rate(cfg, planned, results).ratings}}


def write_records(cfg: LeagueConfig, results: list[MatchResult], path: str | Path) -> Path:
    """The records of every scheduled match ``results`` holds, then their ratings, as JSON lines at ``path``."""
    planned = schedule(cfg)
    by_key = {r.match_key: r for r in results}
    played = [m for m in planned if m.key in by_key]
    lines = [match_record(m, by_key[m.key]) for m in played]
    lines.append(ratings_record(cfg, planned, [by_key[m.key] for m in played]))
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("".join(json.dumps(line, sort_keys=True) + "\n" for line in lines))
    return out


def read_records(path: str | Path) -> tuple[list[dict[str, Any]], dict[str, Any] | None]:
    """(match records, the ratings line or None) of a records file (as given, else the shipped one of that name)."""
    text = resolve_shipped_path(path, "replay records").read_text()
    lines = [json.loads(line) for line in text.splitlines() if line.strip()]
    matches = [line for line in lines if "key" in line]
    ratings = next((line for line in lines if "ratings" in line), None)
    return matches, ratings


def verify_records(cfg: LeagueConfig, path: str | Path, workers: int = 0,
                   at_once: int = DEFAULT_AT_ONCE) -> list[str]:
    """Play every match recorded at ``path`` again (``at_once`` at a time in ``workers`` processes, as the league
    would) and compare every field of its record, and the ratings line, exactly. Returns the differences, each
    naming the match and the field; empty: a bit-identical replay."""
    records, ratings = read_records(path)
    by_key = {m.key: m for m in schedule(cfg)}
    unknown = [r["key"] for r in records if r["key"] not in by_key]
    if unknown:
        return [f"{key}: not in the schedule of league {cfg.name!r}" for key in unknown]
    matches = [by_key[r["key"]] for r in records]
    replayed = dict((match.key, result) for match, result in play_local_matches(cfg, matches, workers,
                                                                                at_once=at_once))
    differences = []
    for record, match in zip(records, matches):
        again = match_record(match, replayed[match.key])
        differences += [f"{match.key}: {name} was {record.get(name)!r}, replayed {value!r}"
                        for name, value in again.items() if record.get(name) != value]
    if ratings is not None:
        again = ratings_record(cfg, list(by_key.values()), [replayed[m.key] for m in matches])
        differences += [f"ratings: {name} was {ratings['ratings'].get(name)!r}, replayed {value!r}"
                        for name, value in again["ratings"].items() if ratings["ratings"].get(name) != value]
    return differences
