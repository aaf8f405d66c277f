"""Run `rocketdrl-ma serve` or `rocketdrl-ma web` with timestamps on the key-to-screen path, for
``benchmarks/web_latency.py --legs``: ``python benchmarks/web_latency_probe.py LOG.jsonl serve|web ARGS...``.

It wraps (in this process only, nothing is changed on disk) the points a jump passes through and appends one
JSON line per point to LOG.jsonl, with the wall clock (``time.time()``: the page's ``performance.timeOrigin +
performance.now()`` is on the same clock, so legs across processes on one machine line up to about a
millisecond). Match server: an action arriving for ``SLOT`` (with its jump button), the first physics tick
playing a jump of ``SLOT``, and every state published (its tick, ``SLOT``'s height). Page server: the page's
controls handed to the seat and sent on Zenoh, each state arriving from Zenoh (the newest one a poll shows), and
each frame built for the page.
"""
from __future__ import annotations

import json
import sys
import threading
import time

SLOT = "blue_0"


class ProbeLog:
    """JSON lines, written by a thread twice a second (the probed threads only append to a list)."""

    def __init__(self, path: str):
        self._file = open(path, "a", buffering=1)
        self._lines: list[str] = []
        self._lock = threading.Lock()
        threading.Thread(target=self._flush_forever, daemon=True).start()

    def add(self, kind: str, **fields) -> None:
        line = json.dumps({"kind": kind, "t": time.time(), **fields})
        with self._lock:
            self._lines.append(line)

    def _flush_forever(self) -> None:
        while True:
            time.sleep(0.5)
            with self._lock:
                lines, self._lines = self._lines, []
            if lines:
                self._file.write("\n".join(lines) + "\n")


def probe_match_server(log: ProbeLog) -> None:
    from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
    from rocketdrl_ma.server.match import MatchRunner

    on_action, publish_state, play = MatchRunner.on_action, MatchRunner._publish_state, RocketDRLParallelEnv.play
    jumping = {"now": False}

    def probed_on_action(self, slot, sample):
        received = time.time()
        on_action(self, slot, sample)
        if slot.name == SLOT:
            log.add("action_rx", at=received, jump=bool(slot.last_controls.jump), tick=int(self.env.game_state.tick),
                    acted=slot.acted_decision, decision=self.decision)

    def probed_publish_state(self, state, common, state_bytes=None):
        publish_state(self, state, common, state_bytes)
        car = state.cars.get(SLOT)
        if car is not None:
            log.add("state_pub", tick=int(state.tick), z=float(car.pos[2]), kickoff=bool(state.kickoff_pending))

    def probed_play(self, controls, actions=None, observe=True):
        mine = controls.get(SLOT)
        jump = bool(mine is not None and mine.jump)
        if jump and not jumping["now"]:
            log.add("tick_jump", tick=int(self.game_state.tick))
        jumping["now"] = jump
        return play(self, controls, actions, observe)

    MatchRunner.on_action, MatchRunner._publish_state = probed_on_action, probed_publish_state
    RocketDRLParallelEnv.play = probed_play


def probe_page_server(log: ProbeLog) -> None:
    from rocketdrl_ma.web import bridge, feed, play

    set_controls, on_state, poll, frame = (play.HumanSeat.set_controls, feed.Follower._on_state,
                                           feed.Follower.poll, bridge.frame)

    def probed_set_controls(self, values):
        handed = time.time()
        set_controls(self, values)
        log.add("seat_put", at=handed, jump=isinstance(values, list) and len(values) == 8 and values[5] > 0)

    def probed_on_state(self, sample):
        self._probe_arrived = time.time()
        on_state(self, sample)

    def probed_poll(self):
        update = poll(self)
        if update.state is not None:
            log.add("state_rx", at=getattr(self, "_probe_arrived", None), tick=int(update.state.state.tick))
        return update

    def probed_frame(state, agents, events=()):
        message = frame(state, agents, events)
        log.add("frame_out", tick=int(state.tick))
        return message

    play.HumanSeat.set_controls, feed.Follower._on_state, feed.Follower.poll = (probed_set_controls, probed_on_state,
                                                                                probed_poll)
    bridge.frame = probed_frame


def main() -> None:
    log = ProbeLog(sys.argv[1])
    command = sys.argv[2]
    if command == "serve":
        probe_match_server(log)
    elif command == "web":
        probe_page_server(log)
    else:
        raise ValueError(f"command: {command!r} is not one of ['serve', 'web']")
    from rocketdrl_ma.cli import main as cli_main
    sys.exit(cli_main(sys.argv[2:]))


if __name__ == "__main__":
    main()
