"""Rating-curve configs: the fixed anchors every snapshot of a training run plays, and their pinned ratings.

```yaml
name: curve_2v2
match: matches/2v2.yaml          # the game config (teams of one size)
overrides: {clock_s: 120.0}      # its keys to replace
matches_per_anchor: 8            # games of every snapshot against every anchor, sides alternating
seed: 11000                      # every snapshot plays the same games: seed + a hash of <anchor>/<game>
anchors:                         # pinned ratings: `rocketdrl-ma league-curve CONFIG --pin-anchors` prints them
  - {name: idle, policy: "scripted:idle", mu: 14.2, sigma: 1.1}
  - {name: ball_chaser, policy: "scripted:ball_chaser", mu: 25.3, sigma: 1.0}
```
An anchor without ``mu``/``sigma`` can be pinned but not rated against.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rocketdrl_ma.config import load_yaml_file, resolve_shipped_path
from rocketdrl_ma.validation import as_mapping, check_int, check_name, check_number, reject_unknown

from .config import LeagueConfig, validate_league_config

CURVE_KEYS = ("name", "match", "overrides", "matches_per_anchor", "seed", "anchors")
ANCHOR_KEYS = ("name", "policy", "mu", "sigma")


@dataclass(frozen=True)
class Anchor:
    """A fixed opponent; ``mu``/``sigma`` are its pinned openskill rating (None until pinned)."""
    name: str
    policy: str
    mu: float | None = None
    sigma: float | None = None


@dataclass(frozen=True)
class CurveConfig:
    name: str
    match: str
    overrides: dict
    matches_per_anchor: int
    seed: int
    anchors: tuple[Anchor, ...]

    def anchor(self, name: str) -> Anchor:
        return next(a for a in self.anchors if a.name == name)

    @property
    def pinned(self) -> bool:
        return all(a.mu is not None for a in self.anchors)

    def league(self, players: dict[str, str], results: Path, report: Path, rounds: int = 1,
               name: str | None = None) -> LeagueConfig:
        """The league config that plays this curve's matches: the anchors and ``players`` (name -> policy spec)
        as entrants, ``results``/``report`` where they go; ``rounds`` and ``name`` for the anchors' own league."""
        entrants = [{"name": a.name, "policy": a.policy} for a in self.anchors]
        entrants += [{"name": name, "policy": spec} for name, spec in players.items()]
        return validate_league_config({
            "name": name or self.name, "match": self.match, "overrides": self.overrides, "format": "round_robin",
            "rounds": rounds, "matches_per_pair": self.matches_per_anchor, "seed": self.seed,
            "results": str(results), "report": str(report), "entrants": entrants})


def _anchor(i: int, raw: Any) -> Anchor:
    where = f"anchors[{i}]"
    d = as_mapping(where, raw, ANCHOR_KEYS)
    policy = d.get("policy")
    if not isinstance(policy, str) or ":" not in policy:
        raise ValueError(f"{where}.policy: expected a policy spec like 'scripted:ball_chaser', got {policy!r}")
    if ("mu" in d) != ("sigma" in d):
        raise ValueError(f"{where}: give both mu and sigma (a pinned rating) or neither, got {sorted(d)}")
    mu = check_number(f"{where}.mu", d["mu"]) if "mu" in d else None
    sigma = check_number(f"{where}.sigma", d["sigma"], above=0.0) if "sigma" in d else None
    return Anchor(check_name(f"{where}.name", d.get("name")), policy, mu, sigma)


def validate_curve_config(raw: Any) -> CurveConfig:
    if not isinstance(raw, dict):
        raise ValueError(f"curve config: expected a mapping, got {type(raw).__name__}")
    reject_unknown("curve config", raw, CURVE_KEYS)
    anchors_raw = raw.get("anchors")
    if not isinstance(anchors_raw, list) or len(anchors_raw) < 2:
        raise ValueError(f"anchors: expected a list of at least two anchors, got {anchors_raw!r}")
    anchors = tuple(_anchor(i, a) for i, a in enumerate(anchors_raw))
    names = [a.name for a in anchors]
    if len(set(names)) != len(names):
        raise ValueError(f"anchors: names must be unique, got {names}")
    seed = raw.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ValueError(f"seed: expected an int, got {seed!r}")
    cfg = CurveConfig(name=check_name("name", raw.get("name")), match=raw.get("match"),
                      overrides=as_mapping("overrides", raw.get("overrides")),
                      matches_per_anchor=check_int("matches_per_anchor", raw.get("matches_per_anchor", 8), minimum=1),
                      seed=seed, anchors=anchors)
    # the match config's own checks (mode 'match', teams of one size) are the league's
    cfg.league({}, Path("results.sqlite"), Path("report"))
    return cfg


def load_curve_config(path: str | Path, overrides: dict | None = None) -> CurveConfig:
    """A curve YAML (as given, else the shipped one); ``overrides`` replace its top-level keys."""
    raw = load_yaml_file(resolve_shipped_path(path, "curve config"), "curve config") or {}
    if not isinstance(raw, dict):
        raise ValueError(f"curve config: {path} must hold a mapping of keys to values")
    return validate_curve_config({**raw, **(overrides or {})})
