"""openskill ratings and the win-rate payoff matrix, recomputed from the stored results.

Results are rated in schedule order (not the order they finished in), so a league that was interrupted
and resumed ends with exactly the ratings of one that ran straight through.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from rocketdrl_ma.results import MatchResult

from .config import LeagueConfig
from .schedule import ScheduledMatch


@dataclass
class PlayerRating:
    name: str
    mu: float
    sigma: float
    ordinal: float
    matches: int = 0
    wins: int = 0
    draws: int = 0
    losses: int = 0


@dataclass
class LeagueTable:
    ratings: list[PlayerRating]                       # best ordinal first
    #: payoff[a][b]: points per match of entrant a against b (win 1, draw 0.5), None if they never met
    payoff: dict[str, dict[str, float | None]] = field(default_factory=dict)
    games: dict[str, dict[str, int]] = field(default_factory=dict)
    played: int = 0


def team_players(cfg: LeagueConfig, result: MatchResult, team: str) -> list[str]:
    """The distinct players of ``team`` in a stored match (from its slot -> player map)."""
    players = result.details.get("players", {})
    names = [players[slot] for slot in sorted(players) if slot.startswith(team)]
    return list(dict.fromkeys(names))


def rate(cfg: LeagueConfig, planned: list[ScheduledMatch], results: list[MatchResult]) -> LeagueTable:
    """Ratings of every player and the payoff matrix of every entrant pair."""
    from openskill.models import PlackettLuce

    model = PlackettLuce()
    by_key = {r.match_key: r for r in results}
    ratings = {p.name: model.rating(name=p.name) for p in cfg.players}
    table = {p.name: PlayerRating(p.name, 0.0, 0.0, 0.0) for p in cfg.players}
    names = [e.name for e in cfg.entrants]
    points = {a: {b: 0.0 for b in names} for a in names}
    games = {a: {b: 0 for b in names} for a in names}
    played = 0
    for match in planned:
        result = by_key.get(match.key)
        if result is None:
            continue
        played += 1
        blue, orange = team_players(cfg, result, "blue"), team_players(cfg, result, "orange")
        # a draw is a shared rank; the winner's rank is lower (better)
        ranks = [1, 1] if result.winner is None else ([1, 2] if result.winner == "blue" else [2, 1])
        new_blue, new_orange = model.rate([[ratings[n] for n in blue], [ratings[n] for n in orange]], ranks=ranks)
        for name, rating in zip(blue + orange, new_blue + new_orange):
            ratings[name] = rating
        for team, members in (("blue", blue), ("orange", orange)):
            for name in members:
                row = table[name]
                row.matches += 1
                if result.winner is None:
                    row.draws += 1
                elif result.winner == team:
                    row.wins += 1
                else:
                    row.losses += 1
        score = {"blue": 1.0 if result.winner == "blue" else 0.5 if result.winner is None else 0.0}
        score["orange"] = 1.0 - score["blue"]
        points[match.blue][match.orange] += score["blue"]
        points[match.orange][match.blue] += score["orange"]
        games[match.blue][match.orange] += 1
        games[match.orange][match.blue] += 1
    for name, rating in ratings.items():
        row = table[name]
        row.mu, row.sigma, row.ordinal = float(rating.mu), float(rating.sigma), float(rating.ordinal())
    payoff = {a: {b: (points[a][b] / games[a][b] if games[a][b] else None) for b in names} for a in names}
    ranked = sorted(table.values(), key=lambda r: r.ordinal, reverse=True)
    return LeagueTable(ranked, payoff, games, played)
