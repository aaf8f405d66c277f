"""Server, client, Zenoh and match settings: YAML in, validated dataclasses out (errors name the key).

A server YAML (``server/local.yaml``)::

    name: local                     # <server> in every key expression
    zenoh:                          # see ZenohSettings
      mode: peer
      listen: [tcp/127.0.0.1:7447]
    results: runs/server/results.sqlite
    key_dir: runs/server/local      # the server's Ed25519 key and admin secret (created on first start)
    access: {...}                   # Zenoh users and their roles; see AccessSettings (absent: no authentication)
    limits: {...}                   # quotas and bounds on what the lobby accepts; see Limits
    match_defaults: {mode: lockstep, deadline_ms: 50, ...}   # see MatchOptions
    matches: []                     # matches to create at start: MatchOptions keys plus ``id``

A client YAML (``server/client.yaml``, or one written per user by ``rocketdrl-ma keys``): see ClientSettings.
"""
from __future__ import annotations

import fnmatch
import ipaddress
import json
import os
import re
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Annotated, Any

from rocketdrl_ma.config import load_yaml_mapping
from rocketdrl_ma.validation import Check, Expect, Name, OneOf, Range, check_choice, check_name, load_dataclass

from .protocol import MAX_MESSAGE_BYTES

ZENOH_MODES = ("peer", "client", "router")
MATCH_MODES = ("lockstep", "realtime")
REPLACEMENTS = ("repeat", "neutral")
ROLES = ("admin", "player", "spectator")
SERVER_USER = "server"  # the match server's own Zenoh user when it is a client of a router
MEMBERS_USER = "members"  # the one Zenoh user as whom every member the server manages connects (members.py)
MEMBERS_DIR = "members"  # in the key dir: each member's private key, <name>.key
LOCAL_USER = "local"  # who a client on the server's machine authenticates as unless it names a user
USERS_FILE = "users.txt"  # in the key dir unless access.users_file names another
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
DEFAULT_USER = "guest"  # a client without Zenoh authentication (loopback): just a name, proves nothing
_SECURE_PROTOCOLS = ("tls", "quic")
_CONFIG_NAME = re.compile(r"^([A-Za-z0-9_\-]+)/([A-Za-z0-9_\-]+)\.ya?ml$")

Endpoints = Annotated[tuple[str, ...], Expect(f"a list of endpoints like {DEFAULT_ENDPOINT!r}")]
PathText = Annotated[str, Expect("a path")]
Names = Annotated[tuple[str, ...], Expect("a list of names")]
Count = Annotated[int, Range(minimum=0), Expect("an integer >= 0")]
Amount = Annotated[float, Range(minimum=0), Expect("a finite number >= 0")]


def _endpoint_host(endpoint: str) -> str:
    """``tcp/127.0.0.1:7447`` -> ``127.0.0.1``; ``tcp/[::1]:7447`` -> ``::1``."""
    _, sep, address = endpoint.partition("/")
    if not sep:
        raise ValueError(f"zenoh: {endpoint!r} is not a Zenoh endpoint like {DEFAULT_ENDPOINT!r}")
    address = address.split("#", 1)[0].split("?", 1)[0]
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


def is_wildcard_endpoint(endpoint: str) -> bool:
    """Listening on every interface (0.0.0.0 or ::) unless the endpoint names one (``#iface=eth0``)."""
    if "iface=" in endpoint:
        return False
    try:
        return ipaddress.ip_address(_endpoint_host(endpoint)).is_unspecified
    except ValueError:
        return False


def is_encrypted_endpoint(endpoint: str) -> bool:
    return endpoint.split("/", 1)[0] in _SECURE_PROTOCOLS


