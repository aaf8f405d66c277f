"""Server, Zenoh and match settings: YAML in, validated dataclasses out (errors name the key).

A server YAML (``server/local.yaml``)::

    name: local                     # <server> in every key expression
    zenoh:                          # see ZenohSettings
      mode: peer
      listen: [tcp/127.0.0.1:7447]
    results: runs/server/results.sqlite
    admin_token: null               # if set, create and stop must carry it
    match_defaults: {mode: lockstep, deadline_ms: 50, ...}   # see MatchOptions
    matches: []                     # matches to create at start: MatchOptions keys plus ``id``
"""
from __future__ import annotations

import ipaddress
import json
import math
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import yaml

from .protocol import check_name

ZENOH_MODES = ("peer", "client", "router")
MATCH_MODES = ("lockstep", "realtime")
REPLACEMENTS = ("repeat", "neutral")
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"


def _unknown(section: str, given: dict, allowed) -> None:
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        raise ValueError(f"{section}: unknown key(s) {unknown}; allowed: {sorted(allowed)}")


def _endpoint_host(endpoint: str) -> str:
    """``tcp/127.0.0.1:7447`` -> ``127.0.0.1``; ``tcp/[::1]:7447`` -> ``::1``."""
    _, sep, address = endpoint.partition("/")
    if not sep:
        raise ValueError(f"zenoh.listen: {endpoint!r} is not a Zenoh endpoint like {DEFAULT_ENDPOINT!r}")
    address = address.split("#", 1)[0]
    host = address.rsplit(":", 1)[0]
    return host[1:-1] if host.startswith("[") and host.endswith("]") else host


def is_loopback_endpoint(endpoint: str) -> bool:
    host = _endpoint_host(endpoint)
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:  # a host name: only localhost is known to be loopback
        return False


@dataclass(frozen=True)
class ZenohSettings:
    """How a process joins the Zenoh network.

    ``mode``: peer (the embedded default: nothing else to run on one machine), client (through routers
    listed in ``connect``) or router. ``listen`` defaults to loopback for peers and routers; clients
    listen on nothing. Any non-loopback listen endpoint, and multicast scouting (which binds a UDP socket
    on every interface), need ``allow_remote: true``. ``tls`` and ``auth`` pass through to Zenoh's
    ``transport/link/tls/*`` and ``transport/auth/usrpwd/*`` keys (e.g. ``root_ca_certificate``,
    ``listen_private_key``, ``listen_certificate``; ``user``, ``password``, ``dictionary_file``);
    ``options`` sets any other Zenoh config key by its path.
    """
    mode: str = "peer"
    listen: tuple[str, ...] | None = None
    connect: tuple[str, ...] = ()
    multicast: bool = False
    allow_remote: bool = False
    tls: dict = field(default_factory=dict)
    auth: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: dict | None) -> "ZenohSettings":
        d = dict(d or {})
        _unknown("zenoh", d, [f.name for f in fields(cls)])
        for key in ("listen", "connect"):
            if d.get(key) is not None:
                if not (isinstance(d[key], (list, tuple)) and all(isinstance(e, str) for e in d[key])):
                    raise ValueError(f"zenoh.{key}: expected a list of endpoints like {DEFAULT_ENDPOINT!r}, "
                                     f"got {d[key]!r}")
                d[key] = tuple(d[key])
        for key in ("tls", "auth", "options"):
            if not isinstance(d.get(key, {}), dict):
                raise ValueError(f"zenoh.{key}: expected a mapping, got {d[key]!r}")
        settings = cls(**d)
        settings.check()
        return settings

    def check(self) -> None:
        if self.mode not in ZENOH_MODES:
            raise ValueError(f"zenoh.mode: {self.mode!r} is not one of {list(ZENOH_MODES)}")
        if self.mode == "client" and not self.connect:
            raise ValueError("zenoh.connect: client mode needs at least one router endpoint to connect to")
        if self.allow_remote:
            return
        remote = [e for e in self.listen_endpoints() if not is_loopback_endpoint(e)]
        if remote:
            raise ValueError(f"zenoh.listen: {remote} is not loopback; set zenoh.allow_remote: true to listen on "
                             "other interfaces")
        if self.multicast:
            raise ValueError("zenoh.multicast: multicast scouting binds every interface; it needs "
                             "zenoh.allow_remote: true")

    def listen_endpoints(self) -> tuple[str, ...]:
        if self.listen is not None:
            return self.listen
        return () if self.mode == "client" else (DEFAULT_ENDPOINT,)

    def with_overrides(self, listen: list[str] | None = None, connect: list[str] | None = None,
                       mode: str | None = None) -> "ZenohSettings":
        changed = replace(self, listen=tuple(listen) if listen is not None else self.listen,
                          connect=tuple(connect) if connect is not None else self.connect,
                          mode=mode or self.mode)
        changed.check()
        return changed

    def zenoh_config(self):
        """The ``zenoh.Config`` these settings describe."""
        import zenoh

        config = zenoh.Config()
        entries: list[tuple[str, Any]] = [
            ("mode", self.mode),
            ("scouting/multicast/enabled", self.multicast),
            ("listen/endpoints", list(self.listen_endpoints())),
            ("connect/endpoints", list(self.connect)),
        ]
        entries += [(f"transport/link/tls/{k}", v) for k, v in self.tls.items()]
        entries += [(f"transport/auth/usrpwd/{k}", v) for k, v in self.auth.items()]
        entries += list(self.options.items())
        for path, value in entries:
            try:
                config.insert_json5(path, json.dumps(value))
            except Exception as e:  # zenoh.ZError: the path or value is not one Zenoh knows
                raise ValueError(f"zenoh: cannot set {path!r} to {value!r} ({e})") from None
        return config

    def open(self):
        """A Zenoh session; a client that reaches no router is a ValueError naming the endpoints."""
        import zenoh
        try:
            return zenoh.open(self.zenoh_config())
        except zenoh.ZError as e:
            raise ValueError(f"zenoh: cannot open a {self.mode} session (connect {list(self.connect)}, "
                             f"listen {list(self.listen_endpoints())}): {e}") from None


