"""Users the server manages itself, added while it runs (``rocketdrl-ma users add``).

Zenoh reads its users and access control only when its session opens, so a user added later cannot get a
Zenoh identity of its own. A *member* instead holds an Ed25519 key: ``users add NAME`` writes the private key
to ``<key_dir>/members/<NAME>.key`` (readable by its owner only) and a line ``NAME ROLE ed25519:<public>`` to
the register ``<key_dir>/members.txt``, which the running server reads again whenever the file changes. With
Zenoh users on, every member connects as the one Zenoh user ``members`` (its password made at the server's
first start, like the others); the generated access control lets it use the prefixes ``u/*/**`` except those
of the users Zenoh itself knows, so members cannot touch those users' keys, but the transport does not tell
one member from another. The server does, wherever it matters: a member's ``create``, ``stop``, ``join``,
``rejoin`` and ``leave`` carry ``Ed25519(MEMBER_TAG + op + 0 + server + 0 + user + 0 + challenge + nonce +
args)`` over a single-use challenge of the server, and a member's training run signs each message
(``RUN_TAG``); the page checks it against the key the server lists for that member (lobby op ``members``).
A member's name, whatever transport it came by, proves nothing without its key.
"""
from __future__ import annotations

import os
import threading
from dataclasses import dataclass
from pathlib import Path

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

from rocketdrl_ma.validation import check_name

from .crypto import ServerIdentity, append_private, parse_public_key, public_key_text, write_private
from .protocol import ProtocolError, pack, unpack, unpack_map
from .settings import MEMBERS_DIR, MEMBERS_USER

MEMBERS_FILE = "members.txt"
MEMBER_ROLES = ("admin", "player", "spectator")
MEMBER_TAG = b"rocketdrl-ma/2 member request\x00"
RUN_TAG = b"rocketdrl-ma/2 training run\x00"
#: the ops a member must sign: the ones that create, stop or take something
SIGNED_OPS = ("create", "stop", "join", "rejoin", "leave")


@dataclass(frozen=True)
class Member:
    name: str
    role: str
    public_key: bytes

    def verify(self, tagged: bytes, signature: object) -> bool:
        if not isinstance(signature, bytes):
            return False
        try:
            Ed25519PublicKey.from_public_bytes(self.public_key).verify(signature, tagged)
        except InvalidSignature:
            return False
        return True


def request_text(op: str, server: str, user: str, challenge: bytes, nonce: bytes, raw_args: bytes) -> bytes:
    """What a member's request signature covers: op, server, user, the server's challenge, the request's
    nonce (which the tickets and slot keys are bound to) and its args."""
    return MEMBER_TAG + b"\x00".join(s.encode() for s in (op, server, user)) + b"\x00" + challenge + nonce + raw_args


def run_text(server: str, user: str, run: str, body: bytes) -> bytes:
    """What a training run's message signature covers: the run it belongs to, and the message."""
    return RUN_TAG + b"\x00".join(s.encode() for s in (server, user, run)) + b"\x00" + body


def member_key_path(key_dir: str | Path, name: str) -> Path:
    return Path(key_dir) / MEMBERS_DIR / f"{check_name('user', name)}.key"


def load_member_key(path: str | Path) -> ServerIdentity:
    """A member's private key (PEM, as the server's own)."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"user_key_file: no such file {str(path)!r} (`rocketdrl-ma users add` writes it)")
    return ServerIdentity.load_or_create(p)


def read_members(path: str | Path) -> dict[str, Member]:
    """``NAME ROLE ed25519:...`` lines -> members by name (a bad line is a ValueError naming it)."""
    members: dict[str, Member] = {}
    for n, line in enumerate(Path(path).read_text().splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        parts = line.split()
        if len(parts) != 3 or parts[1] not in MEMBER_ROLES:
            raise ValueError(f"{MEMBERS_FILE} line {n}: expected 'NAME ROLE ed25519:KEY' with ROLE one of "
                             f"{list(MEMBER_ROLES)}")
        name = check_name(f"{MEMBERS_FILE} line {n}", parts[0])
        members[name] = Member(name, parts[1], parse_public_key(parts[2], f"{MEMBERS_FILE} line {n}"))
    return members


def add_member(key_dir: str | Path, name: str, role: str, reserved: tuple[str, ...] = ()) -> Path:
    """Make ``name``'s key (``<key_dir>/members/<name>.key``, mode 0600) and register its public key; the key's
    path. ``reserved``: names taken by the server's Zenoh users."""
    name = check_name("user", name)
    if role not in MEMBER_ROLES:
        raise ValueError(f"role: expected one of {list(MEMBER_ROLES)}, got {role!r}")
    register = Path(key_dir) / MEMBERS_FILE
    taken = set(read_members(register)) if register.is_file() else set()
    if name in taken or name in reserved or name == MEMBERS_USER:
        raise ValueError(f"user: {name!r} already exists on this server")
    key_path = member_key_path(key_dir, name)
    if key_path.exists():
        raise ValueError(f"user: {key_path} already exists; remove it to make a new key")
    identity = ServerIdentity.load_or_create(key_path)
    append_private(register, f"{name} {role} {identity.public_text}\n".encode())
    return key_path


def remove_member(key_dir: str | Path, name: str) -> None:
    """Take ``name`` out of the register: the running server refuses its key from its next request on."""
    register = Path(key_dir) / MEMBERS_FILE
    members = read_members(register) if register.is_file() else {}
    if name not in members:
        raise ValueError(f"user: no member {name!r} on this server (members: {sorted(members)})")
    kept = "".join(f"{m.name} {m.role} {public_key_text(m.public_key)}\n" for m in members.values() if m.name != name)
    tmp = register.with_suffix(".tmp")
    write_private(tmp, kept.encode())
    os.replace(tmp, register)


class MemberRegister:
    """The server's view of ``members.txt``: read again whenever the file's size or modification time changes
    (one ``stat`` a lookup), so members added or removed take effect without a restart."""

    def __init__(self, path: Path):
        self.path = path
        self._stamp: tuple[int, int] | None = None
        self._members: dict[str, Member] = {}
        self._lock = threading.Lock()

    def members(self) -> dict[str, Member]:
        try:
            st = self.path.stat()
            stamp = (st.st_mtime_ns, st.st_size)
        except FileNotFoundError:
            stamp = None
        with self._lock:
            if stamp != self._stamp:
                self._members = read_members(self.path) if stamp is not None else {}
                self._stamp = stamp
            return self._members

    def get(self, name: str) -> Member | None:
        return self.members().get(name)


def seal_run(key: ServerIdentity, server: str, user: str, run: str, packed_body: bytes) -> bytes:
    """A training run's message signed by its member's key: ``{"v", "body", "run_sig"}``."""
    return pack({"body": packed_body, "run_sig": key.sign_tagged(run_text(server, user, run, packed_body))})


def open_run(member: Member, server: str, user: str, run: str, payload: bytes, max_bytes: int) -> dict | None:
    """The message of ``user``'s run ``run`` if ``member``'s key signed it for that run; None otherwise."""
    try:
        message = unpack(payload, max_bytes)
        body = message.get("body")
        if not isinstance(body, bytes) or not member.verify(run_text(server, user, run, body), message.get("run_sig")):
            return None
        return unpack_map(body, max_bytes, "body")
    except ProtocolError:
        return None