@dataclass(frozen=True)
class ZenohSettings:
    """How a process joins the Zenoh network.

    ``mode``: peer (the embedded default: nothing else to run on one machine), client (through the
    server or routers listed in ``connect``) or router. ``listen`` defaults to loopback for peers and
    routers; clients listen on nothing. Secure by default: a non-loopback endpoint (listen or connect)
    must be TLS (``tls/`` or ``quic/``) unless ``insecure: true``; listening beyond loopback also needs
    ``allow_remote: true`` and a named address (never 0.0.0.0 or ``::`` unless ``any_interface: true``);
    multicast scouting needs ``allow_remote``. ``tls`` and ``auth`` pass through to Zenoh's
    ``transport/link/tls/*`` and ``transport/auth/usrpwd/*`` keys (``root_ca_certificate``,
    ``listen_certificate``, ``listen_private_key``, their ``*_base64`` forms; ``user``, ``password``,
    ``dictionary_file``); ``options`` sets any other Zenoh config key by its path. Gossip scouting and
    shared memory are off and Zenoh reassembles at most ``MAX_MESSAGE_BYTES`` per message, unless
    ``options`` says otherwise.
    """
    mode: Annotated[str, OneOf(ZENOH_MODES)] = "peer"
    listen: Endpoints | None = None
    connect: Endpoints = ()
    multicast: bool = False
    allow_remote: bool = False
    any_interface: bool = False
    insecure: bool = False
    tls: dict = field(default_factory=dict)
    auth: dict = field(default_factory=dict)
    options: dict = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: dict | None) -> "ZenohSettings":
        return load_dataclass(cls, d, "zenoh", "zenoh.")

    def check(self) -> None:
        if self.mode == "client" and not self.connect:
            raise ValueError("zenoh.connect: client mode needs at least one endpoint to connect to")
        remote = [e for e in self.listen_endpoints() if not is_loopback_endpoint(e)]
        if remote and not self.allow_remote:
            raise ValueError(f"zenoh.listen: {remote} is not loopback; set zenoh.allow_remote: true to listen on "
                             "other interfaces")
        if self.multicast and not self.allow_remote:
            raise ValueError("zenoh.multicast: multicast scouting binds every interface; it needs "
                             "zenoh.allow_remote: true")
        wildcard = [e for e in remote if is_wildcard_endpoint(e)]
        if wildcard and not self.any_interface:
            raise ValueError(f"zenoh.listen: {wildcard} listens on every interface; name this machine's address "
                             "on the bots' network (e.g. tls/192.0.2.10:7447) or an interface "
                             "(tls/0.0.0.0:7447#iface=eth0), or set zenoh.any_interface: true")
        if self.insecure:
            return
        plain = [e for e in (*remote, *self.connect) if not is_loopback_endpoint(e) and not is_encrypted_endpoint(e)]
        if plain:
            raise ValueError(f"zenoh: {plain} would carry plaintext beyond this machine; use tls/HOST:PORT with "
                             "zenoh.tls certificates (`rocketdrl-ma keys` makes them), or set zenoh.insecure: true "
                             "on a network you trust")

    def listen_endpoints(self) -> tuple[str, ...]:
        if self.listen is not None:
            return self.listen
        return () if self.mode == "client" else (DEFAULT_ENDPOINT,)

    def remote_listen(self) -> list[str]:
        return [e for e in self.listen_endpoints() if not is_loopback_endpoint(e)]

    def with_overrides(self, listen: list[str] | None = None, connect: list[str] | None = None,
                       mode: str | None = None) -> "ZenohSettings":
        changes = {"listen": listen, "connect": connect, "mode": mode or None}
        return ZenohSettings.from_dict({**_values(self), **{k: v for k, v in changes.items() if v is not None}})

    def zenoh_config(self, extra: dict[str, Any] | None = None):
        """The ``zenoh.Config`` these settings describe; ``extra`` adds config paths (e.g. the server's ACL)."""
        import zenoh

        config = zenoh.Config()
        entries: list[tuple[str, Any]] = [
            ("mode", self.mode),
            ("scouting/multicast/enabled", self.multicast),
            ("scouting/gossip/enabled", False),
            ("transport/shared_memory/enabled", False),
            ("transport/link/rx/max_message_size", MAX_MESSAGE_BYTES),
            ("listen/endpoints", list(self.listen_endpoints())),
            ("connect/endpoints", list(self.connect)),
        ]
        entries += [(f"transport/link/tls/{k}", v) for k, v in self.tls.items()]
        entries += [(f"transport/auth/usrpwd/{k}", v) for k, v in self.auth.items()]
        entries += list((extra or {}).items())
        entries += list(self.options.items())
        for path, value in entries:
            try:
                config.insert_json5(path, json.dumps(value))
            except Exception as e:  # zenoh.ZError: the path or value is not one Zenoh knows
                raise ValueError(f"zenoh: cannot set {path!r} to {value!r} ({e})") from None
        return config

    def open(self, extra: dict[str, Any] | None = None):
        """A Zenoh session; a client that reaches nobody is a ValueError naming the endpoints."""
        import zenoh
        try:
            return zenoh.open(self.zenoh_config(extra))
        except zenoh.ZError as e:
            raise ValueError(f"zenoh: cannot open a {self.mode} session (connect {list(self.connect)}, "
                             f"listen {list(self.listen_endpoints())}): {e}") from None


