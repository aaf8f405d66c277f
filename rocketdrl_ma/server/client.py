"""The client side of the protocol, shared by bots, spectators and lobby commands: which server key to
trust, lobby requests with verified replies, and checking the server's signed message streams.

Trusting the key (``trusted_server_key``): a pinned ``server_key``; else ``<key_dir>/server.pub`` (a client
on the server's machine, in its folder); else the key remembered for this server and endpoints in the
known-servers file; else, with ``trust_on_first_use``, the key the server announces on
``rocketdrl/<server>/key``, if exactly one key answers (several different ones are refused), remembered from
then on. A remembered key that no longer matches is never replaced silently: requests fail until the line
is removed from the known-servers file.
"""
from __future__ import annotations

import logging
import random
import threading
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .crypto import (KeyExchange, ServerKey, SignatureError, open_secret, parse_secret, random_bytes,
                     read_secret_file, request_mac)
from .members import SIGNED_OPS, load_member_key, request_text
from .protocol import Keys, ProtocolError, decode_space, open_sealed, pack, pack_value, unpack, unpack_map
from .settings import ClientSettings

log = logging.getLogger(__name__)
#: a generous bound on any server message (observations carry the game state); refuses absurd ones
MAX_SERVER_MESSAGE_BYTES = 4 * 1024 * 1024
#: the first and the longest pause between two tries of an unanswered ``inspect`` (doubling in between)
RETRY_FIRST_S, RETRY_MAX_S = 0.1, 4.0


class ServerError(RuntimeError):
    """The server answered a request with an error (the message says why)."""


class ServerGone(ConnectionError):
    """No reply signed by the server: it is not running (or someone else answers in its name)."""


def _known_key(client: ClientSettings) -> str:
    return f"{client.server} {','.join(sorted(client.zenoh.connect))}"


def _read_known(client: ClientSettings) -> str | None:
    path = client.known_servers_path
    if not path.is_file():
        return None
    wanted = _known_key(client)
    for line in path.read_text().splitlines():
        name, _, key = line.rpartition(" ")
        if name == wanted:
            return key
    return None


def _announced_keys(session, client: ClientSettings, timeout_s: float) -> set[ServerKey]:
    """Every key that answers on the well-known key, each proven by a signature over our fresh nonce."""
    import zenoh
    keys = Keys(client.server)
    nonce = random_bytes()
    found: set[ServerKey] = set()
    for reply in session.get(keys.key, payload=nonce, timeout=timeout_s,
                             consolidation=zenoh.ConsolidationMode.NONE):
        if reply.ok is None:
            continue
        try:
            message = unpack(reply.ok.payload.to_bytes(), 4096)
            body = unpack_map(message["body"], 4096, "body")
            key = ServerKey(body["key"])  # self-signed: proves the answerer holds this key, nothing more
            key.verify(message["body"], message["sig"])
        except (ProtocolError, SignatureError, KeyError, TypeError, ValueError):
            continue
        if body.get("kind") == "key" and body.get("server") == client.server and body.get("nonce") == nonce:
            found.add(key)
    return found


def trusted_server_key(session, client: ClientSettings, timeout_s: float = 5.0) -> tuple[ServerKey, str]:
    """The key to verify this server's messages with (see the module docstring for the order), and where
    it came from."""
    if client.server_key is not None:
        return ServerKey.parse(client.server_key), "pinned"
    pub = client.keys_path / "server.pub"
    if pub.is_file():
        return ServerKey.parse(pub.read_text().strip(), str(pub)), str(pub)
    known = _read_known(client)
    if known is not None:
        where = f"{client.known_servers_path} ({_known_key(client)})"
        return ServerKey.parse(known, where), f"remembered in {where}: remove that line if the server's key changed"
    if not client.trust_on_first_use:
        raise ValueError(f"server_key: no key pinned for server {client.server!r}; pass --server-key (printed by "
                         "`rocketdrl-ma serve`) or allow trust_on_first_use")
    found = _announced_keys(session, client, timeout_s)
    if not found:
        raise ServerGone(f"no match server {client.server!r} announced its key on {Keys(client.server).key}")
    if len(found) > 1:
        raise ValueError(f"server_key: {len(found)} different keys answer as server {client.server!r} "
                         f"({sorted(k.text for k in found)}); someone impersonates it: pin the real one with "
                         "--server-key")
    key = found.pop()
    path = client.known_servers_path
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as f:
        f.write(f"{_known_key(client)} {key.text}\n")
    log.warning("trusting server %r key %s on first use (remembered in %s)", client.server, key.text, path)
    return key, f"trusted on first use, remembered in {path}"


