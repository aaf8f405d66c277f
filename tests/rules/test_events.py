"""Typed game events: what the rules emit, their wire maps, and reading maps back (also from hostile peers)."""
from __future__ import annotations

import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import BallState
from rocketdrl_ma.policies.scripted import make_scripted
from rocketdrl_ma.rules import events as E
from rocketdrl_ma.server.protocol import ProtocolError, decode_events, pack, unpack


def test_every_kind_has_one_type_and_round_trips_through_its_map():
    samples = [E.Touch(1, "blue_0"), E.Shot(2, "blue_0"), E.Save(3, "orange_1"), E.Goal(4, "orange", None, True),
               E.Miss(5, "wide"), E.Demo(6, "blue_0", "orange_0"), E.Bump(7, "orange_0", "blue_1"),
               E.BoostPickup(8, "blue_0", 33), E.Overtime(9), E.AerialTouch(10, "blue_0", 612.5)]
    assert {type(e) for e in samples} == set(E.EVENT_TYPES.values())
    assert {e.kind for e in samples} == set(E.GameEventKind)
    for event in samples:
        wire = unpack(pack({"e": event.as_dict()}))["e"]
        assert list(wire)[:2] == ["kind", "tick"] and wire["kind"] == event.kind.value
        assert E.event_from_dict(wire) == event


def test_the_wire_maps_are_the_documented_ones():
    assert E.Goal(4, "blue", "blue_0", False).as_dict() == {
        "kind": "goal", "tick": 4, "team": "blue", "scorer": "blue_0", "own_goal": False}
    assert E.Demo(6, "blue_0", "orange_0").as_dict() == {"kind": "demo", "tick": 6, "agent": "blue_0",
                                                         "victim": "orange_0"}


def test_reading_maps_back_names_the_bad_field_and_skips_unknown_kinds():
    assert E.event_from_dict({"kind": "a_kind_from_the_future", "tick": 1}) is None
    with pytest.raises(ValueError, match=r"event goal\.own_goal"):
        E.event_from_dict({"kind": "goal", "tick": 1, "team": "blue", "scorer": None, "own_goal": "yes"})
    with pytest.raises(ValueError, match=r"event touch\.tick"):
        E.event_from_dict({"kind": "touch", "tick": True, "agent": "blue_0"})
    with pytest.raises(ProtocolError, match="events: expected a list"):
        decode_events({"kind": "touch"})
    assert decode_events([{"kind": "touch", "tick": 1, "agent": "blue_0"}, {"kind": "new", "tick": 2}]) == [
        E.Touch(1, "blue_0")]


def test_a_match_reports_typed_events_in_infos_and_counts_them_per_agent():
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", kickoff_countdown_s=0.0)
    env.reset(seed=3)
    env.rules.arena.ball.set_state(BallState(pos=np.array([0.0, 5150.0, 93.15]), vel=np.array([0.0, 2000.0, 0.0])))
    *_, infos = env.step({a: np.zeros(8, np.float32) for a in env.agents})
    goals = [e for e in infos["blue_0"]["events"] if isinstance(e, E.Goal)]
    assert len(goals) == 1 and goals[0].team == "blue" and goals[0].kind is E.GameEventKind.GOAL
    assert "GOAL blue" in E.describe_event(goals[0], 120)
    env.close()
    numeric = rocketdrl_ma.parallel_env("matches/1v1.yaml", kickoff_countdown_s=0.0, info_format="numeric")
    numeric.reset(seed=3)
    chaser = make_scripted("ball_chaser")
    for _ in range(60):  # two ball-chasers at the kickoff: someone touches it
        state = numeric.game_state
        *_, infos = numeric.step({a: numeric.action_parser.encode(chaser.controls(a, state)) for a in numeric.agents})
        if infos["blue_0"]["touch"] or infos["orange_0"]["touch"]:
            break
    assert infos["blue_0"]["touch"] + infos["orange_0"]["touch"] >= 1.0
    numeric.close()
