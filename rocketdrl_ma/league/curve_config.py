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
from typing import Annotated, Any

from rocketdrl_ma.config import load_yaml_dataclass
from rocketdrl_ma.validation import Expect, Name, Range, load_dataclass

from .config import LeagueConfig, PolicySpec, validate_league_config


@dataclass(frozen=True)
class Anchor:
    """A fixed opponent; ``mu``/``sigma`` are its pinned openskill rating (None until pinned)."""
    name: Name
    policy: PolicySpec
    mu: float | None = None
    sigma: Annotated[float, Range(above=0.0), Expect("a number > 0")] | None = None

    def check(self) -> None:
        if (self.mu is None) != (self.sigma is None):
            raise ValueError(f"anchor {self.name}: give both mu and sigma (a pinned rating) or neither")


@dataclass(frozen=True)
class CurveConfig:
    """A curve YAML's keys (the module docstring shows one)."""
    name: Name
    match: Annotated[str, Expect("the path of a match YAML like 'matches/2v2.yaml'")]
    anchors: Annotated[tuple[Anchor, ...], Expect("a list of at least two anchors")]
    overrides: Annotated[dict, Expect("a mapping of match config keys")] | None = None
    matches_per_anchor: Annotated[int, Range(minimum=1)] = 8
    seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "overrides", self.overrides or {})

    def check(self) -> None:
        if len(self.anchors) < 2:
            raise ValueError(f"anchors: expected a list of at least two anchors, got {len(self.anchors)}")
        names = [a.name for a in self.anchors]
        if len(set(names)) != len(names):
            raise ValueError(f"anchors: names must be unique, got {names}")
        # the match config's own checks (mode 'match', teams of one size) are the league's
        self.league({}, Path("results.sqlite"), Path("report"))

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
        entrants += [{"name": player, "policy": spec} for player, spec in players.items()]
        return validate_league_config({
            "name": name or self.name, "match": self.match, "overrides": self.overrides, "format": "round_robin",
            "rounds": rounds, "matches_per_pair": self.matches_per_anchor, "seed": self.seed,
            "results": str(results), "report": str(report), "entrants": entrants})


def validate_curve_config(raw: Any) -> CurveConfig:
    return load_dataclass(CurveConfig, raw, "curve config")


def load_curve_config(path: str | Path, overrides: dict | None = None) -> CurveConfig:
    """A curve YAML (as given, else the shipped one); ``overrides`` replace its top-level keys."""
    return load_yaml_dataclass(CurveConfig, path, "curve config", overrides)
