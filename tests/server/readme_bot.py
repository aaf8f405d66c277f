"""A bot written from the wire protocol page (docs/guides/wire-protocol.md) alone: plain Python with msgpack, zenoh and
cryptography, no import of rocketdrl_ma. It joins a match, checks every message the server signs, and
drives its car at the ball with the continuous action format until the match ends.

    python tests/server/readme_bot.py --connect tcp/127.0.0.1:7447 --server local --match M
        --server-key ed25519:... [--slot blue_0] [--ticket HEX] [--user guest]

Prints ``joined SLOT`` once seated and ``done REASON DECISIONS DROPPED`` at the end.
"""
from __future__ import annotations

import argparse
import base64
import hashlib
import hmac
import json
import math
import os
import queue
import struct
import sys
import time

import msgpack
import zenoh
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey
from cryptography.hazmat.primitives.asymmetric.x25519 import X25519PrivateKey, X25519PublicKey
from cryptography.hazmat.primitives.hashes import SHA256
from cryptography.hazmat.primitives.kdf.hkdf import HKDF

VERSION = 2


def packb(value) -> bytes:
    return msgpack.packb(value, use_bin_type=True)


def array(d: dict) -> list[float]:
    """A ``{"$nd": dtype, "shape": [...], "data": bytes}`` map as a flat list (little-endian floats here)."""
    codes = {"<f4": "f", "<f8": "d", "<i8": "q", "<i4": "i", "|b1": "?", "|u1": "B"}
    code = codes[d["$nd"]]
    n = len(d["data"]) // struct.calcsize(code)
    return list(struct.unpack(f"<{n}{code}", d["data"]))


class Server:
    def __init__(self, session, name: str, user: str, key_text: str):
        self.session, self.name, self.user = session, name, user
        raw = base64.b64decode(key_text.split(":", 1)[1])
        self.key = Ed25519PublicKey.from_public_bytes(raw)

    def open(self, payload: bytes) -> dict | None:
        """The body of a signed server message, or None if the signature does not hold."""
        try:
            message = msgpack.unpackb(payload, raw=False)
            self.key.verify(message["sig"], b"rocketdrl-ma/2 signed\x00" + message["body"])
            return msgpack.unpackb(message["body"], raw=False, strict_map_key=False)
        except Exception:
            return None

    def request(self, op: str, args: dict, proof_key: bytes | None = None, nonce: bytes | None = None) -> dict:
        nonce = nonce or os.urandom(16)
        raw_args = packb(args)
        message = {"v": VERSION, "op": op, "nonce": nonce, "args": raw_args}
        if proof_key is not None:
            challenge = self.request("challenge", {})["challenge"]
            mac_input = (b"rocketdrl-ma/2 request\x00" + op.encode() + b"\x00" + self.name.encode() + b"\x00"
                         + self.user.encode() + b"\x00" + challenge + raw_args)
            message.update(challenge=challenge, mac=hmac.digest(proof_key, mac_input, hashlib.sha256))
        replies = self.session.get(f"rocketdrl/{self.name}/u/{self.user}/lobby", payload=packb(message), timeout=5.0,
                                   consolidation=zenoh.ConsolidationMode.NONE)
        for reply in replies:
            sample = reply.ok if reply.ok is not None else reply.err
            body = self.open(sample.payload.to_bytes())
            if body is None or body.get("kind") != "reply" or body.get("nonce") != nonce or body.get("op") != op \
                    or body.get("server") != self.name:
                continue  # not from our server, or not for this request: ignore it
            if not body["ok"]:
                raise RuntimeError(f"{op}: {body['error']}")
            return body
        raise RuntimeError(f"{op}: no signed reply")