@dataclass(frozen=True)
class MatchOptions:
    """How one match is played.

    ``config``: a game config path (``matches/2v2.yaml``, ``minigames/penalty.yaml``) or mapping;
    ``overrides``: config keys replaced for this match (``clock_s``, ``kickoff_countdown_s``...).
    ``mode``: lockstep (every decision waits for every connected bot up to ``deadline_ms``) or realtime
    (120 Hz wall clock, the latest action of each bot applies). ``replacement``: what a late, missing or
    refused action becomes: ``repeat`` (the slot's last action) or ``neutral``. ``ready_timeout_s``: the
    match starts when every slot holds a connected bot, or this long after it was created; ``fill``
    plays the empty slots then: a policy spec (``scripted:ball_chaser``) or ``idle``.
    """
    config: str | dict = "matches/1v1.yaml"
    overrides: dict = field(default_factory=dict)
    mode: str = "lockstep"
    deadline_ms: float = 50.0
    replacement: str = "repeat"
    ready_timeout_s: float = 30.0
    fill: str = "scripted:ball_chaser"
    seed: int | None = None

    @classmethod
    def from_dict(cls, d: dict, base: "MatchOptions | None" = None) -> "MatchOptions":
        if not isinstance(d, dict):
            raise ValueError(f"match options: expected a mapping, got {type(d).__name__}")
        _unknown("match options", d, [f.name for f in fields(cls)])
        options = replace(base or cls(), **d)
        options.check()
        return options

    def check(self) -> None:
        if not isinstance(self.config, (str, dict)):
            raise ValueError(f"config: expected a config path or mapping, got {self.config!r}")
        if not isinstance(self.overrides, dict):
            raise ValueError(f"overrides: expected a mapping of config keys, got {self.overrides!r}")
        if self.mode not in MATCH_MODES:
            raise ValueError(f"mode: {self.mode!r} is not one of {list(MATCH_MODES)}")
        if self.replacement not in REPLACEMENTS:
            raise ValueError(f"replacement: {self.replacement!r} is not one of {list(REPLACEMENTS)}")
        for name in ("deadline_ms", "ready_timeout_s"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or value < 0:
                raise ValueError(f"{name}: expected a finite number >= 0, got {value!r}")
        if not isinstance(self.fill, str) or not (self.fill == "idle" or ":" in self.fill):
            raise ValueError(f"fill: expected 'idle' or a policy spec like 'scripted:ball_chaser', got {self.fill!r}")
        if self.seed is not None and (isinstance(self.seed, bool) or not isinstance(self.seed, int)):
            raise ValueError(f"seed: expected an int or null, got {self.seed!r}")

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class ServerSettings:
    name: str = "local"
    zenoh: ZenohSettings = field(default_factory=ZenohSettings)
    results: str = "runs/server/results.sqlite"
    admin_token: str | None = None
    match_defaults: MatchOptions = field(default_factory=MatchOptions)
    matches: tuple[dict, ...] = ()
    max_finished_kept: int = 100

    @classmethod
    def from_dict(cls, d: dict) -> "ServerSettings":
        d = dict(d or {})
        _unknown("server", d, [f.name for f in fields(cls)])
        check_name("name", d.get("name", cls.name))
        if "zenoh" in d and not isinstance(d["zenoh"], ZenohSettings):
            d["zenoh"] = ZenohSettings.from_dict(d["zenoh"])
        if "match_defaults" in d and not isinstance(d["match_defaults"], MatchOptions):
            d["match_defaults"] = MatchOptions.from_dict(d["match_defaults"] or {})
        matches = d.get("matches") or []
        if not isinstance(matches, list):
            raise ValueError(f"matches: expected a list of match options, got {matches!r}")
        for i, m in enumerate(matches):
            if not isinstance(m, dict):
                raise ValueError(f"matches[{i}]: expected a mapping, got {m!r}")
            MatchOptions.from_dict({k: v for k, v in m.items() if k != "id"}, d.get("match_defaults"))
        d["matches"] = tuple(matches)
        if not isinstance(d.get("results", cls.results), str):
            raise ValueError(f"results: expected a file path, got {d['results']!r}")
        token = d.get("admin_token")
        if token is not None and (not isinstance(token, str) or not token):
            raise ValueError("admin_token: expected a non-empty string or null")
        return cls(**d)

    @classmethod
    def load(cls, path: str | Path) -> "ServerSettings":
        p = Path(path)
        if not p.is_file():
            raise ValueError(f"server config: no such file {str(path)!r}")
        raw = yaml.safe_load(p.read_text()) or {}
        if not isinstance(raw, dict):
            raise ValueError(f"server config: {path} must hold a mapping")
        return cls.from_dict(raw)


def load_zenoh_settings(path: str | Path) -> ZenohSettings:
    """The ``zenoh:`` section of a YAML file (a server or client config)."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"config: no such file {str(path)!r}")
    raw = yaml.safe_load(p.read_text()) or {}
    if not isinstance(raw, dict) or "zenoh" not in raw:
        raise ValueError(f"config: {path} has no 'zenoh' section")
    return ZenohSettings.from_dict(raw["zenoh"])