@dataclass(frozen=True)
class AccessSettings:
    """Who may connect, and what each user may do.

    ``users_file``: Zenoh's user/password dictionary (``user:password`` lines; default ``<key_dir>/users.txt``).
    The server (in peer mode) adds a random password for every user of ``roles`` it lacks when it starts,
    in a file readable by its owner only, as it makes its key; ``rocketdrl-ma keys`` does the same and writes
    client YAMLs. With users, Zenoh authenticates every connection and the server generates
    Zenoh access-control rules (default deny) from ``roles``: each user may use only its own key prefix
    ``rocketdrl/<server>/u/<user>/**`` (its lobby, its slots), read the public state and events, and
    fetch the server's key; ``admin`` users may also invite league entrants. ``roles``: user -> ``admin``
    (create and stop matches, with the admin secret as well), ``player`` (join matches) or ``spectator``
    (watch). ``create``: the role that may create matches (``admin``, or ``player`` to let players create
    their own, within the per-user limit). The user ``server`` is the server itself (router set-up).
    Without ``roles`` and ``users_file`` nobody is authenticated (the open mode, ``server/open.yaml``): every
    client is a ``player`` by the name it claims (demos on loopback only; admin ops still need the admin
    secret; seats are refused).
    """
    users_file: Annotated[str, Expect("a file path")] | None = None
    roles: Annotated[dict[str, str], Check(_check_roles)] = field(default_factory=dict)
    create: Annotated[str, OneOf(("admin", "player"))] = "admin"

    @classmethod
    def from_dict(cls, d: Any) -> "AccessSettings":
        return load_dataclass(cls, d, "access", "access.")

    @property
    def enabled(self) -> bool:
        return self.users_file is not None or bool(self.roles)

    def role(self, user: str) -> str | None:
        """The user's role; without authentication everyone is a player."""
        return self.roles.get(user) if self.enabled else "player"


