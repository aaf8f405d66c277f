"""A hostile client for issue 50's lobby and league attacks: an outsider's process (msgpack, zenoh,
cryptography; no import of rocketdrl_ma) that tries one attack and prints what it got as one JSON line
(``result {...}``). It starts by printing ``ready`` (or a result saying it could not connect at all).

    python tests/server/hostile_lobby.py ATTACK --server NAME (--connect tcp/127.0.0.1:PORT | --config FILE) [...]

Attacks:

- ``relay``: listen on the victim's lobby key; when the victim asks for a challenge, keep the victim's rate
  limit empty with cheap requests in its name until its ``create`` passes by, then resend that create byte for
  byte once a token frees, keep the signed reply, and join a slot with any ticket the reply shows;
- ``seat``: join ``--match`` claiming to be ``--victim``, whose seat the match holds;
- ``invite``: invite ``--victim``'s league bot to ``--match`` (``--slots``), an invitation nobody signed;
- ``answer-invite``: answer the league's invitations to ``--victim`` in its place, then join the invited
  seats as the victim and hold them (liveliness tokens) until SIGTERM;
- ``train``: publish a forged training run ``--match`` on ``train/**`` (and under the victim's prefix); with
  ``--copy``, also republish each message of the victim's real run ``--match`` with its iteration changed to
  ``FORGED_ITERATION`` (the signature, if any, kept as it came);
- ``member``: claim to be ``--victim``, a member the server manages, signing with a key of our own: create a
  match with the victim's seat, and join ``--match``'s seat ``--slots``.
"""
from __future__ import annotations

import argparse
import hashlib
import hmac
import json
import os
import signal
import sys
import threading
import time

import msgpack
import zenoh

import yaml
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
from cryptography.hazmat.primitives.asymmetric.x25519 import X25519PrivateKey

from hostile import zenoh_config  # the other hostile client's Zenoh set-up (run as a script beside it)

V = 2
REQUEST_TAG = b"rocketdrl-ma/2 request\x00"
MEMBER_TAG = b"rocketdrl-ma/2 member request\x00"
FORGED_ITERATION = 999_999


def pack(message: dict) -> bytes:
    return msgpack.packb({"v": V, **message}, use_bin_type=True)


def body_of(raw: bytes) -> dict:
    """The body of a sealed reply (the signature is the server's: a relay keeps it intact), or the error map."""
    message = msgpack.unpackb(raw, raw=False)
    if isinstance(message.get("body"), bytes):
        return msgpack.unpackb(message["body"], raw=False)
    return message


def open_session(args):
    args.mode = "client"
    return zenoh.open(zenoh_config(args))  # the other hostile client's Zenoh set-up: a config file or an endpoint


class Lobby:
    """Lobby requests as any user we claim to be."""

    def __init__(self, session, server: str):
        self.session, self.server = session, server

    def ask(self, user: str, op: str, args: dict, proof: bytes | None = None, nonce: bytes | None = None,
            timeout_s: float = 5.0, signer: Ed25519PrivateKey | None = None) -> dict:
        raw_args = msgpack.packb(args, use_bin_type=True)
        nonce = nonce or os.urandom(16)
        message = {"op": op, "nonce": nonce, "args": raw_args}
        if proof is not None or signer is not None:
            challenge = self.ask(user, "challenge", {}).get("challenge")
            if not isinstance(challenge, bytes):
                return {"ok": False, "error": "no challenge"}
            names = b"\x00".join(s.encode() for s in (op, self.server, user)) + b"\x00" + challenge
            message["challenge"] = challenge
            if proof is not None:
                message["mac"] = hmac.digest(proof, REQUEST_TAG + names + raw_args, hashlib.sha256)
            if signer is not None:  # a member's signature, by a key the server never registered
                message["user_sig"] = signer.sign(MEMBER_TAG + names + nonce + raw_args)
        return self.send(user, pack(message), timeout_s)

    def send(self, user: str, payload: bytes, timeout_s: float = 5.0) -> dict:
        for reply in self.session.get(f"rocketdrl/{self.server}/u/{user}/lobby", payload=payload, timeout=timeout_s,
                                      consolidation=zenoh.ConsolidationMode.NONE):
            sample = reply.ok if reply.ok is not None else reply.err
            try:
                body = body_of(sample.payload.to_bytes())
            except Exception:
                continue
            if "ok" in body:
                return body
        return {"ok": False, "error": "no reply"}

    def join(self, user: str, match: str, slot: str, ticket: bytes | None = None) -> dict:
        private = X25519PrivateKey.generate()
        public = private.public_key().public_bytes_raw()
        return self.ask(user, "join", {"match": match, "slot": slot, "client_key": public, "name": "mallory"},
                        proof=ticket)


