"""`rocketdrl-ma watch --replay` writes each decision's state with every event of its decision: the published
state carries its last tick's events only, and the decision's events message may come before or after it."""
from __future__ import annotations

from rocketdrl_ma.env.replay import load_replay
from rocketdrl_ma.rules.events import events_from_dicts
from rocketdrl_ma.server.protocol import encode_state
from rocketdrl_ma.server.spectator import EventsUpdate, StateUpdate
from rocketdrl_ma.server.watch import DecisionRecorder
from web_helpers import write_replay


class Collected:
    def __init__(self):
        self.states = []

    def add(self, state) -> None:
        self.states.append(state)


def touch(tick: int, agent: str = "blue_0"):
    return events_from_dicts([{"kind": "touch", "tick": tick, "agent": agent}])[0]


def updates(tmp_path, n: int):
    replay = load_replay(write_replay(tmp_path / "r.npz", "matches/1v1.yaml", decisions=n))
    out = []
    for k in range(n):
        state = replay.state(k)
        state.events = []
        out.append(StateUpdate("m", k, k, "running", False, {}, {}, encode_state(state)))
    return out


def test_events_before_or_after_their_state_are_written_with_it_once(tmp_path):
    states = updates(tmp_path, 4)
    last_tick = states[1].state.tick
    states[1].state.events = [touch(last_tick)]  # the state carries its last tick's event...
    writer = Collected()
    recorder = DecisionRecorder(writer)
    recorder.state(states[0])
    # ...its decision's message all of them, here before the state
    recorder.events(EventsUpdate("m", 1, 1, [touch(last_tick - 3), touch(last_tick)]))
    recorder.state(states[1])
    recorder.state(states[2])
    recorder.state(states[3])
    late = touch(states[2].state.tick - 1, "orange_0")
    recorder.events(EventsUpdate("m", 2, 2, [late]))  # after state 3 came: written with it, at its own tick
    recorder.flush()
    written = [[(e.tick, e.agent) for e in s.events] for s in writer.states]
    assert written == [[], [(last_tick - 3, "blue_0"), (last_tick, "blue_0")], [], [(late.tick, "orange_0")]]