@dataclass(frozen=True)
class Limits:
    """Quotas and bounds on what lobby clients may ask for (matches listed in the server YAML are trusted).

    ``max_matches`` waiting or running at once, ``max_matches_per_user`` of them created by one user;
    game clock, overtime (never unlimited), kickoff countdown and minigame time (``rounds`` x
    ``timeout_s``) bounds; ``deadline_ms`` and ``ready_timeout_s`` ranges; ``configs``: the folders a
    match config may be named from (``matches/2v2.yaml``); ``overrides``: the config keys a lobby request
    may change; ``fill``: the policy specs that may play empty slots (shell-style patterns);
    ``missed_streak``: that many missed decisions in a row count as a disconnect (the match stops waiting
    for the slot until its next action; 0: never); ``requests_per_s``/``request_burst``: lobby requests
    per user, ten times that in all (0: no limit). A slot's observation (the one its bot asks for at the
    join, or a lobby-created match's own) is built on the match thread at every decision, so it is
    bounded: ``observations``: the builders it may use (each part of a ``+``-joined spec);
    ``max_observation_floats``: its size; ``max_observation_rays``: the rays cast for it, summed over
    every ray sensor it joins (the builders' main cost).
    """
    max_matches: Count = 16
    max_matches_per_user: Count = 4
    max_clock_s: Amount = 900.0
    max_overtime_limit_s: Amount = 300.0
    max_kickoff_countdown_s: Amount = 10.0
    max_minigame_s: Amount = 900.0
    min_deadline_ms: Amount = 1.0
    max_deadline_ms: Amount = 2000.0
    max_ready_timeout_s: Amount = 3600.0
    missed_streak: Count = 10
    configs: Names = ("matches", "minigames")
    overrides: Names = ("clock_s", "overtime_limit_s", "kickoff_countdown_s", "boost_pads", "demos",
                                  "car_preset", "max_cycles", "observation", "action", "rounds", "timeout_s",
                                  "difficulty", "arena_shape")
    fill: Names = ("idle", "scripted:*")
    requests_per_s: Amount = 50.0
    request_burst: Count = 100
    observations: Annotated[Names, Check(_check_builders)] = (
        "general_sensors", "ray", "team_relative", "barrier_sensors", "aerial_sensors", "seed_sensors", "seed_barrier",
        "seed_aerial")
    max_observation_floats: Count = 1024
    max_observation_rays: Count = 64

    @classmethod
    def from_dict(cls, d: Any) -> "Limits":
        return load_dataclass(cls, d, "limits", "limits.")

    def check(self) -> None:
        if self.min_deadline_ms > self.max_deadline_ms:
            raise ValueError("limits.min_deadline_ms: larger than limits.max_deadline_ms")

    def check_config_name(self, config: Any) -> str:
        """A lobby ``config``: a name like ``matches/2v2.yaml`` from an allowed folder, nothing else."""
        m = _CONFIG_NAME.match(config) if isinstance(config, str) else None
        if m is None or m.group(1) not in self.configs:
            raise ValueError(f"config: expected a config name like 'matches/2v2.yaml' from the server's folders "
                             f"{list(self.configs)}, got {config!r}")
        return config

    def check_options(self, options: "MatchOptions") -> None:
        if not self.min_deadline_ms <= options.deadline_ms <= self.max_deadline_ms:
            raise ValueError(f"deadline_ms: {options.deadline_ms!r} is outside this server's range "
                             f"[{self.min_deadline_ms}, {self.max_deadline_ms}]")
        if options.ready_timeout_s > self.max_ready_timeout_s:
            raise ValueError(f"ready_timeout_s: {options.ready_timeout_s!r} is over this server's limit of "
                             f"{self.max_ready_timeout_s}")
        if not any(fnmatch.fnmatchcase(options.fill, pattern) for pattern in self.fill):
            raise ValueError(f"fill: {options.fill!r} is not allowed on this server; allowed: {list(self.fill)}")
        not_allowed = sorted(set(options.overrides) - set(self.overrides))
        if not_allowed:
            raise ValueError(f"overrides: {not_allowed} may not be changed on this server; allowed: "
                             f"{sorted(self.overrides)}")

    def check_observation(self, spec_name: str, builder, blue_size: int, orange_size: int) -> None:
        """A slot's observation builder (``spec_name``: its registry name, ``a+b`` for a joined one) within
        this server's allow-list and budget for a match of these team sizes."""
        from rocketdrl_ma.env.observations import CombinedObs, RaySensor

        not_allowed = sorted({part.strip() for part in spec_name.split("+")} - set(self.observations))
        if not_allowed:
            raise ValueError(f"observation: builder(s) {not_allowed} are not allowed on this server; allowed: "
                             f"{list(self.observations)} (limits.observations)")
        floats = int(builder.space(blue_size, orange_size).shape[0])
        if floats > self.max_observation_floats:
            raise ValueError(f"observation: {floats} floats a decision is over this server's limit of "
                             f"{self.max_observation_floats} (limits.max_observation_floats)")
        parts = builder.builders if isinstance(builder, CombinedObs) else [builder]
        rays = sum(part.n_rays for part in parts if isinstance(part, RaySensor))
        if rays > self.max_observation_rays:
            raise ValueError(f"observation: {rays} rays a decision (summed over its ray sensors) is over this server's "
                             f"limit of {self.max_observation_rays} (limits.max_observation_rays)")

    def check_game(self, config: dict) -> None:
        """Bounds on the resolved game config (after overrides)."""
        def bounded(key: str, limit: float, none_ok: bool = False) -> None:
            if key not in config:
                return
            value = config[key]
            if value is None and not none_ok:
                raise ValueError(f"{key}: must be set on this server (at most {limit})")
            if value is not None and not 0 <= value <= limit:
                raise ValueError(f"{key}: {value!r} is outside this server's range [0, {limit}]")
        bounded("clock_s", self.max_clock_s)
        bounded("overtime_limit_s", self.max_overtime_limit_s)
        bounded("kickoff_countdown_s", self.max_kickoff_countdown_s)
        if "timeout_s" in config:
            total = config["timeout_s"] * config.get("rounds", 1)
            if not 0 <= total <= self.max_minigame_s:
                raise ValueError(f"timeout_s: rounds x timeout_s = {total!r} s is over this server's limit of "
                                 f"{self.max_minigame_s}")