@dataclass
class JoinInfo:
    """The server's answer to a join: the seat, the slot's secret, and what the match looks like."""
    match: str
    instance: str
    slot: str
    user: str
    secret: bytes
    rejoin_key: bytes
    lease: str
    status: str
    mode: str
    deadline_ms: float
    decision_ticks: int
    config: dict
    observation: dict
    action: dict
    observation_space: Any
    action_space: Any
    keys: dict

    @classmethod
    def from_reply(cls, r: dict, secret: bytes, rejoin_key: bytes) -> "JoinInfo":
        return cls(match=r["match"], instance=r["instance"], slot=r["slot"], user=r["user"], secret=secret,
                   rejoin_key=rejoin_key, lease=r["lease"], status=r["status"], mode=r["mode"],
                   deadline_ms=r["deadline_ms"], decision_ticks=r["decision_ticks"], config=r["config"], observation=r["observation"],
                   action=r["action"], observation_space=decode_space(r["observation_space"]),
                   action_space=decode_space(r["action_space"]), keys=r["keys"])

    @property
    def rejoin_token(self) -> str:
        """``<slot>:<rejoin key as hex>``: what ``rocketdrl-ma bot --rejoin`` needs after a crash. Keep it private:
        it lets its holder take the slot back (with new keys), though it never signs an action."""
        return f"{self.slot}:{self.rejoin_key.hex()}"


def parse_rejoin_token(token: str) -> tuple[str, bytes]:
    """``<slot>:<rejoin key hex>``, or the path of a file holding it (``rocketdrl-ma bot`` writes one)."""
    path = Path(token)
    if ":" not in token and path.is_file():
        token = path.read_text().strip()
    slot, sep, key = token.partition(":")
    if not sep:
        raise ValueError("rejoin: expected '<slot>:<rejoin key hex>' or the file `rocketdrl-ma bot` wrote it to")
    return slot, parse_secret(key, "rejoin")


def read_ticket(value: str, slot: str | None) -> str:
    """A ticket as hex, or the tickets file ``rocketdrl-ma lobby create`` wrote (``slot ticket`` lines): ``slot``'s."""
    path = Path(value)
    if not path.is_file():
        return value
    tickets = dict(line.split(None, 1) for line in path.read_text().splitlines() if line.strip())
    if slot not in tickets:
        raise ValueError(f"ticket: {value} holds tickets for {sorted(tickets)}; name one with --slot")
    return tickets[slot].strip()


