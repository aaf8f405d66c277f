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

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rocketdrl_ma.config import load_config, load_yaml_file, resolve_shipped_path
from rocketdrl_ma.validation import check_int, check_name, reject_unknown

LEAGUE_KEYS = ("name", "match", "overrides", "format", "rounds", "matches_per_pair", "seed", "results", "report",
               "server", "entrants")
FORMATS = ("round_robin", "per_pair")
ENTRANT_KEYS = ("name", "policy", "members", "remote")
SERVER_KEYS = ("name", "connect", "mode", "deadline_ms", "join_timeout_s")


@dataclass(frozen=True)
class Player:
    """One rated player: a policy spec, or a remote bot (``policy`` None)."""
    name: str
    policy: str | None


@dataclass(frozen=True)
class Entrant:
    """A side of a match. ``players`` has one player who drives every car, or one per car (a team)."""
    name: str
    players: tuple[Player, ...]
    remote: bool = False

    def slot_players(self, team_size: int) -> list[Player]:
        """The player driving each of the team's cars, in slot order."""
        return list(self.players) if len(self.players) > 1 else [self.players[0]] * team_size


@dataclass(frozen=True)
class ServerLink:
    """How the league reaches the match server that remote entrants play on."""
    name: str = "local"
    connect: tuple[str, ...] = ("tcp/127.0.0.1:7447",)
    mode: str = "lockstep"
    deadline_ms: float = 200.0
    join_timeout_s: float = 60.0


@dataclass(frozen=True)
class LeagueConfig:
    name: str
    match: str
    overrides: dict
    format: str
    rounds: int
    matches_per_pair: int
    seed: int
    results: str
    report: str
    server: ServerLink
    entrants: tuple[Entrant, ...]
    team_size: int
    game_config: dict

    def entrant(self, name: str) -> Entrant:
        return next(e for e in self.entrants if e.name == name)

    @property
    def players(self) -> list[Player]:
        seen: dict[str, Player] = {}
        for entrant in self.entrants:
            for player in entrant.players:
                seen.setdefault(player.name, player)
        return list(seen.values())


def _player(where: str, d: Any) -> Player:
    if not isinstance(d, dict):
        raise ValueError(f"{where}: expected a mapping with name and policy, got {d!r}")
    reject_unknown(where, d, ("name", "policy"))
    policy = d.get("policy")
    if not isinstance(policy, str) or ":" not in policy:
        raise ValueError(f"{where}.policy: expected a policy spec like 'scripted:ball_chaser' or "
                         f"'checkpoint:PATH', got {policy!r}")
    return Player(check_name(f"{where}.name", d.get("name")), policy)


def _entrant(i: int, d: Any, team_size: int) -> Entrant:
    where = f"entrants[{i}]"
    if not isinstance(d, dict):
        raise ValueError(f"{where}: expected a mapping with name and one of policy/members/remote, got {d!r}")
    reject_unknown(where, d, ENTRANT_KEYS)
    name = check_name(f"{where}.name", d.get("name"))
    kinds = [k for k in ("policy", "members", "remote") if d.get(k) not in (None, False)]
    if len(kinds) != 1:
        raise ValueError(f"{where} ({name}): needs exactly one of policy, members, remote: true; got {kinds}")
    if kinds == ["remote"]:
        if d["remote"] is not True:
            raise ValueError(f"{where}.remote: expected true, got {d['remote']!r}")
        return Entrant(name, (Player(name, None),), remote=True)
    if kinds == ["policy"]:
        return Entrant(name, (_player(where, {"name": name, "policy": d["policy"]}),))
    members = d["members"]
    if not isinstance(members, list) or len(members) != team_size:
        raise ValueError(f"{where}.members: expected a list of {team_size} players (the match's team_size), "
                         f"got {members!r}")
    return Entrant(name, tuple(_player(f"{where}.members[{k}]", m) for k, m in enumerate(members)))