@dataclass(frozen=True)
class MatchOptions:
    """How one match is played.

    ``config``: a game config (``matches/2v2.yaml``, ``minigames/penalty.yaml``; the server YAML may also
    give a mapping); ``overrides``: config keys replaced for this match (``clock_s``, ``kickoff_countdown_s``...).
    ``mode``: lockstep (every decision waits for every connected bot up to ``deadline_ms``) or realtime
    (120 Hz wall clock, the latest action of each bot applies). ``replacement``: what a late, missing or
    refused action becomes: ``repeat`` (the slot's last action) or ``neutral``. ``ready_timeout_s``: the
    match starts when every slot holds a connected bot, or this long after it was created; ``fill``
    plays the empty slots then: a policy spec (``scripted:ball_chaser``) or ``idle``. ``open``: any
    player may join an empty slot; otherwise a slot needs its ticket (handed out by the match's creator)
    or a seat: ``seats`` maps slots to the user who alone may join them.
    """
    config: Annotated[str | dict, Expect("a config name or mapping")] = "matches/1v1.yaml"
    overrides: Annotated[dict, Expect("a mapping of config keys")] = field(default_factory=dict)
    mode: Annotated[str, OneOf(MATCH_MODES)] = "lockstep"
    deadline_ms: Amount = 50.0
    replacement: Annotated[str, OneOf(REPLACEMENTS)] = "repeat"
    ready_timeout_s: Amount = 30.0
    fill: Annotated[str, Check(_check_fill)] = "scripted:ball_chaser"
    seed: Annotated[int | None, Expect("an int or null")] = None
    open: bool = False
    seats: Annotated[dict[Name, Name], Expect("a mapping of slot to user")] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: dict, base: "MatchOptions | None" = None) -> "MatchOptions":
        return load_dataclass(cls, d, "match options", base=base)

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class ServerSettings:
    name: Name = "local"
    zenoh: ZenohSettings = field(default_factory=ZenohSettings)
    results: PathText = "runs/server/results.sqlite"
    key_dir: PathText | None = None
    access: AccessSettings = field(default_factory=AccessSettings)
    limits: Limits = field(default_factory=Limits)
    match_defaults: MatchOptions = field(default_factory=MatchOptions)
    matches: Annotated[tuple[dict, ...] | None, Expect("a list of match options"), Check(_listed)] = ()
    max_finished_kept: Count = 100

    @classmethod
    def from_dict(cls, d: dict) -> "ServerSettings":
        return load_dataclass(cls, d, "server")

    def check(self) -> None:
        for i, m in enumerate(self.matches):
            load_dataclass(MatchOptions, {k: v for k, v in m.items() if k != "id"}, f"matches[{i}]", f"matches[{i}].",
                           self.match_defaults)
        zenoh = self.zenoh
        if zenoh.remote_listen() and not self.access.enabled and not zenoh.insecure:
            raise ValueError(f"access.users_file: the server listens beyond loopback ({zenoh.remote_listen()}) "
                             "but authenticates nobody; add users (`rocketdrl-ma keys` writes them) or set "
                             "zenoh.insecure: true on a network you trust")

    @property
    def keys_path(self) -> Path:
        return Path(self.key_dir if self.key_dir is not None else f"runs/server/{self.name}")

    @property
    def users_path(self) -> Path:
        """The Zenoh users' passwords (``access.users_file``, default ``<key_dir>/users.txt``)."""
        return Path(self.access.users_file) if self.access.users_file else self.keys_path / USERS_FILE

    @classmethod
    def load(cls, path: str | Path) -> "ServerSettings":
        return cls.from_dict(load_yaml_mapping(path, "server config"))


def load_zenoh_settings(path: str | Path) -> ZenohSettings:
    """The ``zenoh:`` section of a YAML file (a server, router or client config)."""
    raw = load_yaml_mapping(path, "config")
    if "zenoh" not in raw:
        raise ValueError(f"config: {path} has no 'zenoh' section")
    return ZenohSettings.from_dict(raw["zenoh"])