def steer_at_ball(state: dict, slot: str) -> list[float]:
    car, ball = state["cars"][slot], state["ball"]
    pos, rot, target = array(car["pos"]), array(car["rot_mat"]), array(ball["pos"])
    to_ball = [t - p for t, p in zip(target, pos)]
    norm = math.sqrt(sum(v * v for v in to_ball)) or 1.0
    forward = (rot[0], rot[3], rot[6])  # rot_mat is 3x3, row-major: its columns are forward, right, up
    right = (rot[1], rot[4], rot[7])
    ahead = sum(a * b for a, b in zip(forward, to_ball)) / norm
    side = sum(a * b for a, b in zip(right, to_ball)) / norm
    steer = max(-1.0, min(1.0, 3.0 * side if ahead > 0 else math.copysign(1.0, side)))
    # throttle, steer, pitch, yaw, roll, jump, boost, handbrake (buttons pressed when > 0)
    return [1.0, steer, 0.0, 0.0, 0.0, -1.0, 1.0 if ahead > 0.9 else -1.0, -1.0]


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--connect", required=True)
    ap.add_argument("--server", required=True)
    ap.add_argument("--match", required=True)
    ap.add_argument("--server-key", required=True)
    ap.add_argument("--slot", default=None)
    ap.add_argument("--ticket", default=None)
    ap.add_argument("--user", default="guest")
    args = ap.parse_args()
    config = zenoh.Config()
    for path, value in (("mode", "client"), ("connect/endpoints", [args.connect]),
                        ("scouting/multicast/enabled", False)):
        config.insert_json5(path, json.dumps(value))
    session = zenoh.open(config)
    server = Server(session, args.server, args.user, args.server_key)

    # 1. join with a fresh X25519 key; the slot's secret is derived, never sent
    exchange, nonce = X25519PrivateKey.generate(), os.urandom(16)
    client_key = exchange.public_key().public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)
    join = server.request("join", {"match": args.match, "slot": args.slot, "name": "readme-bot",
                                   "action": "continuous", "with_state": True, "client_key": client_key},
                          proof_key=bytes.fromhex(args.ticket) if args.ticket else None, nonce=nonce)
    slot = join["slot"]
    shared = exchange.exchange(X25519PublicKey.from_public_bytes(join["server_key_exchange"]))
    info = b"rocketdrl-ma/2 slot\x00" + f"{args.server}\x00{args.match}\x00{slot}".encode()
    secret = HKDF(algorithm=SHA256(), length=32, salt=nonce, info=info).derive(shared)
    print(f"joined {slot}", flush=True)

    # 2. subscribe to our observations, then declare our liveliness token: the match waits for it
    inbox: queue.Queue = queue.Queue()
    subscriber = session.declare_subscriber(join["keys"]["obs"], lambda s: inbox.put(s.payload.to_bytes()))
    token = session.liveliness().declare_token(join["keys"]["alive"])
    last_seq, decisions, dropped, reason = -1, 0, 0, None
    quiet_since = time.monotonic()
    while reason is None:
        try:
            payload = inbox.get(timeout=0.5)
        except queue.Empty:
            if time.monotonic() - quiet_since > 2.0:  # quiet: ask the lobby whether the match is over
                quiet_since = time.monotonic()
                status = server.request("inspect", {"match": args.match})["status"]
                if status in ("finished", "stopped", "failed"):
                    reason = status
            continue
        body = server.open(payload)
        if body is None or body.get("kind") != "obs" or body.get("server") != args.server or \
                body.get("match") != args.match or body.get("instance") != join["instance"] or \
                body.get("slot") != slot or body["seq"] <= last_seq:
            dropped += 1
            continue
        last_seq, quiet_since = body["seq"], time.monotonic()
        if body["done"]:
            reason = body["reason"]
            break
        # 3. answer this decision: {match, slot, decision, action} and its MAC under the slot's secret
        action_body = packb({"match": args.match, "slot": slot, "decision": body["decision"],
                             "action": steer_at_ball(body["state"], slot)})
        mac = hmac.digest(secret, b"rocketdrl-ma/2 act\x00" + action_body, hashlib.sha256)
        session.put(join["keys"]["act"], packb({"v": VERSION, "body": action_body, "mac": mac}))
        decisions += 1
    token.undeclare()
    subscriber.undeclare()
    session.close()
    print(f"done {reason} {decisions} {dropped}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