def validate_league_config(raw: Any) -> LeagueConfig:
    if not isinstance(raw, dict):
        raise ValueError(f"league config: expected a mapping, got {type(raw).__name__}")
    reject_unknown("league config", raw, LEAGUE_KEYS)
    name = check_name("name", raw.get("name"))
    match = raw.get("match")
    if not isinstance(match, str):
        raise ValueError(f"match: expected the path of a match YAML like 'matches/1v1.yaml', got {match!r}")
    overrides = raw.get("overrides", {}) or {}
    if not isinstance(overrides, dict):
        raise ValueError(f"overrides: expected a mapping of match config keys, got {overrides!r}")
    game_config = load_config(match, overrides)
    if game_config.get("mode") != "match":
        raise ValueError(f"match: {match} is a {game_config.get('mode')!r} config; a league needs mode 'match'")
    sizes = [game_config[key] if game_config.get(key) is not None else game_config["team_size"]
             for key in ("blue_size", "orange_size")]
    if sizes[0] != sizes[1]:
        raise ValueError(f"blue_size/orange_size: a league plays every pair on both sides, so its match needs "
                         f"teams of one size; got {sizes[0]}v{sizes[1]} (set team_size only)")
    team_size = int(sizes[0])
    fmt = raw.get("format", "round_robin")
    if fmt not in FORMATS:
        raise ValueError(f"format: {fmt!r} is not one of {list(FORMATS)}")
    rounds = check_int("rounds", raw.get("rounds", 1), minimum=1)
    per_pair = check_int("matches_per_pair", raw.get("matches_per_pair", 2), minimum=1)
    seed = raw.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise ValueError(f"seed: expected an int, got {seed!r}")
    for key in ("results", "report"):
        if not isinstance(raw.get(key, ""), str):
            raise ValueError(f"{key}: expected a path, got {raw[key]!r}")
    entrants_raw = raw.get("entrants")
    if not isinstance(entrants_raw, list) or len(entrants_raw) < 2:
        raise ValueError(f"entrants: expected a list of at least 2 entrants, got {entrants_raw!r}")
    entrants = tuple(_entrant(i, d, team_size) for i, d in enumerate(entrants_raw))
    names = [e.name for e in entrants]
    if len(set(names)) != len(names):
        raise ValueError(f"entrants: names must be unique, got {names}")
    players: dict[str, str | None] = {}
    for entrant in entrants:
        for player in entrant.players:
            if players.setdefault(player.name, player.policy) != player.policy:
                raise ValueError(f"entrants: player {player.name!r} appears with two policies "
                                 f"({players[player.name]!r} and {player.policy!r})")
    return LeagueConfig(name=name, match=match, overrides=overrides, format=fmt, rounds=rounds,
                        matches_per_pair=per_pair, seed=seed,
                        results=raw.get("results", f"runs/league/{name}.sqlite"),
                        report=raw.get("report", f"runs/league/{name}"), server=_server(raw.get("server")),
                        entrants=entrants, team_size=team_size, game_config=game_config)


def _server(d: Any) -> ServerLink:
    if d is None:
        return ServerLink()
    if not isinstance(d, dict):
        raise ValueError(f"server: expected a mapping with {list(SERVER_KEYS)}, got {d!r}")
    reject_unknown("server", d, SERVER_KEYS)
    connect = d.get("connect", ServerLink.connect)
    if not isinstance(connect, (list, tuple)) or not connect or not all(isinstance(c, str) for c in connect):
        raise ValueError(f"server.connect: expected a list of Zenoh endpoints like 'tcp/127.0.0.1:7447', "
                         f"got {connect!r}")
    mode = d.get("mode", "lockstep")
    if mode not in ("lockstep", "realtime"):
        raise ValueError(f"server.mode: {mode!r} is not one of ['lockstep', 'realtime']")
    out = {}
    for key in ("deadline_ms", "join_timeout_s"):
        value = d.get(key, getattr(ServerLink, key))
        if isinstance(value, bool) or not isinstance(value, (int, float)) or value <= 0:
            raise ValueError(f"server.{key}: expected a number > 0, got {value!r}")
        out[key] = float(value)
    return ServerLink(name=check_name("server.name", d.get("name", "local")), connect=tuple(connect), mode=mode,
                      **out)


def load_league_config(path: str | Path, overrides: dict | None = None) -> LeagueConfig:
    """A league YAML (as given, else the shipped one); ``overrides`` replace its top-level keys."""
    raw = load_yaml_file(resolve_shipped_path(path, "league config"), "league config") or {}
    if not isinstance(raw, dict):
        raise ValueError(f"league config: {path} must hold a mapping of keys to values")
    return validate_league_config({**raw, **(overrides or {})})