def relay(session, lobby: Lobby, args) -> dict:
    seen: dict[str, bytes] = {}
    lock = threading.Lock()

    def on_query(query) -> None:
        if query.payload is None:
            return
        payload = query.payload.to_bytes()
        try:
            op = msgpack.unpackb(payload, raw=False).get("op")
        except Exception:
            return
        with lock:
            if op in ("challenge", "create") and op not in seen:
                seen[op] = payload

    queryable = session.declare_queryable(f"rocketdrl/{args.server}/u/{args.victim}/lobby", on_query)
    # declared with the lobby queryable: who hears this probe's answer gets its queries routed here too
    probe = session.declare_queryable(f"rocketdrl/{args.server}/u/{args.victim}/probe",
                                      lambda query: query.reply(query.key_expr, b"here"))
    print("ready", flush=True)
    deadline = time.monotonic() + args.wait_s
    while time.monotonic() < deadline and "challenge" not in seen:
        time.sleep(0.001)
    flood = 0
    junk = pack({"op": "list", "nonce": os.urandom(16), "args": b"\x80"})
    while time.monotonic() < deadline and "create" not in seen:  # the victim's bucket stays empty meanwhile
        session.get(f"rocketdrl/{args.server}/u/{args.victim}/lobby", payload=junk, timeout=0.5)
        flood += 1
        time.sleep(0.002)
    result = {"saw": sorted(seen), "flood": flood}
    if "create" not in seen:
        return result
    time.sleep(args.refill_s)  # a token frees
    reply = lobby.send(args.victim, seen["create"])
    tickets = reply.get("tickets") if reply.get("ok") else None
    result.update(replayed_ok=bool(reply.get("ok")), reply_error=reply.get("error"),
                  readable_tickets=sorted(tickets) if isinstance(tickets, dict) else [])
    joined = []
    if isinstance(tickets, dict):
        for slot, ticket in tickets.items():
            try:
                secret = bytes.fromhex(ticket)
            except (TypeError, ValueError):
                continue
            if lobby.join(args.victim, reply["id"], slot, secret).get("ok"):
                joined.append(slot)
    result["joined_with_stolen_tickets"] = joined
    queryable.undeclare()
    probe.undeclare()
    return result


def seat(session, lobby: Lobby, args) -> dict:
    print("ready", flush=True)
    reply = lobby.join(args.victim, args.match, args.slots.split(",")[0])
    return {"joined": bool(reply.get("ok")), "error": reply.get("error")}


def invite(session, lobby: Lobby, args) -> dict:
    print("ready", flush=True)
    answers = []
    for reply in session.get(f"rocketdrl/{args.server}/u/{args.victim}/invite", timeout=5.0,
                             payload=pack({"match": args.match, "slots": args.slots.split(",")})):
        sample = reply.ok if reply.ok is not None else reply.err
        try:
            answers.append(msgpack.unpackb(sample.payload.to_bytes(), raw=False))
        except Exception:
            answers.append({"ok": False, "error": "unreadable"})
    return {"answers": len(answers), "accepted": sum(bool(a.get("ok")) for a in answers)}


def answer_invite(session, lobby: Lobby, args, stop: threading.Event) -> dict:
    invited: list = []
    tokens: list = []
    joins: list = []

    def on_query(query) -> None:
        try:
            request = msgpack.unpackb(query.payload.to_bytes(), raw=False)
            query.reply(query.key_expr, pack({"ok": True}))
        except Exception:
            return
        invited.append(request)
        for slot in request.get("slots") or []:
            reply = lobby.join(args.victim, request.get("match"), slot)
            joins.append({"slot": slot, "ok": bool(reply.get("ok")), "error": reply.get("error")})
            if reply.get("ok"):
                tokens.append(session.liveliness().declare_token(reply["keys"]["alive"]))

    queryable = session.declare_queryable(f"rocketdrl/{args.server}/u/{args.victim}/invite", on_query)
    print("ready", flush=True)
    stop.wait(args.wait_s)
    queryable.undeclare()
    for token in tokens:
        token.undeclare()
    return {"invitations": len(invited), "joins": joins, "seats_held": sum(j["ok"] for j in joins)}


