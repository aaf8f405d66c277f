"""The league report: ``report.md`` (ratings table, payoff matrix, how to reproduce) and ``ratings.png``."""
from __future__ import annotations

from pathlib import Path

from .config import LeagueConfig
from .ratings import LeagueTable


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
                 out_dir: str | Path | None = None) -> Path:
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
    report = out / "report.md"
    report.write_text("\n".join(lines) + "\n")
    return report
