"""League configs: who plays, on which match config, how often, where results and the report go.

```yaml
name: scripted                 # prefix of every match_key: <name>/<round>/<blue>-vs-<orange>/<game>
match: matches/1v1.yaml        # the game config (2v2 and up: team entrants)
overrides: {clock_s: 300.0}    # its keys to replace
format: round_robin            # every pair once per round (sides alternate by round), or: per_pair
rounds: 2                      # round_robin: how many rounds
matches_per_pair: 4            # per_pair: matches between every pair (sides alternate)
seed: 0                        # match seeds: seed + a hash of the match key (stable when entrants join)
results: runs/league/results.sqlite
report: results/league         # report.md + ratings.png
server: {name: local, connect: [tcp/127.0.0.1:7447]}   # only for remote entrants
entrants:
  - {name: chaser, policy: scripted:ball_chaser}        # one policy drives every car of its team
  - {name: duo, members: [{name: keeper, policy: scripted:goalie}, {name: striker, policy: scripted:ball_chaser}]}
  - {name: alice, remote: true}  # a bot waiting with `rocketdrl-ma league-bot --entrant alice --policy ...`
```
Ratings are per player: an entrant with ``policy`` (or ``remote``) is one player, a team entrant's
members are one player each, rated as a team in the matches they play together.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from rocketdrl_ma.config import load_config, load_yaml_dataclass
from rocketdrl_ma.validation import Check, Expect, Name, OneOf, Range, load_dataclass

FORMATS = ("round_robin", "per_pair")
POLICY_SPEC = "a policy spec like 'scripted:ball_chaser' or 'checkpoint:PATH'"
ENDPOINTS = "a list of Zenoh endpoints like 'tcp/127.0.0.1:7447'"


def _check_policy_spec(field_name: str, spec: str) -> str:
    if ":" not in spec:
        raise ValueError(f"{field_name}: expected {POLICY_SPEC}, got {spec!r}")
    return spec


def _check_some(field_name: str, endpoints: tuple[str, ...]) -> tuple[str, ...]:
    if not endpoints:
        raise ValueError(f"{field_name}: expected {ENDPOINTS}, got []")
    return endpoints


PolicySpec = Annotated[str, Expect(POLICY_SPEC), Check(_check_policy_spec)]
PathText = Annotated[str, Expect("a path")]
AboveZero = Annotated[float, Range(above=0.0), Expect("a number > 0")]


@dataclass(frozen=True)
class Player:
    """One rated player: a team entrant's member (``{name, policy}``), or an entrant that drives every car of its
    team alone."""
    name: Name
    policy: PolicySpec | None
    """the policy spec; None: a remote bot"""


@dataclass(frozen=True)
class Entrant:
    """A side of a match: exactly one of ``policy`` (one player drives every car), ``members`` (one player per car,
    a team) or ``remote: true`` (a bot waiting on the match server)."""
    name: Name
    policy: PolicySpec | None = None
    members: tuple[Player, ...] | None = None
    remote: bool = False

    @property
    def players(self) -> tuple[Player, ...]:
        return self.members if self.members else (Player(self.name, self.policy),)

    def slot_players(self, team_size: int) -> list[Player]:
        """The player driving each of the team's cars, in slot order."""
        return list(self.players) if len(self.players) > 1 else [self.players[0]] * team_size


@dataclass(frozen=True)
class ServerLink:
    """How the league reaches the match server that remote entrants play on."""
    name: Name = "local"
    connect: Annotated[tuple[str, ...], Expect(ENDPOINTS), Check(_check_some)] = ("tcp/127.0.0.1:7447",)
    mode: Annotated[str, OneOf(("lockstep", "realtime"))] = "lockstep"
    deadline_ms: AboveZero = 200.0
    join_timeout_s: AboveZero = 60.0