def known_servers_path() -> Path:
    """Where clients remember the keys of servers they trusted on first use (like ssh's known_hosts)."""
    if os.environ.get("ROCKETDRL_MA_KNOWN_SERVERS"):
        return Path(os.environ["ROCKETDRL_MA_KNOWN_SERVERS"])
    base = os.environ.get("XDG_CONFIG_HOME") or os.path.join(os.path.expanduser("~"), ".config")
    return Path(base) / "rocketdrl-ma" / "known_servers"


@dataclass(frozen=True)
class ClientSettings:
    """How a bot, spectator or lobby client reaches a server and knows it is the real one.

    ``server``: the server's name. ``zenoh``: a client session (default: loopback ``tcp/127.0.0.1:7447``).
    ``user``: the client's user in key expressions (default: ``zenoh.auth.user``, else ``local`` when the
    server's folder holds its password, else ``guest``); with Zenoh authentication it must be the
    authenticated user. Without ``zenoh.auth``, a client on the server's machine authenticates with the
    password of its user (default ``local``) in ``<key_dir>/users.txt`` if it may read that file
    (``credentials_from`` then names it), as it finds the server's key there. ``server_key``: the server's public key
    (``ed25519:...``, printed by ``rocketdrl-ma serve``) to pin; without it the client uses
    ``<key_dir>/server.pub`` if that exists (same machine and folder as the server), else the key
    remembered in the known-servers file, else, with ``trust_on_first_use``, the one key the server
    announces (remembered from then on; several different announced keys are refused).
    ``admin_secret_file`` or ``admin_secret`` (hex): for create and stop (default
    ``<key_dir>/admin.secret`` if it exists). ``key_dir`` defaults to ``runs/server/<server>``.
    ``user_key_file``: the private key of a member the server manages (``rocketdrl-ma users add``; default
    ``<key_dir>/members/<user>.key`` if readable): its requests and training runs are signed with it, and on the
    server's machine it connects as the Zenoh user ``members`` with that user's password from ``users.txt``.
    ``inspect_retry_s``: how long an ``inspect`` (a waiting bot's "is my match still on?") goes on asking,
    with exponential backoff and jitter, while no signed reply comes back (a lobby rate-limited by a flood,
    a lost reply) before the server counts as gone; 0: one try.
    """
    server: Name = "local"
    zenoh: ZenohSettings = field(default_factory=lambda: ZenohSettings(mode="client", connect=(DEFAULT_ENDPOINT,)))
    user: Name | None = None
    server_key: Annotated[str, Check(_check_public_key)] | None = None
    key_dir: PathText | None = None
    admin_secret_file: PathText | None = None
    admin_secret: Annotated[str, Check(_check_secret)] | None = None
    trust_on_first_use: bool = True
    known_servers: PathText | None = None
    inspect_retry_s: Annotated[float, Range(minimum=0), Expect("a finite number of seconds >= 0")] = 30.0
    credentials_from: PathText | None = None
    user_key_file: PathText | None = None

    @classmethod
    def from_dict(cls, d: dict) -> "ClientSettings":
        settings = load_dataclass(cls, d, "client")
        if not settings.zenoh.auth and settings.credentials_from is None:
            settings = settings._with_local_credentials()
        return settings

    def check(self) -> None:
        if self.zenoh.mode != "client":
            raise ValueError(f"zenoh.mode: a bot, spectator or lobby client connects as a client (Zenoh access "
                             f"control does not hold for peers), got {self.zenoh.mode!r}")
        auth_user = self.zenoh.auth.get("user")
        if auth_user == MEMBERS_USER:
            if self.user is None or self.user_key_path is None:
                raise ValueError(f"user: a client authenticated as {MEMBERS_USER!r} is a member: name it (user) and "
                                 "its key (user_key_file, written by `rocketdrl-ma users add`)")
        elif auth_user is not None and self.user is not None and auth_user != self.user:
            raise ValueError(f"user: {self.user!r} differs from zenoh.auth.user {auth_user!r}; the server "
                             "knows a client by its authenticated user")

    def _with_local_credentials(self) -> "ClientSettings":
        """With the password of its user from the server's folder, if that file is there and readable."""
        path = self.keys_path / USERS_FILE
        try:
            lines = path.read_text().splitlines()
        except OSError:  # no server in this folder, or another OS user's: no credentials
            return self
        user = self.user or LOCAL_USER
        passwords = {}
        for line in lines:
            name, sep, password = line.partition(":")
            if sep and password:
                passwords[name] = password
        if user in passwords:
            return replace(self, zenoh=replace(self.zenoh, auth={"user": user, "password": passwords[user]}),
                           credentials_from=str(path))
        if self.user is not None and MEMBERS_USER in passwords and self.user_key_path is not None:
            return replace(self, zenoh=replace(self.zenoh, auth={"user": MEMBERS_USER,
                                                                 "password": passwords[MEMBERS_USER]}),
                           credentials_from=str(path))
        return self

    @classmethod
    def load(cls, path: str | Path, **overrides: Any) -> "ClientSettings":
        raw = load_yaml_mapping(path, "client config")
        return cls.from_dict({**raw, **{k: v for k, v in overrides.items() if v is not None}})

    def replace(self, **changes: Any) -> "ClientSettings":
        current = _values(self)
        if self.credentials_from is not None and "zenoh" not in changes and \
                {"user", "key_dir", "server", "user_key_file"} & {k for k, v in changes.items() if v is not None}:
            current.update(zenoh=replace(self.zenoh, auth={}), credentials_from=None)  # found again for the change
        return ClientSettings.from_dict({**current, **changes})

    @property
    def user_name(self) -> str:
        return self.user or self.zenoh.auth.get("user") or DEFAULT_USER

    @property
    def keys_path(self) -> Path:
        return Path(self.key_dir if self.key_dir is not None else f"runs/server/{self.server}")

    @property
    def user_key_path(self) -> Path | None:
        """The member key this client signs with: ``user_key_file``, else its user's key in the server's folder
        if this process may read it, else None."""
        if self.user_key_file is not None:
            return Path(self.user_key_file)
        default = self.keys_path / MEMBERS_DIR / f"{self.user_name}.key"
        try:
            return default if default.is_file() and os.access(default, os.R_OK) else None
        except OSError:  # another OS user's folder
            return None

    @property
    def known_servers_path(self) -> Path:
        return Path(self.known_servers) if self.known_servers else known_servers_path()


