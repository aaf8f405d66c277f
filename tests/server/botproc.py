"""Bots with test behaviours, run as separate processes by the server tests (not a pytest module).

    python tests/server/botproc.py --connect tcp/127.0.0.1:PORT --server test --key-dir DIR --match m
        --slots blue_0,blue_1 [--policy scripted:ball_chaser] [--delay-ms 300]

Each slot plays in its own thread (one Zenoh session per process). ``--delay-ms`` makes every
decision that much slower, to play a bot that misses the lockstep deadline. Prints
``joined SLOT REJOIN_TOKEN`` per slot and ``done SLOT DECISIONS REASON`` at the end.
"""
from __future__ import annotations

import argparse
import sys
import threading
import time

from rocketdrl_ma.server.bot import PolicyBot
from rocketdrl_ma.server.settings import ClientSettings


class DelayedBot(PolicyBot):
    def __init__(self, spec: str, delay_s: float):
        super().__init__(spec, name=f"{spec}+{delay_s * 1e3:g}ms")
        self.delay_s = delay_s

    def act(self, obs, info):
        time.sleep(self.delay_s)
        return super().act(obs, info)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--connect", required=True)
    ap.add_argument("--server", required=True)
    ap.add_argument("--key-dir", required=True)
    ap.add_argument("--match", required=True)
    ap.add_argument("--slots", required=True)
    ap.add_argument("--policy", default="scripted:ball_chaser")
    ap.add_argument("--delay-ms", type=float, default=0.0)
    args = ap.parse_args()
    client = ClientSettings.from_dict({"server": args.server, "key_dir": args.key_dir,
                                       "zenoh": {"mode": "client", "connect": [args.connect]}})
    session = client.zenoh.open()
    failures = []
    lock = threading.Lock()

    def say(line: str) -> None:  # one whole line at a time from several threads
        with lock:
            print(line, flush=True)

    def play(slot: str) -> None:
        try:
            bot = DelayedBot(args.policy, args.delay_ms / 1e3)
            report = bot.run(args.match, slot, client=client, session=session,
                             on_joined=lambda j: say(f"joined {j.slot} {j.rejoin_token}"))
            say(f"done {slot} {report.decisions} {report.reason}")
        except Exception as e:  # reported on stdout for the test to show
            failures.append(slot)
            say(f"failed {slot} {type(e).__name__}: {e}")

    threads = [threading.Thread(target=play, args=(slot,)) for slot in args.slots.split(",")]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    session.close()
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