def member(session, lobby: Lobby, args) -> dict:
    print("ready", flush=True)
    own_key = Ed25519PrivateKey.generate()
    client_key = X25519PrivateKey.generate().public_key().public_bytes_raw()
    created = lobby.ask(args.victim, "create", {"config": "matches/1v1.yaml", "id": "claimed", "fill": "idle",
                                                "seats": {"blue_0": args.victim}, "client_key": client_key},
                        signer=own_key)
    unsigned = lobby.ask(args.victim, "join", {"match": args.match, "slot": args.slots, "client_key": client_key,
                                               "name": "mallory"})
    signed = lobby.ask(args.victim, "join", {"match": args.match, "slot": args.slots, "client_key": client_key,
                                             "name": "mallory"}, signer=own_key)
    return {"created": bool(created.get("ok")), "create_error": created.get("error"),
            "joined": bool(unsigned.get("ok")) or bool(signed.get("ok")),
            "join_errors": [unsigned.get("error"), signed.get("error")]}


def forged_copy(payload: bytes) -> bytes:
    """The victim's run message with its iteration changed (a signed one keeps its signature)."""
    message = msgpack.unpackb(payload, raw=False)
    if isinstance(message.get("body"), bytes):
        body = msgpack.unpackb(message["body"], raw=False)
        body.setdefault("info", {})["iteration"] = FORGED_ITERATION
        return msgpack.packb({**message, "body": msgpack.packb(body, use_bin_type=True)}, use_bin_type=True)
    message.setdefault("info", {})["iteration"] = FORGED_ITERATION
    return msgpack.packb(message, use_bin_type=True)


def train(session, lobby: Lobby, args, stop: threading.Event) -> dict:
    root = f"rocketdrl/{args.server}"
    keys = [f"{root}/train/{args.match}", f"{root}/u/{args.victim}/train/{args.match}"]
    tokens = [session.liveliness().declare_token(f"{k}/alive") for k in keys]
    copied = []
    if args.copy:
        victim_state = f"{root}/u/{args.victim}/train/{args.match}/state"

        def republish(sample) -> None:
            if sample.attachment is not None:  # our own copy coming back
                return
            session.put(victim_state, forged_copy(sample.payload.to_bytes()), attachment=b"copy")
            copied.append(1)
        tokens.append(session.declare_subscriber(victim_state, republish))
    print("ready", flush=True)
    sent = 0
    while True:
        for key in keys:
            session.put(f"{key}/state", pack({"match": args.match, "decision": sent, "status": "running",
                                               "done": False, "info": {"run": args.match, "iteration": 1}}))
        sent += 1
        if stop.wait(0.05):
            break
    for token in tokens:
        token.undeclare()
    return {"sent": sent, "copied": len(copied)}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("attack", choices=["relay", "seat", "invite", "answer-invite", "train", "member"])
    ap.add_argument("--server", required=True)
    ap.add_argument("--connect", default=None)
    ap.add_argument("--config", default=None, help="a client YAML: our own user, password and the server's CA")
    ap.add_argument("--victim", default="guest")
    ap.add_argument("--match", default="m")
    ap.add_argument("--slots", default="blue_0")
    ap.add_argument("--wait-s", type=float, default=60.0)
    ap.add_argument("--refill-s", type=float, default=0.5)
    ap.add_argument("--copy", action="store_true", help="train: also republish the victim's run, altered")
    args = ap.parse_args()
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        session = open_session(args)
    except zenoh.ZError as e:
        print(f"result {json.dumps({'connected': False, 'error': str(e)[:200]})}", flush=True)
        return 0
    lobby = Lobby(session, args.server)
    try:
        if args.attack == "relay":
            result = relay(session, lobby, args)
        elif args.attack == "seat":
            result = seat(session, lobby, args)
        elif args.attack == "invite":
            result = invite(session, lobby, args)
        elif args.attack == "answer-invite":
            result = answer_invite(session, lobby, args, stop)
        elif args.attack == "member":
            result = member(session, lobby, args)
        else:
            result = train(session, lobby, args, stop)
    finally:
        session.close()
    print(f"result {json.dumps({'connected': True, **result})}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
