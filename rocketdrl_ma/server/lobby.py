"""The match server: one Zenoh session, the lobby, the server's key, bot liveliness, several matches at once.

A lobby request is a Zenoh ``get`` on ``rocketdrl/<server>/u/<user>/lobby`` whose payload is the msgpack
map ``{"v": 2, "op": ..., "nonce": <16+ random bytes>, "args": <bin: msgpack map of the op's fields>}``,
plus ``"challenge"`` and ``"mac"`` for the ops that prove a secret (``crypto.request_mac``). The user in
the key is who asks: with Zenoh access control on, nobody else can query that key. Every reply, ok or
error, is sealed (signed) and echoes the request's ``op`` and ``nonce``: ``{"kind": "reply", "server",
"op", "nonce", "ok": true, ...}`` or ``{..., "ok": false, "error": "..."}``.

Ops: ``challenge`` (a single-use nonce for a MAC), ``list``, ``inspect``, ``create`` and ``stop`` (the
admin role and the admin secret; ``create``'s tickets come back sealed to the request's ``client_key``),
``join`` (an open match, the user's seat, or the slot's ticket), ``rejoin`` (the slot's rejoin key: new
keys), ``leave`` (the slot's secret) and ``members`` (the public keys of the members the server manages).
A member (``members.py``: a user added while the server runs) also signs its ``create``, ``stop``, ``join``,
``rejoin`` and ``leave`` with its key (``user_sig``, over the same single-use challenge).
"""
from __future__ import annotations

import logging
import secrets
import threading
import time
from collections import OrderedDict
from typing import Any

from rocketdrl_ma.config import load_config
from rocketdrl_ma.results import MatchResult, ResultsStore
from rocketdrl_ma.validation import check_name

from .access import acl_config, add_missing_users, read_users_file
from .crypto import (NONCE_BYTES, KeyExchange, ServerIdentity, load_or_create_secret, random_bytes, request_mac,
                     same_mac, seal_secret)
from .match import INTERNAL_ERROR, JoinRequest, MatchRunner
from .members import MEMBERS_FILE, SIGNED_OPS, MemberRegister, request_text
from .protocol import (ENDED_STATUSES, MAX_REQUEST_BYTES, Keys, ProtocolError, pack, pack_value, seal, unpack,
                       unpack_map)
from .settings import MEMBERS_USER, SERVER_USER, MatchOptions, ServerSettings

log = logging.getLogger(__name__)
OPS = ("challenge", "list", "inspect", "create", "stop", "join", "rejoin", "leave", "members")
PLAYER_OPS = ("join", "rejoin", "leave")
CHALLENGE_TTL_S = 30.0
MAX_CHALLENGES = 4096
MAX_NONCE_BYTES = 64


class RateLimiter:
    """Token buckets: ``rate_per_s`` requests per user name (``burst`` at once), and for names anyone may claim
    also ten times that in total (``allow(user, claimable=True)``). A user Zenoh authenticated is who sent the
    request, so its flood empties its own bucket only; a name is claimable without Zenoh users (the open mode)
    and among members (who share one Zenoh user): only a total bounds what the server signs for those. A
    queryable cannot bound a Zenoh session instead: a query carries its sender's ``source_info`` only if the
    sender sets it (and then any id it likes), and a process may open as many sessions as it wants."""

    def __init__(self, rate_per_s: float, burst: int, max_users: int = 4096):
        self.rate, self.burst, self.max_users = rate_per_s, burst, max_users
        self._buckets: OrderedDict[str, list[float]] = OrderedDict()
        self._total = [burst * 10.0, time.monotonic()]
        self._lock = threading.Lock()

    def _take(self, bucket: list[float], rate: float, burst: float, now: float) -> bool:
        bucket[0] = min(burst, bucket[0] + (now - bucket[1]) * rate)
        bucket[1] = now
        if bucket[0] < 1.0:
            return False
        bucket[0] -= 1.0
        return True

    def allow(self, user: str, claimable: bool = True) -> bool:
        if self.rate <= 0:
            return True
        now = time.monotonic()
        with self._lock:
            bucket = self._buckets.pop(user, None) or [float(self.burst), now]
            self._buckets[user] = bucket
            while len(self._buckets) > self.max_users:
                self._buckets.popitem(last=False)
            return self._take(bucket, self.rate, self.burst, now) and \
                (not claimable or self._take(self._total, self.rate * 10, self.burst * 10, now))


