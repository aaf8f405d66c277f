"""The results store: one SQLite file, WAL mode, append-only, shared by the match server and the league.

One row per finished match. Rows are never updated or deleted (triggers refuse it), so ratings are
always derived from the full history. A ``match_key`` names each match uniquely (e.g. a league's
``round/pair/game``): appending a key twice keeps the first row, which is how an interrupted league
resumes without losing or duplicating a match. Each append is its own committed transaction, so a
process killed with -9 loses nothing it had appended.
"""
from __future__ import annotations

import json
import sqlite3
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

SCHEMA = """
CREATE TABLE IF NOT EXISTS matches (
    id            INTEGER PRIMARY KEY AUTOINCREMENT,
    match_key     TEXT NOT NULL UNIQUE,
    source        TEXT NOT NULL,              -- who played it: 'server', 'league', ...
    finished_at   REAL NOT NULL,              -- unix seconds
    config        TEXT NOT NULL,              -- JSON: the validated game config
    entrants      TEXT NOT NULL,              -- JSON: {agent slot: entrant name}
    score_blue    INTEGER NOT NULL,
    score_orange  INTEGER NOT NULL,
    winner        TEXT,                       -- 'blue', 'orange' or NULL for a draw
    duration_s    REAL NOT NULL,              -- game seconds played
    seed          INTEGER,
    details       TEXT NOT NULL               -- JSON: events summary, stats, missed decisions per bot
);
CREATE TRIGGER IF NOT EXISTS matches_no_update BEFORE UPDATE ON matches
BEGIN SELECT RAISE(ABORT, 'results are append-only'); END;
CREATE TRIGGER IF NOT EXISTS matches_no_delete BEFORE DELETE ON matches
BEGIN SELECT RAISE(ABORT, 'results are append-only'); END;
"""


@dataclass(frozen=True)
class MatchResult:
    """A finished match. ``entrants`` maps agent slots (``blue_0``...) to entrant names."""
    match_key: str
    source: str
    config: dict[str, Any]
    entrants: dict[str, str]
    score_blue: int
    score_orange: int
    duration_s: float
    seed: int | None = None
    details: dict[str, Any] = field(default_factory=dict)
    finished_at: float = field(default_factory=time.time)

    @property
    def winner(self) -> str | None:
        if self.score_blue == self.score_orange:
            return None
        return "blue" if self.score_blue > self.score_orange else "orange"


class ResultsStore:
    """Append and read match results. Safe to share between processes (SQLite's own locking)."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # isolation_level=None: autocommit, every append is durable as soon as it returns.
        self._db = sqlite3.connect(self.path, timeout=30.0, isolation_level=None, check_same_thread=False)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.executescript(SCHEMA)

    def append(self, result: MatchResult) -> bool:
        """Store a finished match; False (and nothing written) if its ``match_key`` is already stored."""
        if not isinstance(result.match_key, str) or not result.match_key:
            raise ValueError(f"match_key: expected a non-empty string, got {result.match_key!r}")
        cursor = self._db.execute(
            "INSERT OR IGNORE INTO matches (match_key, source, finished_at, config, entrants, score_blue,"
            " score_orange, winner, duration_s, seed, details) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (result.match_key, result.source, result.finished_at, json.dumps(result.config, default=str),
             json.dumps(result.entrants), int(result.score_blue), int(result.score_orange), result.winner,
             float(result.duration_s), result.seed, json.dumps(result.details, default=str)))
        return cursor.rowcount == 1

    def keys(self) -> set[str]:
        return {row[0] for row in self._db.execute("SELECT match_key FROM matches")}

    def results(self, source: str | None = None, key_prefix: str | None = None) -> list[MatchResult]:
        """Stored matches in the order they finished, optionally only one source or key prefix."""
        query, args = "SELECT match_key, source, config, entrants, score_blue, score_orange, duration_s, seed," \
                      " details, finished_at FROM matches WHERE 1=1", []
        if source is not None:
            query += " AND source = ?"
            args.append(source)
        if key_prefix is not None:
            query += " AND substr(match_key, 1, ?) = ?"
            args += [len(key_prefix), key_prefix]
        rows = self._db.execute(query + " ORDER BY id", args).fetchall()
        return [MatchResult(match_key=r[0], source=r[1], config=json.loads(r[2]), entrants=json.loads(r[3]),
                            score_blue=r[4], score_orange=r[5], duration_s=r[6], seed=r[7],
                            details=json.loads(r[8]), finished_at=r[9]) for r in rows]

    def __len__(self) -> int:
        return self._db.execute("SELECT COUNT(*) FROM matches").fetchone()[0]

    def close(self) -> None:
        self._db.close()

    def __enter__(self) -> "ResultsStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
