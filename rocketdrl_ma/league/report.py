"""The league report: ``report.md`` (ratings table, payoff matrix, team metrics per entrant, how to reproduce) and
``ratings.png``."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rocketdrl_ma.results import MatchResult
from rocketdrl_ma.rules import agent_number

from .config import LeagueConfig
from .ratings import LeagueTable

TEAMS = ("blue", "orange")
#: team totals reported per match, with their column headers
PER_MATCH = (("passes", "passes"), ("assists", "assists"), ("double_commits", "double commits"),
             ("demos", "demos"), ("boost_collected", "boost collected"))


@dataclass
class EntrantTeamMetrics:
    """An entrant's team metrics (``rules/team_metrics.py``) over the stored matches it played."""
    matches: int = 0
    goals_for: int = 0
    goals_against: int = 0
    totals: dict[str, float] = field(default_factory=dict)     # PER_MATCH keys, summed over matches
    distances_uu: list[float] = field(default_factory=list)    # mean team-mate distance of each match
    last_back: list[list[float]] = field(default_factory=list)  # per match: each car's share, by slot

    def per_match(self, key: str) -> float:
        return self.totals.get(key, 0.0) / self.matches if self.matches else float("nan")


def entrant_team_metrics(cfg: LeagueConfig, results: list[MatchResult]) -> dict[str, EntrantTeamMetrics]:
    """Every entrant's team metrics over ``results`` (matches stored before team metrics existed count for the
    goals only)."""
    out = {e.name: EntrantTeamMetrics() for e in cfg.entrants}
    for result in results:
        team_metrics = result.details.get("team", {})
        for team in TEAMS:
            entrant = {slot: name for slot, name in result.entrants.items() if slot.startswith(team)}
            names = set(entrant.values())
            if len(names) != 1 or next(iter(names)) not in out:
                continue
            row = out[next(iter(names))]
            row.matches += 1
            mine, theirs = ((result.score_blue, result.score_orange) if team == "blue"
                            else (result.score_orange, result.score_blue))
            row.goals_for += mine
            row.goals_against += theirs
            metrics = team_metrics.get(team)
            if not metrics:
                continue
            for key, _ in PER_MATCH:
                row.totals[key] = row.totals.get(key, 0.0) + float(metrics.get(key, 0.0))
            if metrics.get("mean_teammate_distance_uu") is not None:
                row.distances_uu.append(float(metrics["mean_teammate_distance_uu"]))
            shares = metrics.get("last_back_share", {})
            row.last_back.append([shares[slot] for slot in sorted(shares, key=agent_number)])
    return out


def team_metrics_lines(cfg: LeagueConfig, results: list[MatchResult]) -> list[str]:
    """The report's "Team metrics" section: one row per entrant."""
    rows = entrant_team_metrics(cfg, results)
    lines = ["## Team metrics", "",
             "Per match of each entrant, over the stored matches (definitions: docs/guides/team-play.md, "
             "\"Team metrics\"). Last back: the share of live play each of its cars (by slot) was the one nearest "
             "its own goal.", "",
             "| entrant | matches | goals for | goals against | " + " | ".join(h for _, h in PER_MATCH)
             + " | team-mate distance (uu) | last back by slot |",
             "|---|" + "---:|" * (4 + len(PER_MATCH)) + "---|"]
    for name, row in rows.items():
        if not row.matches:
            lines.append(f"| {name} | 0 |" + " - |" * (3 + len(PER_MATCH)) + " - |")
            continue
        distance = f"{np.mean(row.distances_uu):.0f}" if row.distances_uu else "-"
        widths = {len(shares) for shares in row.last_back}
        last_back = (" / ".join(f"{v:.2f}" for v in np.mean(row.last_back, axis=0))
                     if len(widths) == 1 else "-")
        lines.append(f"| {name} | {row.matches} | {row.goals_for / row.matches:.2f} | "
                     f"{row.goals_against / row.matches:.2f} | "
                     + " | ".join(f"{row.per_match(key):.2f}" for key, _ in PER_MATCH)
                     + f" | {distance} | {last_back} |")
    return lines


def plot_ratings(table: LeagueTable, out: Path, title: str) -> Path:
    """Horizontal bars of mu with +-3 sigma whiskers, players ordered by ordinal (mu - 3 sigma)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = table.ratings[::-1]  # best at the top
    fig, ax = plt.subplots(figsize=(8, 0.6 * len(rows) + 1.5))
    y = range(len(rows))
    ax.barh(y, [r.mu for r in rows], xerr=[3 * r.sigma for r in rows], color="tab:blue", alpha=0.6,
            capsize=4, label="mean (mu) with +-3 sigma")
    ax.scatter([r.ordinal for r in rows], y, color="black", zorder=3, marker="|", s=200,
               label="ordinal (mu - 3 sigma)")
    ax.set_yticks(list(y), [r.name for r in rows])
    ax.set_xlabel("openskill rating (Plackett-Luce)")
    ax.set_title(title)
    ax.grid(axis="x", alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def write_report(cfg: LeagueConfig, table: LeagueTable, scheduled: int, config_path: str,
                 out_dir: str | Path | None = None, results: list[MatchResult] | None = None) -> Path:
    """``report.md`` and ``ratings.png`` in ``out_dir`` (default: the config's report folder); with ``results`` (the
    league's stored matches) also the team metrics per entrant."""
    out = Path(out_dir or cfg.report)
    png = plot_ratings(table, out / "ratings.png", f"league {cfg.name}: {table.played} matches")
    names = [e.name for e in cfg.entrants]
    lines = [f"# League `{cfg.name}`", "",
             f"{table.played} of {scheduled} scheduled matches played on `{cfg.match}`"
             + (f" with overrides `{cfg.overrides}`" if cfg.overrides else "")
             + f", {cfg.format.replace('_', ' ')}"
             + (f", {cfg.rounds} round(s)" if cfg.format == "round_robin" else
                f", {cfg.matches_per_pair} matches per pair") + ".", "",
             f"Reproduce: `rocketdrl-ma league {config_path}` (results: `{cfg.results}`; resumes where it stopped).",
             "", "## Entrants", ""]
    for e in cfg.entrants:
        who = "remote bot" if e.remote else ", ".join(f"{p.name} = `{p.policy}`" for p in e.players)
        lines.append(f"- **{e.name}**: {who}")
    lines += ["", "## Ratings (openskill Plackett-Luce, rated in schedule order)", "",
              "| rank | player | mu | sigma | ordinal (mu - 3 sigma) | matches | W | D | L |",
              "|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for i, r in enumerate(table.ratings, 1):
        lines.append(f"| {i} | {r.name} | {r.mu:.2f} | {r.sigma:.2f} | {r.ordinal:.2f} | {r.matches} | {r.wins} "
                     f"| {r.draws} | {r.losses} |")
    lines += ["", f"![ratings]({png.name})", "",
              "## Payoff matrix", "", "Points per match of the row entrant against the column entrant "
              "(win 1, draw 0.5, loss 0), with the number of matches.", "",
              "| | " + " | ".join(names) + " |", "|---|" + "---:|" * len(names)]
    for a in names:
        cells = ["-" if a == b or table.payoff[a][b] is None else f"{table.payoff[a][b]:.2f} ({table.games[a][b]})"
                 for b in names]
        lines.append(f"| **{a}** | " + " | ".join(cells) + " |")
    if results is not None:
        lines += [""] + team_metrics_lines(cfg, results)
    report = out / "report.md"
    report.write_text("\n".join(lines) + "\n")
    return report