class Challenges:
    """Single-use server nonces, each issued to one user, valid for ``CHALLENGE_TTL_S``."""

    def __init__(self):
        self._issued: OrderedDict[bytes, tuple[str, float]] = OrderedDict()
        self._lock = threading.Lock()

    def issue(self, user: str) -> bytes:
        now = time.monotonic()
        with self._lock:
            while self._issued and (len(self._issued) >= MAX_CHALLENGES or
                                    next(iter(self._issued.values()))[1] < now):
                self._issued.popitem(last=False)
            challenge = random_bytes(NONCE_BYTES)
            self._issued[challenge] = (user, now + CHALLENGE_TTL_S)
            return challenge

    def take(self, user: str, challenge: Any) -> bool:
        """Whether ``challenge`` was issued to ``user`` and is still fresh; it is used up either way."""
        if not isinstance(challenge, bytes):
            return False
        with self._lock:
            issued = self._issued.pop(challenge, None)
        return issued is not None and issued[0] == user and issued[1] >= time.monotonic()


class MatchServer:
    """``MatchServer(settings).start()`` serves until ``close()``; matches run in their own threads."""

    def __init__(self, settings: ServerSettings, results_path: str | None = None):
        self.settings = settings
        self.keys = Keys(settings.name)
        key_dir = settings.keys_path
        self.identity = ServerIdentity.load_or_create(key_dir / "server.key")
        self.admin_secret = load_or_create_secret(key_dir / "admin.secret")
        self.store = ResultsStore(results_path or settings.results)
        self.matches: dict[str, MatchRunner] = {}
        self._lock = threading.Lock()
        self._store_lock = threading.Lock()
        self._rate = RateLimiter(settings.limits.requests_per_s, settings.limits.request_burst)
        self.members = MemberRegister(key_dir / MEMBERS_FILE)
        self._challenges = Challenges()
        self.session = None
        self._declared: list[Any] = []
        self.requests_rejected = 0
        self.requests_limited = 0

    # ------------------------------------------------------------------------------------------ lifecycle
    def zenoh_extra(self) -> dict[str, Any]:
        """Zenoh config the server adds to its own: with users, authentication and the ACL on its session."""
        access = self.settings.access
        if not access.enabled:
            return {}
        zenoh = self.settings.zenoh
        users_path = self.settings.users_path
        if zenoh.mode != "client":  # made on the first start, as the key and admin secret (a router reads it too)
            for user in add_missing_users(users_path, [*sorted(access.roles), MEMBERS_USER]):
                log.info("made a password for user %s in %s", user, users_path)
        users = read_users_file(users_path)
        extra: dict[str, Any] = {}
        if zenoh.mode == "client":  # behind a router, which holds the ACL: the server is its user "server"
            if SERVER_USER not in users:
                raise ValueError(f"access.users_file: no {SERVER_USER!r} user to connect to the router as")
            extra["transport/auth/usrpwd/user"] = SERVER_USER
            extra["transport/auth/usrpwd/password"] = users[SERVER_USER]
        else:
            missing = sorted({*access.roles, MEMBERS_USER} - set(users))
            if missing:
                raise ValueError(f"access.roles: users {missing} have no password in access.users_file")
            extra["transport/auth/usrpwd/dictionary_file"] = str(users_path)
            extra["access_control"] = acl_config(self.settings.name, access.roles)
        return extra

    def start(self) -> "MatchServer":
        self.session = self.settings.zenoh.open(self.zenoh_extra())
        try:
            s = self.session
            self._declared = [
                s.declare_queryable(self.keys.all_lobbies, self._on_query),
                s.declare_queryable(self.keys.key, self._on_key_query),
                s.liveliness().declare_subscriber(self.keys.all_bot_alive, self._on_liveliness, history=True),
                s.liveliness().declare_token(self.keys.server_alive),
            ]
            for entry in self.settings.matches:
                entry = dict(entry)
                match_id = entry.pop("id", None)
                self.create(MatchOptions.from_dict(entry, self.settings.match_defaults), match_id)
        except Exception:
            self.close()
            raise
        return self

    def close(self) -> None:
        with self._lock:
            matches = list(self.matches.values())
        for match in matches:
            match.stop()
        for match in matches:
            match.join_thread(10.0)
        for declared in reversed(self._declared):
            try:
                declared.undeclare()
            except Exception:
                pass
        self._declared = []
        if self.session is not None:
            self.session.close()
            self.session = None
        self.store.close()

    def __enter__(self) -> "MatchServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------------------------------ matches
    def _record(self, result: MatchResult) -> None:
        with self._store_lock:
            self.store.append(result)

    def create(self, options: MatchOptions, match_id: str | None = None, creator: str | None = None) -> MatchRunner:
        """A new match. ``creator`` None: trusted (the server's YAML, or code); a user: the lobby's limits
        apply (config names, bounds, quotas)."""
        match_id = check_name("id", match_id) if match_id is not None else secrets.token_hex(4)
        limits = self.settings.limits
        if options.seats and not self.settings.access.enabled and \
                not all(self.members.get(user) is not None for user in options.seats.values()):
            raise ValueError("seats: need authenticated users (an access section: Zenoh users and access control, "
                             "or members added by `rocketdrl-ma users add`); without them anyone may claim a "
                             "seat's user name. Use tickets instead")
        if creator is not None:
            limits.check_config_name(options.config)
            limits.check_options(options)
            try:
                limits.check_game(load_config(options.config, options.overrides))
            except ValueError as e:
                if "no such file" in str(e):  # never tell where the server looked
                    raise ValueError(f"config: no config {options.config!r} on this server") from None
                raise
        with self._lock:
            if match_id in self.matches:
                raise ValueError(f"id: a match {match_id!r} already exists on server {self.settings.name!r}")
            if creator is not None:
                live = [m for m in self.matches.values() if m.live]
                if len(live) >= limits.max_matches:
                    raise ValueError(f"limit: this server runs at most {limits.max_matches} matches at once; "
                                     "try again when one ends")
                if sum(m.creator == creator for m in live) >= limits.max_matches_per_user:
                    raise ValueError(f"limit: user {creator!r} already has {limits.max_matches_per_user} matches "
                                     "waiting or running")
            self._forget_old()
            runner = MatchRunner(match_id, options, self.session, self.keys, self.identity, self._record,
                                 creator=creator, limits=limits)
            self.matches[match_id] = runner
        runner.start()
        log.info("match %s created by %s (%s, %s)", match_id, creator or "the server", options.config, options.mode)
        return runner

    def _forget_old(self) -> None:
        """Keep at most ``max_finished_kept`` ended matches in memory (their results are in the store)."""
        ended = [m for m in self.matches.values() if m.status in ENDED_STATUSES]
        for match in ended[:max(0, len(ended) - self.settings.max_finished_kept + 1)]:
            del self.matches[match.id]

    def match(self, match_id: Any) -> MatchRunner:
        with self._lock:
            runner = self.matches.get(match_id) if isinstance(match_id, str) else None
        if runner is None:
            raise ValueError(f"match: no match {match_id!r} on server {self.settings.name!r}")
        return runner

    # ------------------------------------------------------------------------------------------ Zenoh side
    def _on_liveliness(self, sample) -> None:
        import zenoh
        parsed = self.keys.parse_bot_alive(str(sample.key_expr))
        if parsed is None:
            return
        user, match_id, slot, lease = parsed
        with self._lock:
            runner = self.matches.get(match_id)
        if runner is not None:
            runner.set_alive(user, slot, lease, sample.kind == zenoh.SampleKind.PUT)

    def _on_key_query(self, query) -> None:
        """The server's public key, signed with it over the asker's nonce (so a replayed answer is stale)."""
        payload = query.payload
        nonce = payload.to_bytes() if payload is not None else b""
        if len(nonce) > MAX_NONCE_BYTES:
            return
        query.reply(query.key_expr, seal(self.identity, {"kind": "key", "server": self.settings.name,
                                                         "nonce": nonce, "key": self.identity.public_bytes}))

    def _on_query(self, query) -> None:
        key = str(query.key_expr)
        user = self.keys.parse_lobby_user(key)
        if user is None:
            return
        access = self.settings.access
        if not self._rate.allow(user, claimable=not (access.enabled and user in access.roles)):
            # unsigned and cheap: a flood must not make the server sign for it
            self.requests_limited += 1
            query.reply_err(pack({"ok": False, "error": "rate limited: too many lobby requests"}))
            return
        op, nonce = None, b""
        try:
            check_name("user", user)  # a wildcard query (u/*/lobby) names no user
            payload = query.payload
            if payload is None:
                raise ProtocolError("message: the lobby needs a msgpack request as the query payload")
            request = unpack(payload.to_bytes(), MAX_REQUEST_BYTES)
            op, nonce = request.get("op"), request.get("nonce")
            if not isinstance(nonce, bytes) or not NONCE_BYTES <= len(nonce) <= MAX_NONCE_BYTES:
                nonce = b""
                raise ProtocolError(f"nonce: expected {NONCE_BYTES}-{MAX_NONCE_BYTES} random bytes")
            reply = self.handle(user, request)
            query.reply(key, self._reply(op, nonce, {"ok": True, **reply}))
        except ValueError as e:  # ProtocolError included: every bad request gets a reason back
            self.requests_rejected += 1
            query.reply_err(self._reply(op, nonce, {"ok": False, "error": str(e)}))
        except Exception as e:
            log.exception("lobby request %r from %s failed (%s)", op, user, type(e).__name__)
            query.reply_err(self._reply(op, nonce, {"ok": False, "error": INTERNAL_ERROR}))

    def _reply(self, op: Any, nonce: bytes, body: dict) -> bytes:
        return seal(self.identity, {"kind": "reply", "server": self.settings.name,
                                    "op": op if isinstance(op, str) else None, "nonce": nonce, **body})

    # ------------------------------------------------------------------------------------------ lobby ops
    def handle(self, user: str, request: dict) -> dict:
        """Answer one lobby request (already decoded and version-checked) from ``user``."""
        op = request.get("op")
        if op not in OPS:
            raise ValueError(f"op: unknown lobby op {op!r}; allowed: {list(OPS)}")
        raw_args = request.get("args", b"\x80")
        if not isinstance(raw_args, bytes):
            raise ProtocolError("args: expected a bin holding the msgpack map of the op's fields")
        args = unpack_map(raw_args, MAX_REQUEST_BYTES, "args")
        access = self.settings.access
        # a user Zenoh knows is who it is; any other name is a member's only with the member's signature
        member = None if access.enabled and user in access.roles else self.members.get(user)
        role = member.role if member is not None else access.role(user)
        if role is None:
            raise ValueError(f"user: {user!r} has no role on this server")
        challenge_used = []

        def fresh_challenge() -> bool:
            """Whether the request's challenge was given to this user and is fresh (used up at the first check)."""
            if not challenge_used:
                challenge_used.append(self._challenges.take(user, request.get("challenge")))
            return challenge_used[0]

        def proves(key: bytes) -> bool:
            """A MAC under ``key`` over a challenge this user was given."""
            return fresh_challenge() and same_mac(request.get("mac"), request_mac(
                key, op, self.settings.name, user, request["challenge"], raw_args))

        if member is not None and op in SIGNED_OPS and not (fresh_challenge() and member.verify(
                request_text(op, self.settings.name, user, request["challenge"], request["nonce"], raw_args),
                request.get("user_sig"))):
            raise ValueError(f"op {op!r}: {user!r} is a member of this server: the request must be signed with its "
                             "key (user_key_file) over a fresh challenge (op challenge)")

        if op == "challenge":
            return {"challenge": self._challenges.issue(user)}
        if op == "list":
            with self._lock:
                runners = list(self.matches.values())
            return {"server": self.settings.name, "matches": [m.summary() for m in runners]}
        if op == "inspect":
            return self.match(args.get("match")).inspect()
        if op == "members":
            # zenoh_users: the users whose prefix Zenoh lets only them publish on (their runs need no signature)
            return {"members": {m.name: {"role": m.role, "key": m.public_key}
                                for m in self.members.members().values()},
                    "zenoh_users": sorted(access.roles) if access.enabled else []}
        if op in PLAYER_OPS and role == "spectator":
            raise ValueError(f"op {op!r}: user {user!r} is a spectator on this server")
        if op == "create":
            self._check_admin(op, user, role, proves, allow_players=access.create == "player")
            fields = {k: v for k, v in args.items() if k not in ("id", "client_key")}
            options = MatchOptions.from_dict(fields, self.settings.match_defaults)
            match_id = check_name("id", args["id"]) if args.get("id") is not None else secrets.token_hex(4)
            # the tickets are sealed to the creator's one-use key (covered by the request's MAC): whoever else
            # gets this signed reply, a relay that resent the request included, reads none
            exchange = KeyExchange()
            key = exchange.tickets_key(args.get("client_key"), request["nonce"], self.settings.name, match_id)
            runner = self.create(options, match_id, creator=user)
            return {**runner.inspect(), "creator_role": role, "server_key_exchange": exchange.public_bytes,
                    "tickets_sealed": seal_secret(key, pack_value(runner.tickets))}
        if op == "stop":
            runner = self.match(args.get("match"))
            own = access.create == "player" and access.enabled and runner.creator == user
            if not own:
                self._check_admin(op, user, role, proves)
            runner.stop()
            return {"match": runner.id}
        join = JoinRequest(user=user, args=args, nonce=request["nonce"], proves=proves)
        runner = self.match(args.get("match"))
        if op == "join":
            return runner.join(join)
        if op == "rejoin":
            return runner.rejoin(join)
        return runner.leave(join)

    def _check_admin(self, op: str, user: str, role: str, proves, allow_players: bool = False) -> None:
        if allow_players and role in ("admin", "player"):
            return
        if self.settings.access.enabled and role != "admin":
            raise ValueError(f"op {op!r}: needs the admin role; user {user!r} is a {role}")
        if not proves(self.admin_secret):
            raise ValueError(f"op {op!r}: needs the admin secret: a MAC over a fresh challenge (op challenge) "
                             "under this server's admin secret")