@dataclass(frozen=True)
class LeagueConfig:
    """A league YAML's keys (the module docstring shows one); ``game_config`` and ``team_size`` follow from
    ``match`` and ``overrides``."""
    name: Name
    match: Annotated[str, Expect("the path of a match YAML like 'matches/1v1.yaml'")]
    entrants: Annotated[tuple[Entrant, ...], Expect("a list of at least 2 entrants")]
    overrides: Annotated[dict, Expect("a mapping of match config keys")] | None = None
    format: Annotated[str, OneOf(FORMATS)] = "round_robin"
    rounds: Annotated[int, Range(minimum=1)] = 1
    matches_per_pair: Annotated[int, Range(minimum=1)] = 2
    seed: int = 0
    results: PathText | None = None
    """default ``runs/league/<name>.sqlite``"""
    report: PathText | None = None
    """default ``runs/league/<name>``"""
    server: ServerLink = field(default_factory=ServerLink)

    def __post_init__(self) -> None:  # the defaults that depend on the league's name
        object.__setattr__(self, "overrides", self.overrides or {})
        object.__setattr__(self, "results", self.results or f"runs/league/{self.name}.sqlite")
        object.__setattr__(self, "report", self.report or f"runs/league/{self.name}")

    @functools.cached_property
    def game_config(self) -> dict[str, Any]:
        return load_config(self.match, self.overrides)

    @property
    def team_size(self) -> int:
        return int(self.game_config["team_size"] if self.game_config.get("blue_size") is None
                   else self.game_config["blue_size"])

    def check(self) -> None:
        game_config = self.game_config
        if game_config.get("mode") != "match":
            raise ValueError(f"match: {self.match} is a {game_config.get('mode')!r} config; a league needs mode "
                             "'match'")
        sizes = [game_config[key] if game_config.get(key) is not None else game_config["team_size"]
                 for key in ("blue_size", "orange_size")]
        if sizes[0] != sizes[1]:
            raise ValueError(f"blue_size/orange_size: a league plays every pair on both sides, so its match needs "
                             f"teams of one size; got {sizes[0]}v{sizes[1]} (set team_size only)")
        if len(self.entrants) < 2:
            raise ValueError(f"entrants: expected a list of at least 2 entrants, got {len(self.entrants)}")
        for i, entrant in enumerate(self.entrants):
            self._check_entrant(f"entrants[{i}]", entrant)
        names = [e.name for e in self.entrants]
        if len(set(names)) != len(names):
            raise ValueError(f"entrants: names must be unique, got {names}")
        players: dict[str, str | None] = {}
        for entrant in self.entrants:
            for player in entrant.players:
                if players.setdefault(player.name, player.policy) != player.policy:
                    raise ValueError(f"entrants: player {player.name!r} appears with two policies "
                                     f"({players[player.name]!r} and {player.policy!r})")

    def _check_entrant(self, where: str, entrant: Entrant) -> None:
        kinds = [k for k in ("policy", "members", "remote") if getattr(entrant, k) not in (None, False)]
        if len(kinds) != 1:
            raise ValueError(f"{where} ({entrant.name}): needs exactly one of policy, members, remote: true; got "
                             f"{kinds}")
        if entrant.members is not None and len(entrant.members) != self.team_size:
            raise ValueError(f"{where}.members: expected a list of {self.team_size} players (the match's "
                             f"team_size), got {len(entrant.members)}")
        for k, member in enumerate(entrant.members or ()):
            if member.policy is None:
                raise ValueError(f"{where}.members[{k}].policy: expected {POLICY_SPEC}, got None")

    def entrant(self, name: str) -> Entrant:
        return next(e for e in self.entrants if e.name == name)

    @property
    def players(self) -> list[Player]:
        seen: dict[str, Player] = {}
        for entrant in self.entrants:
            for player in entrant.players:
                seen.setdefault(player.name, player)
        return list(seen.values())


def validate_league_config(raw: Any) -> LeagueConfig:
    return load_dataclass(LeagueConfig, raw, "league config")


def load_league_config(path: str | Path, overrides: dict | None = None) -> LeagueConfig:
    """A league YAML (as given, else the shipped one); ``overrides`` replace its top-level keys."""
    return load_yaml_dataclass(LeagueConfig, path, "league config", overrides)