class LobbyClient:
    """Lobby requests over an open Zenoh session; only replies signed by the server's key count."""

    def __init__(self, session, client: ClientSettings | str | None = None, timeout_s: float = 5.0,
                 **client_fields):
        """``client``: a ``ClientSettings``, or just the server's name (its other fields as keywords)."""
        self.session = session
        if isinstance(client, str):
            client, client_fields = None, {**client_fields, "server": client}
        self.client = resolve_client(client, **client_fields)
        self.keys, self.user, self.timeout_s = Keys(self.client.server), self.client.user_name, timeout_s
        self._server_key: ServerKey | None = None
        self.key_source = ""
        key_path = self.client.user_key_path
        self.member_key = load_member_key(key_path) if key_path is not None else None  # signs a member's requests

    @property
    def server_key(self) -> ServerKey:
        if self._server_key is None:
            self._server_key, self.key_source = trusted_server_key(self.session, self.client, self.timeout_s)
        return self._server_key

    def admin_secret(self) -> bytes | None:
        if self.client.admin_secret is not None:
            return parse_secret(self.client.admin_secret, "admin_secret")
        path = self.client.admin_secret_file
        if path is None:
            default = self.client.keys_path / "admin.secret"
            path = str(default) if default.is_file() else None
        return read_secret_file(path, "admin_secret_file") if path is not None else None

    def request(self, op: str, args: dict | None = None, prove_with: bytes | None = None,
                nonce: bytes | None = None) -> dict:
        """One lobby op; the reply body, once verified. ``prove_with``: a secret to MAC a fresh challenge with."""
        return self._request(op, args, prove_with, nonce)[0]

    def _request(self, op: str, args: dict | None, prove_with: bytes | None,
                 nonce: bytes | None) -> tuple[dict, bytes]:
        """The verified reply body, and the signed reply as it came."""
        import zenoh
        server_key = self.server_key
        nonce = nonce or random_bytes()
        raw_args = pack_value(args or {})
        message = {"op": op, "nonce": nonce, "args": raw_args}
        signs = self.member_key is not None and op in SIGNED_OPS
        if prove_with is not None or signs:
            challenge = self.request("challenge")["challenge"]
            message["challenge"] = challenge
            if prove_with is not None:
                message["mac"] = request_mac(prove_with, op, self.keys.server, self.user, challenge, raw_args)
            if signs:
                message["user_sig"] = self.member_key.sign_tagged(
                    request_text(op, self.keys.server, self.user, challenge, nonce, raw_args))
        unverified: list[str] = []
        for reply in self.session.get(self.keys.lobby(self.user), payload=pack(message), timeout=self.timeout_s,
                                      consolidation=zenoh.ConsolidationMode.NONE):
            raw = (reply.ok if reply.ok is not None else reply.err).payload.to_bytes()
            try:
                body = open_sealed(server_key, raw, MAX_SERVER_MESSAGE_BYTES)
            except (ProtocolError, SignatureError):
                unverified.append(_describe_unverified(raw))
                continue
            if body.get("kind") != "reply" or body.get("server") != self.keys.server or body.get("nonce") != nonce \
                    or body.get("op") != op:
                unverified.append("a signed reply to another request")
                continue
            if body.get("ok") is True:
                return body, raw
            raise ServerError(f"{op}: {body.get('error')}")
        raise ServerGone(f"no reply signed by server {self.keys.server!r} ({server_key.text}, {self.key_source}) "
                         f"on {self.keys.lobby(self.user)}" +
                         (f"; {len(unverified)} unverified ({unverified[0]})" if unverified else ""))

    def create(self, config: str | dict, match_id: str | None = None, **options: Any) -> dict:
        """A new match (the admin role: the admin secret proves it). The reply's ``tickets`` map each slot
        that needs one to its ticket (hex), for the bots the creator invites (sealed to this request's key: no
        one else who gets the reply reads them); ``signed``: the server's signed reply as it came (a league
        sends it with its invitations, so its entrants know the server made their seats)."""
        exchange, nonce = KeyExchange(), random_bytes()
        args = {"config": config, **options, "client_key": exchange.public_bytes}
        if match_id is not None:
            args["id"] = match_id
        reply, signed = self._request("create", args, self.admin_secret(), nonce)
        reply["signed"] = signed
        key = exchange.tickets_key(reply["server_key_exchange"], nonce, self.keys.server, reply["id"])
        sealed = reply.pop("tickets_sealed")
        if not isinstance(sealed, bytes):
            raise ProtocolError("tickets_sealed: expected the sealed tickets (bin)")
        reply["tickets"] = unpack_map(open_secret(key, sealed), MAX_SERVER_MESSAGE_BYTES, "tickets")
        return reply

    def list(self) -> list[dict]:
        return self.request("list")["matches"]

    def members(self) -> dict[str, dict]:
        """The members the server manages now: ``{name: {"role", "key": raw Ed25519 public key}}``."""
        return self.request("members")["members"]

    def inspect(self, match: str, retry_s: float | None = None) -> dict:
        """The match's status, slots and counters. While no signed reply comes back (a flooded, rate-limited
        lobby; a lost reply) it asks again after ``Backoff``'s pauses for up to ``retry_s`` (default: the
        client's ``inspect_retry_s``; 0: one try), then raises ``ServerGone`` saying how long it tried."""
        backoff = Backoff(self.client.inspect_retry_s if retry_s is None else retry_s)
        while True:
            try:
                return self.request("inspect", {"match": match})
            except ServerGone as e:
                pause_s = backoff.next_pause_s()
                if pause_s is None:
                    raise backoff.gave_up(f"inspect {match!r}", e) from None
                log.info("inspect %r: no signed reply (%s); trying again in %.2f s", match, e, pause_s)
                time.sleep(pause_s)

    def stop(self, match: str) -> dict:
        return self.request("stop", {"match": match}, prove_with=self.admin_secret())

    def join(self, match: str, slot: str | None = None, ticket: str | None = None, **fields: Any) -> JoinInfo:
        """Take a slot (the named one or any this user may take); ``ticket``: the slot's ticket (hex) from
        the match's creator, unless the match is open or the slot is this user's seat."""
        exchange, nonce = KeyExchange(), random_bytes()
        args = {"match": match, "slot": slot, "client_key": exchange.public_bytes, **fields}
        reply = self.request("join", args, prove_with=parse_secret(ticket, "ticket") if ticket else None,
                             nonce=nonce)
        secret, rejoin_key = exchange.slot_keys(reply["server_key_exchange"], nonce, self.keys.server, match,
                                                reply["slot"])
        return JoinInfo.from_reply(reply, secret, rejoin_key)

    def rejoin(self, match: str, slot: str, rejoin_key: bytes) -> JoinInfo:
        """Take a slot back with its rejoin key; new keys replace the old ones (``rejoin_token`` changes)."""
        exchange, nonce = KeyExchange(), random_bytes()
        reply = self.request("rejoin", {"match": match, "slot": slot, "client_key": exchange.public_bytes},
                             prove_with=rejoin_key, nonce=nonce)
        return JoinInfo.from_reply(reply, *exchange.slot_keys(reply["server_key_exchange"], nonce, self.keys.server,
                                                              match, slot))

    def leave(self, match: str, slot: str, secret: bytes) -> dict:
        return self.request("leave", {"match": match, "slot": slot}, prove_with=secret)


