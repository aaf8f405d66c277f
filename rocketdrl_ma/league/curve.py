"""A training run's rating curve: every snapshot plays the same games against fixed anchors whose ratings are
pinned, so each snapshot's openskill rating is on one scale with the others and with any other run's.

The matches go into a results store like a league's (append-only, keyed by ``<curve>/<snapshot>/<pair>/<game>``),
so rating a run again, or following it while it trains, plays only the matches not stored yet.
"""
from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path

from rocketdrl_ma.results import MatchResult, ResultsStore
from rocketdrl_ma.validation import check_name

from .batch_play import DEFAULT_AT_ONCE
from .curve_config import CurveConfig
from .runner import play_local_matches
from .schedule import ScheduledMatch, match_seed

#: the normal quantile of a two-sided 95 % interval
Z_95 = 1.959963984540054


@dataclass(frozen=True)
class Snapshot:
    """A checkpoint of a run: ``name`` is its player name in the curve's store."""
    name: str
    path: Path
    agent_steps: int
    train_hours: float | None = None


@dataclass(frozen=True)
class CurvePoint:
    snapshot: str
    agent_steps: int
    train_hours: float | None
    mu: float
    sigma: float
    matches: int
    #: points per match against each anchor (win 1, draw 0.5)
    points: dict[str, float] = field(default_factory=dict)

    @property
    def low(self) -> float:
        return self.mu - Z_95 * self.sigma

    @property
    def high(self) -> float:
        return self.mu + Z_95 * self.sigma


def read_snapshot(path: Path, name: str | None = None) -> Snapshot:
    """The checkpoint at ``path`` with its step count (and training hours, if its metadata has them)."""
    meta = json.loads(path.with_suffix(".json").read_text())
    seconds = meta.get("metrics", {}).get("train_seconds")
    return Snapshot(check_name("snapshot name", name or path.stem), path, int(meta["agent_steps"]),
                    None if seconds is None else float(seconds) / 3600.0)


def run_snapshots(run_dir: Path, final: Path | None = None) -> list[Snapshot]:
    """A training run's snapshots (``snapshots/step_*.pt``) and its final checkpoint (``final``, default
    ``final.pt`` in the run's folder) once written, by step."""
    found = [read_snapshot(p) for p in Path(run_dir, "snapshots").glob("step_*[0-9].pt")]
    final = Path(run_dir, "final.pt") if final is None else Path(final)
    if final.is_file() and final.with_suffix(".json").is_file():
        found.append(read_snapshot(final, "final"))
    return sorted(found, key=lambda s: (s.agent_steps, s.name == "final"))


def snapshot_matches(cfg: CurveConfig, snapshot: Snapshot) -> list[ScheduledMatch]:
    """The snapshot's games against every anchor, sides alternating; game ``g`` against an anchor has the same seed
    for every snapshot, so the curve compares snapshots on the same games."""
    out = []
    for anchor in cfg.anchors:
        for game in range(cfg.matches_per_anchor):
            blue, orange = (snapshot.name, anchor.name) if game % 2 == 0 else (anchor.name, snapshot.name)
            key = f"{cfg.name}/{snapshot.name}/{blue}-vs-{orange}/{game}"
            out.append(ScheduledMatch(len(out), key, blue, orange, match_seed(cfg.seed, f"{anchor.name}/{game}")))
    return out


def play_snapshots(cfg: CurveConfig, snapshots: Iterable[Snapshot], store: ResultsStore, report_dir: Path,
                   workers: int = 0, at_once: int = DEFAULT_AT_ONCE,
                   on_result: Callable[[ScheduledMatch, MatchResult], None] | None = None) -> int:
    """Play every snapshot's matches the store lacks; returns how many were played."""
    snapshots = list(snapshots)
    stored = store.keys()
    todo = [m for s in snapshots for m in snapshot_matches(cfg, s) if m.key not in stored]
    if not todo:
        return 0
    league = cfg.league({s.name: f"checkpoint:{s.path}" for s in snapshots}, store.path, report_dir)
    played = 0
    for match, result in play_local_matches(league, todo, workers, None, at_once):
        played += store.append(result)
        if on_result is not None:
            on_result(match, result)
    return played


def snapshot_points(match: ScheduledMatch, result: MatchResult, snapshot: str) -> float:
    """The snapshot's points in one match: win 1, draw 0.5, loss 0."""
    if result.winner is None:
        return 0.5
    return 1.0 if (result.winner == "blue") == (match.blue == snapshot) else 0.0


def rate_snapshot(cfg: CurveConfig, snapshot: Snapshot, results: dict[str, MatchResult]) -> CurvePoint | None:
    """The snapshot's rating from its stored matches, each against an anchor held at its pinned rating (the anchors
    never move); None if none of its matches is stored yet."""
    from openskill.models import PlackettLuce

    if not cfg.pinned:
        unpinned = [a.name for a in cfg.anchors if a.mu is None]
        raise ValueError(f"anchors: {unpinned} have no pinned mu/sigma; `rocketdrl-ma league-curve CONFIG "
                         "--pin-anchors` prints them")
    model = PlackettLuce()
    rating = model.rating(name=snapshot.name)
    points: dict[str, list[float]] = {}
    for match in snapshot_matches(cfg, snapshot):
        result = results.get(match.key)
        if result is None:
            continue
        anchor_name = match.orange if match.blue == snapshot.name else match.blue
        anchor = cfg.anchor(anchor_name)
        pinned = model.rating(mu=anchor.mu, sigma=anchor.sigma, name=anchor.name)
        mine = snapshot_points(match, result, snapshot.name)
        ranks = [1, 1] if mine == 0.5 else ([1, 2] if mine == 1.0 else [2, 1])
        [[rating], _] = model.rate([[rating], [pinned]], ranks=ranks)
        points.setdefault(anchor_name, []).append(mine)
    if not points:
        return None
    return CurvePoint(snapshot.name, snapshot.agent_steps, snapshot.train_hours, float(rating.mu),
                      float(rating.sigma), sum(map(len, points.values())),
                      {name: sum(p) / len(p) for name, p in points.items()})


def rating_curve(cfg: CurveConfig, snapshots: Iterable[Snapshot], store: ResultsStore) -> list[CurvePoint]:
    """Every snapshot's rating with at least one stored match, by step."""
    results = {r.match_key: r for r in store.results(key_prefix=f"{cfg.name}/")}
    rated = (rate_snapshot(cfg, s, results) for s in snapshots)
    return sorted((p for p in rated if p is not None), key=lambda p: p.agent_steps)


def pin_anchors(cfg: CurveConfig, store: ResultsStore, report_dir: Path, workers: int = 0,
                at_once: int = DEFAULT_AT_ONCE) -> dict[str, tuple[float, float]]:
    """Play the anchors' round robin (``matches_per_anchor`` rounds, sides alternating) and rate it: each anchor's
    (mu, sigma), the values to pin in the config."""
    from .ratings import rate
    from .schedule import schedule

    league = cfg.league({}, store.path, report_dir, rounds=cfg.matches_per_anchor, name=f"{cfg.name}-anchors")
    planned = schedule(league)
    stored = store.keys()
    for _, result in play_local_matches(league, [m for m in planned if m.key not in stored], workers, None,
                                        at_once):
        store.append(result)
    table = rate(league, planned, store.results(key_prefix=f"{league.name}/"))
    return {r.name: (r.mu, r.sigma) for r in table.ratings}


def write_curve_json(points: list[CurvePoint], path: Path) -> Path:
    rows = [{**asdict(p), "low": p.low, "high": p.high} for p in points]
    path.write_text(json.dumps(rows, indent=2) + "\n")
    return path

