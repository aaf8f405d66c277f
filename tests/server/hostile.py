"""A hostile client for the attack tests: an outsider's process (msgpack, zenoh, cryptography; no import of
rocketdrl_ma) that tries, for a bounded number of rounds, everything issue 21 lists against one victim's
slot of one match, and prints what it got as one JSON line (``result {...}``).

    python tests/server/hostile.py --server lab --match M --victim alice --slot blue_0 --rounds 400
        (--config mallory.yaml | --connect tcp/127.0.0.1:PORT) [--mode client|peer] [--flood 2000]

Each round it: forges actions for the victim's slot (random MACs) and replays every action it sniffed;
forges observations for it (signed with its own key, a forged ``done``) and replays sniffed ones; forges
the match's state, events and final message; answers lobby and key queries in the server's name (a
forged join reply, a forged error); declares liveliness tokens on every bot key it learns and on the
server's. ``--flood N`` also sends N lobby requests (create, join, list) and N junk actions as fast as it
can. It starts by printing ``ready`` once its subscriptions and queryables are declared; SIGTERM ends the
rounds early (the result is still printed).
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import threading
import time

import msgpack
import yaml
import zenoh
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey

V = 2
SIGNED_TAG = b"rocketdrl-ma/2 signed\x00"  # signed as the wire protocol says, only with the hostile's own key


def pack(message: dict) -> bytes:
    return msgpack.packb({"v": V, **message}, use_bin_type=True)


def zenoh_config(args) -> zenoh.Config:
    if args.config:
        section = yaml.safe_load(open(args.config))["zenoh"]
    else:
        section = {"connect": [args.connect]}
    config = zenoh.Config()
    entries = {"mode": args.mode, "connect/endpoints": section["connect"], "listen/endpoints": [],
               "scouting/multicast/enabled": False, "scouting/gossip/enabled": False}
    for key, value in section.get("auth", {}).items():
        entries[f"transport/auth/usrpwd/{key}"] = value
    for key, value in section.get("tls", {}).items():
        entries[f"transport/link/tls/{key}"] = value
    for path, value in entries.items():
        config.insert_json5(path, json.dumps(value))
    return config


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--server", required=True)
    ap.add_argument("--match", required=True)
    ap.add_argument("--victim", required=True, help="the victim's user")
    ap.add_argument("--slot", required=True, help="the victim's slot")
    ap.add_argument("--config", default=None)
    ap.add_argument("--connect", default=None)
    ap.add_argument("--mode", default="client", choices=["client", "peer"])
    ap.add_argument("--user", default=None, help="our own user (default: the config's, else mallory)")
    ap.add_argument("--rounds", type=int, default=400)
    ap.add_argument("--period-s", type=float, default=0.01)
    ap.add_argument("--flood", type=int, default=0)
    args = ap.parse_args()
    me = args.user or (yaml.safe_load(open(args.config))["zenoh"]["auth"]["user"] if args.config else "mallory")
    root, match, slot = f"rocketdrl/{args.server}", args.match, args.slot
    victim_slot = f"{root}/u/{args.victim}/match/{match}/{slot}"
    own_key = Ed25519PrivateKey.generate()
    session = zenoh.open(zenoh_config(args))
    lock = threading.Lock()
    seen = {"victim_samples": 0, "all_samples": 0, "acts": [], "obs": [], "alive_keys": set(), "queries": 0,
            "key_queries": 0, "lobby_queries_seen": []}

    mine: set[bytes] = set()  # what we put ourselves comes back to our own subscribers: not a leak

    def put(key: str, payload: bytes) -> None:
        with lock:
            mine.add(payload)
        session.put(key, payload)

    def on_any(sample) -> None:
        key, payload = str(sample.key_expr), sample.payload.to_bytes()
        with lock:
            if payload in mine:
                return
            seen["all_samples"] += 1
            if key.startswith(f"{root}/u/{args.victim}/"):
                seen["victim_samples"] += 1
            if key.endswith("/act") and len(seen["acts"]) < 200:
                seen["acts"].append((key, payload))
            if key.endswith("/obs") and len(seen["obs"]) < 50:
                seen["obs"].append((key, payload))

    own_tokens = {f"{root}/alive", f"{victim_slot}/alive/forged", f"{root}/u/{me}/match/{match}/{slot}/alive/forged"}

    def on_alive(sample) -> None:
        with lock:
            if str(sample.key_expr) not in own_tokens:
                seen["alive_keys"].add(str(sample.key_expr))

    def forged_reply(query) -> None:
        with lock:
            seen["queries"] += 1
            if query.payload is not None:
                seen["lobby_queries_seen"].append(query.payload.to_bytes()[:4096])
        body = msgpack.packb({"kind": "reply", "server": args.server, "op": "join", "ok": True, "slot": slot,
                              "match": match}, use_bin_type=True)
        try:
            query.reply(query.key_expr, pack({"body": body, "sig": own_key.sign(SIGNED_TAG + body)}))
            query.reply_err(pack({"ok": False, "error": "match: no such match (forged)"}))
        except zenoh.ZError:
            pass

    def forged_key(query) -> None:
        with lock:
            seen["key_queries"] += 1
        nonce = query.payload.to_bytes() if query.payload is not None else b""
        public = own_key.public_key().public_bytes_raw()
        body = msgpack.packb({"kind": "key", "server": args.server, "nonce": nonce, "key": public}, use_bin_type=True)
        try:
            query.reply(query.key_expr, pack({"body": body, "sig": own_key.sign(SIGNED_TAG + body)}))
        except zenoh.ZError:
            pass

    declared = [
        session.declare_subscriber(f"{root}/u/{args.victim}/**", on_any),
        session.declare_subscriber(f"{root}/**", on_any),
        session.declare_subscriber(f"{root}/match/{match}/state", on_any),
        session.liveliness().declare_subscriber(f"{root}/**", on_alive, history=True),
        session.declare_queryable(f"{root}/u/{args.victim}/lobby", forged_reply),
        session.declare_queryable(f"{root}/u/*/lobby", forged_reply),
        session.declare_queryable(f"{root}/key", forged_key),
        *(session.liveliness().declare_token(key) for key in sorted(own_tokens)),
    ]
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    print("ready", flush=True)
    cloned: dict[str, object] = {}
    sent = {"forged_acts": 0, "replayed_acts": 0, "forged_obs": 0, "replayed_obs": 0, "forged_public": 0,
            "lobby_flood": 0, "act_flood": 0}
    for round_ in range(args.rounds):
        if stop.is_set():
            break
        body = msgpack.packb({"match": match, "slot": slot, "decision": round_,
                              "action": [-1.0, 1, 1, 1, 1, 1, 1, 1]}, use_bin_type=True)
        put(f"{victim_slot}/act", pack({"body": body, "mac": os.urandom(32)}))
        sent["forged_acts"] += 1
        with lock:
            acts, obs, alive = list(seen["acts"]), list(seen["obs"]), set(seen["alive_keys"])
        for key, payload in acts[-4:]:
            put(key, payload)
            sent["replayed_acts"] += 1
        obs_body = msgpack.packb({"kind": "obs", "server": args.server, "match": match, "slot": slot,
                                  "seq": 10 ** 9 + round_, "decision": round_, "done": round_ % 5 == 0,
                                  "reward": 0.0, "events": [], "scoreboard": {}, "reason": "finished"},
                                 use_bin_type=True)
        put(f"{victim_slot}/obs", pack({"body": obs_body, "sig": own_key.sign(SIGNED_TAG + obs_body)}))
        put(f"{victim_slot}/obs", pack({"kind": "obs", "done": True, "decision": round_}))  # unsigned
        sent["forged_obs"] += 2
        for key, payload in obs[:2]:  # old real observations, replayed
            put(key, payload)
            sent["replayed_obs"] += 1
        final = msgpack.packb({"kind": "events", "server": args.server, "match": match, "seq": 10 ** 9 + round_,
                               "decision": 9999, "done": True, "final": True, "events": [], "status": "finished",
                               "summary": {"score": {"blue": 7, "orange": 0}}, "result_key": "forged"},
                              use_bin_type=True)
        put(f"{root}/match/{match}/events", pack({"body": final, "sig": own_key.sign(SIGNED_TAG + final)}))
        put(f"{root}/match/{match}/state", pack({"kind": "state", "decision": round_, "done": True}))
        sent["forged_public"] += 2
        for key in alive:  # keep every bot "connected" we learned of
            if key not in cloned and "/alive/" in key and key.startswith(f"{root}/u/"):
                cloned[key] = session.liveliness().declare_token(key)
        time.sleep(args.period_s)
    for i in range(args.flood):
        op = ("create", "join", "list")[i % 3]
        argsb = msgpack.packb({"config": "matches/4v4.yaml", "match": match, "overrides": {"clock_s": 1e9},
                               "client_key": os.urandom(32)}, use_bin_type=True)
        try:
            session.get(f"{root}/u/{me}/lobby", payload=pack({"op": op, "nonce": os.urandom(16), "args": argsb}),
                        timeout=0.01)
        except zenoh.ZError:
            pass
        put(f"{root}/u/{me}/match/{match}/{slot}/act", pack({"body": b"x" * 64, "mac": os.urandom(32)}))
        sent["lobby_flood"] += 1
        sent["act_flood"] += 1
    with lock:
        result = {"victim_samples": seen["victim_samples"], "all_samples": seen["all_samples"],
                  "acts_sniffed": len(seen["acts"]), "obs_sniffed": len(seen["obs"]),
                  "alive_keys": sorted(seen["alive_keys"]), "cloned_tokens": sorted(cloned),
                  "queries_received": seen["queries"], "key_queries_received": seen["key_queries"],
                  "lobby_queries_seen": [q.hex() for q in seen["lobby_queries_seen"]], **sent}
    for d in [*declared, *cloned.values()]:
        try:
            d.undeclare()
        except zenoh.ZError:
            pass
    session.close()
    print("result " + json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