class Backoff:
    """Pauses between the tries of a request without a signed reply: doubling from ``RETRY_FIRST_S`` up to
    ``RETRY_MAX_S``, each drawn at random below that (full jitter: clients a flood silenced together do not
    come back together), until ``total_s`` have passed since the first try."""

    def __init__(self, total_s: float):
        self.total_s, self.tries = total_s, 0
        self._give_up_at = time.monotonic() + total_s
        self._pause_s = RETRY_FIRST_S

    def next_pause_s(self) -> float | None:
        """After a failed try: the pause before the next one, or None once ``total_s`` is spent."""
        self.tries += 1
        remaining_s = self._give_up_at - time.monotonic()
        if remaining_s <= 0:
            return None
        pause_s = min(random.uniform(0.0, self._pause_s), remaining_s)
        self._pause_s = min(2 * self._pause_s, RETRY_MAX_S)
        return pause_s

    def gave_up(self, what: str, last: ServerGone) -> ServerGone:
        if self.tries == 1:
            return last
        return ServerGone(f"{what}: {self.tries} tries over {self.total_s:g} s (inspect_retry_s) got no signed "
                          f"reply; the server is gone or its lobby is flooded. Last: {last}")


def _describe_unverified(raw: bytes) -> str:
    try:
        message = unpack(raw)
    except ProtocolError:
        return raw[:80].decode("utf-8", "replace")  # e.g. Zenoh's own "Timeout"
    return str(message.get("error", "not signed by the server's key"))


class SealedStream:
    """The server's messages on one key, checked: signed by its key, of the expected kind, for this server,
    match instance (and slot), and newer than the last one accepted (``seq``). Anything else is dropped
    and counted in ``dropped`` by reason."""

    def __init__(self, key: ServerKey, server: str, match: str, instance: str, kinds: tuple[str, ...],
                 slot: str | None = None, dropped: Counter | None = None):
        self.key, self.kinds = key, kinds
        self.expected = {"server": server, "match": match, "instance": instance}
        if slot is not None:
            self.expected["slot"] = slot
        self.last_seq = -1
        self.dropped = dropped if dropped is not None else Counter()
        self._lock = threading.Lock()

    def open(self, payload: bytes) -> dict | None:
        try:
            body = open_sealed(self.key, payload, MAX_SERVER_MESSAGE_BYTES)
        except SignatureError:
            self.dropped["bad_signature"] += 1
            return None
        except ProtocolError:
            self.dropped["malformed"] += 1
            return None
        if body.get("kind") not in self.kinds or any(body.get(k) != v for k, v in self.expected.items()):
            self.dropped["wrong_stream"] += 1
            return None
        seq = body.get("seq")
        with self._lock:
            if isinstance(seq, bool) or not isinstance(seq, int) or seq <= self.last_seq:
                self.dropped["stale"] += 1
                return None
            self.last_seq = seq
        return body


def resolve_client(client: ClientSettings | None, **fields: Any) -> ClientSettings:
    """``client`` (default: a loopback client of ``local``) with the given keyword fields replaced
    (``server=``, ``zenoh=``, ``user=``, ``server_key=``...; None leaves a field as it is)."""
    changes = {k: v for k, v in fields.items() if v is not None}
    if client is None:
        return ClientSettings.from_dict(changes)
    return client.replace(**changes) if changes else client
