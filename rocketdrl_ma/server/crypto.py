"""The protocol's cryptography: who signs what, what each MAC covers, how a slot's secret is agreed.

- The server has an Ed25519 identity. It signs every message it sends (observations, state, events,
  errors, lobby replies) as ``Ed25519(SIGNED_TAG + body)``; clients pin its public key
  (``ed25519:<base64 of the 32 raw bytes>``).
- A slot's secret is agreed at the join by X25519: the bot sends a fresh public key, the server answers
  with its own (in the signed join reply), and both derive ``HKDF-SHA256(shared, salt=request nonce,
  info=SLOT_TAG + server + 0 + match + 0 + slot)`` (64 bytes: the first 32 the slot's secret, the next 32
  its rejoin key). Neither travels. Each action carries ``HMAC-SHA256(slot secret, ACTION_TAG + body)``; a
  rejoin proves the rejoin key (never the action key) and agrees new keys by a new exchange.
- A ``create`` carries a fresh X25519 key too: the tickets in its reply are sealed (ChaCha20-Poly1305) under
  ``HKDF-SHA256(shared, salt=request nonce, info=TICKETS_TAG + server + 0 + match)``, readable by the
  creator alone, whoever else receives the signed reply.
- Admin ops, joins with a ticket, rejoins and leaves carry ``HMAC-SHA256(key, REQUEST_TAG + op + 0 + server
  + 0 + user + 0 + challenge + args)`` where the challenge is a single-use nonce the server handed out
  and ``key`` the admin secret, the ticket or the slot secret (raw bytes; shown to people as hex).
"""
from __future__ import annotations

import base64
import binascii
import hashlib
import hmac
import os
import secrets
from pathlib import Path

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey, Ed25519PublicKey
from cryptography.hazmat.primitives.asymmetric.x25519 import X25519PrivateKey, X25519PublicKey
from cryptography.hazmat.primitives.ciphers.aead import ChaCha20Poly1305
from cryptography.hazmat.primitives.hashes import SHA256
from cryptography.hazmat.primitives.kdf.hkdf import HKDF

SIGNED_TAG = b"rocketdrl-ma/2 signed\x00"
ACTION_TAG = b"rocketdrl-ma/2 act\x00"
REQUEST_TAG = b"rocketdrl-ma/2 request\x00"
SLOT_TAG = b"rocketdrl-ma/2 slot\x00"
TICKETS_TAG = b"rocketdrl-ma/2 tickets\x00"
KEY_PREFIX = "ed25519:"
MAC_BYTES = 32
NONCE_BYTES = 16
SECRET_BYTES = 32


class SignatureError(ValueError):
    """A message that is not signed by the server's key."""


def public_key_text(raw: bytes) -> str:
    return KEY_PREFIX + base64.b64encode(raw).decode()


def parse_public_key(text: str, field: str = "server_key") -> bytes:
    """``ed25519:<base64>`` -> the 32 raw bytes; anything else is a ValueError naming ``field``."""
    if not isinstance(text, str) or not text.startswith(KEY_PREFIX):
        raise ValueError(f"{field}: expected '{KEY_PREFIX}<base64 of 32 bytes>' (printed by `rocketdrl-ma serve`), "
                         f"got {text!r}")
    try:
        raw = base64.b64decode(text[len(KEY_PREFIX):], validate=True)
    except binascii.Error:
        raw = b""
    if len(raw) != 32:
        raise ValueError(f"{field}: {text!r} does not hold a 32-byte Ed25519 public key")
    return raw


def parse_secret(text: str, field: str) -> bytes:
    """A secret shown as hex (admin secret, ticket, slot secret) -> its raw bytes."""
    try:
        raw = bytes.fromhex(text.strip()) if isinstance(text, str) else b""
    except ValueError:
        raw = b""
    if len(raw) < NONCE_BYTES:
        raise ValueError(f"{field}: expected a secret of at least {NONCE_BYTES} bytes written as hex")
    return raw


def random_bytes(n: int = NONCE_BYTES) -> bytes:
    return secrets.token_bytes(n)