def _values(settings: Any) -> dict[str, Any]:
    """A settings dataclass's values by field, to load again with some changed."""
    return {f.name: getattr(settings, f.name) for f in fields(settings)}


def _listed(field_name: str, entries: tuple | None) -> tuple:
    """An empty list written as null (``matches:``) is empty."""
    return entries or ()


def _check_roles(field_name: str, roles: dict[str, str]) -> dict[str, str]:
    for user, role in roles.items():
        check_name(f"{field_name} user", user)
        if user == SERVER_USER:
            raise ValueError(f"{field_name}: {SERVER_USER!r} is the match server's own user; give it no role")
        if user == MEMBERS_USER:
            raise ValueError(f"{field_name}: {MEMBERS_USER!r} is the Zenoh user the server's members share "
                             "(`rocketdrl-ma users add`); give it no role")
        check_choice(f"{field_name}.{user}", role, ROLES)
    return roles


def _check_builders(field_name: str, names: tuple[str, ...]) -> tuple[str, ...]:
    from rocketdrl_ma.env.observations import OBS_BUILDERS

    unknown = sorted(set(names) - set(OBS_BUILDERS))
    if unknown:
        raise ValueError(f"{field_name}: {unknown} are not observation builders; allowed: {sorted(OBS_BUILDERS)}")
    return names


def _check_fill(field_name: str, spec: str) -> str:
    if not (spec == "idle" or ":" in spec):
        raise ValueError(f"{field_name}: expected 'idle' or a policy spec like 'scripted:ball_chaser', got {spec!r}")
    return spec


def _check_public_key(field_name: str, key: str) -> str:
    from .crypto import parse_public_key  # imported when a key is given: the crypto library loads slowly

    parse_public_key(key, field_name)
    return key


def _check_secret(field_name: str, secret: str) -> str:
    from .crypto import parse_secret

    parse_secret(secret, field_name)
    return secret
