"""The league page's data: a league's standings, ratings with their uncertainty, payoff matrix and played matches,
read from the results store its config names; and any local match of it played again from its seed into a replay
the page shows (a local match is a pure function of its config and seed: ``league/replay_check.py``)."""
from __future__ import annotations

import re
import threading
from pathlib import Path

from rocketdrl_ma.league.config import LeagueConfig, load_league_config
from rocketdrl_ma.league.play import LocalMatch, slot_players
from rocketdrl_ma.league.ratings import rate
from rocketdrl_ma.league.runner import needs_server
from rocketdrl_ma.league.schedule import ScheduledMatch, schedule
from rocketdrl_ma.results import MatchResult, ResultsStore

#: a rating's interval on the page: mu +- this many sigma (the report's whiskers; its low end is the ordinal)
INTERVAL_SIGMAS = 3.0


def replay_name(key: str) -> str:
    """A match key as a replay file name (``league/0/a-vs-b/1`` -> ``league__0__a-vs-b__1.npz``)."""
    return re.sub(r"[^A-Za-z0-9._-]", "_", key.replace("/", "__")) + ".npz"


class LeagueView:
    """One league (its config file) as the page shows it. ``replay_dir``: where replayed matches are written."""

    def __init__(self, config_path: str | Path, replay_dir: Path):
        self.config_path = str(config_path)
        self.cfg: LeagueConfig = load_league_config(config_path)
        self.replay_dir = Path(replay_dir)
        self._replaying = threading.Lock()  # one match played again at a time: each costs a core for seconds
        self._replayed_scores: dict[str, list[int]] = {}

    def _results(self) -> list[MatchResult]:
        path = Path(self.cfg.results)
        if not path.is_file():
            return []
        with ResultsStore(path) as store:
            return store.results(key_prefix=f"{self.cfg.name}/")

    def summary(self) -> dict:
        """Everything the league page draws, as JSON-ready values."""
        cfg, planned = self.cfg, schedule(self.cfg)
        by_key = {r.match_key: r for r in self._results()}
        played = [(m, by_key[m.key]) for m in planned if m.key in by_key]
        table = rate(cfg, planned, [r for _, r in played])
        names = [e.name for e in cfg.entrants]
        standings = {name: {"name": name, "matches": 0, "wins": 0, "draws": 0, "losses": 0, "goals_for": 0,
                            "goals_against": 0} for name in names}
        for match, result in played:
            for side, mine, theirs in ((match.blue, result.score_blue, result.score_orange),
                                       (match.orange, result.score_orange, result.score_blue)):
                row = standings[side]
                row["matches"] += 1
                row["goals_for"] += mine
                row["goals_against"] += theirs
                row["wins" if mine > theirs else "draws" if mine == theirs else "losses"] += 1
        for row in standings.values():
            row["points"] = row["wins"] + 0.5 * row["draws"]
        ranked = sorted(standings.values(), key=lambda r: (-r["points"], r["goals_against"] - r["goals_for"],
                                                           r["name"]))
        return {
            "name": cfg.name, "config": self.config_path, "match": cfg.match, "results": str(cfg.results),
            "scheduled": len(planned), "played": len(played), "interval_sigmas": INTERVAL_SIGMAS,
            "standings": ranked,
            "ratings": [{"name": r.name, "mu": r.mu, "sigma": r.sigma, "ordinal": r.ordinal,
                         "low": r.mu - INTERVAL_SIGMAS * r.sigma, "high": r.mu + INTERVAL_SIGMAS * r.sigma,
                         "matches": r.matches, "wins": r.wins, "draws": r.draws, "losses": r.losses}
                        for r in table.ratings],
            "entrants": names,
            "payoff": [[None if a == b or table.payoff[a][b] is None else
                        {"points": table.payoff[a][b], "games": table.games[a][b]} for b in names] for a in names],
            "matches": [{"key": m.key, "blue": m.blue, "orange": m.orange, "seed": r.seed,
                         "score": [r.score_blue, r.score_orange], "winner": r.winner, "duration_s": r.duration_s,
                         "replay": not needs_server(cfg, m)} for m, r in played],
        }

    def replay(self, key: object) -> tuple[Path, bool | None]:
        """The replay of stored match ``key``, played again from its seed (once; then the file is kept), and
        whether the replayed score equals the stored one (None: a file from before, not checked). ValueError for a
        key not stored or a server match."""
        planned = {m.key: m for m in schedule(self.cfg)}
        stored = {r.match_key: r for r in self._results()}
        if not isinstance(key, str) or key not in planned or key not in stored:
            raise ValueError(f"key: {key!r} is no stored match of league {self.cfg.name!r}")
        match, result = planned[key], stored[key]
        if needs_server(self.cfg, match):
            raise ValueError(f"key: {key!r} was played on a match server by a remote entrant; it has no replay")
        path = self.replay_dir / replay_name(key)
        with self._replaying:
            if not path.is_file():  # the writer renames its file into place when the match ends
                self.replay_dir.mkdir(parents=True, exist_ok=True)
                self._replayed_scores[key] = play_into_replay(self.cfg, match, path)
        score = self._replayed_scores.get(key)
        return path, None if score is None else score == [result.score_blue, result.score_orange]


def play_into_replay(cfg: LeagueConfig, match: ScheduledMatch, path: Path) -> list[int]:
    """Play ``match`` again as the league plays it (the same batched forwards) recording a replay; its score."""
    from rocketdrl_ma.policies.ppo.batched import cars_controls, seat_factory

    policies = {slot: seat_factory(spec)() for slot, (_, spec) in slot_players(cfg, match).items()}
    game = LocalMatch(cfg, match, policies)
    try:
        game.env.start_replay(path)
        while not game.over:
            game.step(cars_controls(game.cars()))
        score = game.summary["score"]
        return [int(score["blue"]), int(score["orange"])]
    finally:
        game.close()