def write_private(path: Path, data: bytes) -> None:
    """Create ``path`` readable by its owner only (never overwrites: a second server start keeps its keys)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as f:
        f.write(data)


def append_private(path: Path, data: bytes) -> None:
    """Append ``data`` to ``path``, creating it readable by its owner only if it does not exist yet."""
    if path.is_file():
        with open(path, "ab") as f:
            f.write(data)
    else:
        write_private(path, data)


def read_secret_file(path: str | Path, field: str) -> bytes:
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{field}: no such file {str(path)!r}")
    return parse_secret(p.read_text(), field)


def load_or_create_secret(path: Path) -> bytes:
    if not path.is_file():
        write_private(path, (random_bytes(SECRET_BYTES).hex() + "\n").encode())
    return read_secret_file(path, "admin secret")


class ServerIdentity:
    """The server's Ed25519 signing key."""

    def __init__(self, private: Ed25519PrivateKey):
        self._private = private
        self.public_bytes = private.public_key().public_bytes(serialization.Encoding.Raw,
                                                              serialization.PublicFormat.Raw)
        self.public_text = public_key_text(self.public_bytes)

    @classmethod
    def generate(cls) -> "ServerIdentity":
        return cls(Ed25519PrivateKey.generate())

    @classmethod
    def load_or_create(cls, path: Path) -> "ServerIdentity":
        """The key in ``path`` (PEM, PKCS#8), created with mode 0600 if missing, with ``<path>.pub`` beside it."""
        if not path.is_file():
            identity = cls.generate()
            write_private(path, identity._private.private_bytes(
                serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()))
            path.with_suffix(".pub").write_text(identity.public_text + "\n")
            return identity
        try:
            private = serialization.load_pem_private_key(path.read_bytes(), password=None)
        except ValueError:
            private = None
        if not isinstance(private, Ed25519PrivateKey):
            raise ValueError(f"key_dir: {path.name} is not an Ed25519 private key in PEM")
        return cls(private)

    def sign(self, body: bytes) -> bytes:
        return self._private.sign(SIGNED_TAG + body)

    def sign_tagged(self, tagged: bytes) -> bytes:
        """A signature over ``tagged`` as it is (a member's key signs its own tags, never ``SIGNED_TAG``)."""
        return self._private.sign(tagged)


class ServerKey:
    """A server's public key, as a client pins it."""

    def __init__(self, raw: bytes):
        self.raw = raw
        self.text = public_key_text(raw)
        self._public = Ed25519PublicKey.from_public_bytes(raw)

    @classmethod
    def parse(cls, text: str, field: str = "server_key") -> "ServerKey":
        return cls(parse_public_key(text, field))

    def verify(self, body: bytes, signature: bytes) -> None:
        try:
            self._public.verify(signature, SIGNED_TAG + body)
        except InvalidSignature:
            raise SignatureError("signature: not made by the server's key") from None

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ServerKey) and other.raw == self.raw

    def __hash__(self) -> int:
        return hash(self.raw)


def action_mac(secret: bytes, body: bytes) -> bytes:
    return hmac.digest(secret, ACTION_TAG + body, hashlib.sha256)


def request_mac(key: bytes, op: str, server: str, user: str, challenge: bytes, args: bytes) -> bytes:
    message = REQUEST_TAG + b"\x00".join(s.encode() for s in (op, server, user)) + b"\x00" + challenge + args
    return hmac.digest(key, message, hashlib.sha256)


def same_mac(given: object, expected: bytes) -> bool:
    return isinstance(given, bytes) and hmac.compare_digest(given, expected)


class KeyExchange:
    """One side of the X25519 exchange that gives a slot its secret."""

    def __init__(self):
        self._private = X25519PrivateKey.generate()
        self.public_bytes = self._private.public_key().public_bytes(serialization.Encoding.Raw,
                                                                    serialization.PublicFormat.Raw)

    def derive(self, peer_public: bytes, nonce: bytes, info: bytes, length: int = SECRET_BYTES) -> bytes:
        if not isinstance(peer_public, bytes) or len(peer_public) != 32:
            raise ValueError("client_key: expected the 32 raw bytes of an X25519 public key")
        try:
            shared = self._private.exchange(X25519PublicKey.from_public_bytes(peer_public))
        except ValueError:  # OpenSSL refuses low-order points (an all-zero shared secret)
            shared = bytes(32)
        if shared == bytes(32):
            raise ValueError("client_key: not a usable X25519 public key")
        return HKDF(algorithm=SHA256(), length=length, salt=nonce, info=info).derive(shared)

    def slot_keys(self, peer_public: bytes, nonce: bytes, server: str, match: str, slot: str) -> tuple[bytes, bytes]:
        """The slot's action secret and its rejoin key."""
        info = SLOT_TAG + b"\x00".join(s.encode() for s in (server, match, slot))
        keys = self.derive(peer_public, nonce, info, 2 * SECRET_BYTES)
        return keys[:SECRET_BYTES], keys[SECRET_BYTES:]

    def tickets_key(self, peer_public: bytes, nonce: bytes, server: str, match: str) -> bytes:
        return self.derive(peer_public, nonce, TICKETS_TAG + server.encode() + b"\x00" + match.encode())


_ONE_USE_NONCE = bytes(12)  # every key sealed with is derived for one message only


def seal_secret(key: bytes, plaintext: bytes) -> bytes:
    return ChaCha20Poly1305(key).encrypt(_ONE_USE_NONCE, plaintext, None)


def open_secret(key: bytes, sealed: bytes) -> bytes:
    """``seal_secret``'s plaintext; ValueError if ``sealed`` was not made under ``key``."""
    from cryptography.exceptions import InvalidTag
    try:
        return ChaCha20Poly1305(key).decrypt(_ONE_USE_NONCE, sealed, None)
    except (InvalidTag, TypeError):
        raise ValueError("tickets: not sealed to this request's key") from None
