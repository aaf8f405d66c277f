"""Replay files: exact round trip, version check, re-rendering."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rocketdrl_ma.env.replay import FORMAT_VERSION, ReplayWriter, load_replay, render_replay
from rocketdrl_ma.physics import BallState, CarControls, CarState, yaw_rot_mat
from rocketdrl_ma.physics.car_config import PRESETS
from rocketdrl_ma.rules.events import Touch
from rocketdrl_ma.rules.state import GameState, Obstacle


def _rot(yaw, pitch, roll):
    cy, sy, cp, sp, cr, sr = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def make_states(n=20, seed=0) -> list[GameState]:
    rng = np.random.default_rng(seed)
    states = []
    for t in range(n):
        cars, controls = {}, {}
        agents = ["blue_0", "orange_0"] + (["blue_1"] if t < 12 else []) + (["orange_1"] if t >= 5 else [])
        for a in agents:
            cars[a] = CarState(pos=rng.uniform(-2000, 2000, 3), vel=rng.normal(0, 900, 3), ang_vel=rng.normal(0, 2, 3),
                               rot_mat=_rot(*rng.uniform(-3, 3, 3)), boost=float(rng.uniform(0, 100)),
                               on_ground=bool(rng.integers(2)),
                               wheels_in_contact=tuple(bool(x) for x in rng.integers(0, 2, 4)),
                               has_jumped=bool(rng.integers(2)), is_supersonic=bool(rng.integers(2)),
                               is_demoed=(a == "orange_0" and 8 <= t < 11), handbrake_value=float(rng.uniform()),
                               jump_time=float(rng.uniform()), demo_respawn_timer=float(rng.uniform(0, 3)))
        for a in agents[:2]:
            controls[a] = CarControls(throttle=float(rng.uniform(-1, 1)), steer=float(rng.uniform(-1, 1)),
                                      jump=bool(rng.integers(2)), boost=bool(rng.integers(2)))
        obstacles = (Obstacle(np.array([0.0, -1500.0, 100.0]), np.array([300.0, 40.0, 100.0])),) if t % 3 else ()
        states.append(GameState(
            tick=8 * t + 3, tick_rate=120, cars=cars,
            ball=BallState(pos=rng.uniform(-1000, 1000, 3) + [0, 0, 1100], vel=rng.normal(0, 1000, 3),
                           ang_vel=rng.normal(0, 3, 3)),
            pad_timers=np.where(rng.uniform(size=34) < 0.3, rng.uniform(0, 10, 34), 0.0), last_controls=controls,
            score=(t // 7, t // 9), clock_s=300.0 - t * 8 / 120, is_overtime=t == 19, kickoff_pending=t == 0,
            last_touch=None if t < 2 else agents[t % len(agents)], obstacles=obstacles,
            events=[Touch(8 * t, agents[0])] if t % 4 == 0 else [],
            car_configs={a: PRESETS["merc" if a == "blue_1" else "octane"] for a in agents},
        ))
    return states


def assert_same(a, b, where="state"):
    """Exact, field-by-field equality of dataclasses, dicts, sequences and arrays."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            assert_same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), f"{where}: keys {list(a)} != {list(b)}"
        for k in a:
            assert_same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.shape == b.shape and np.array_equal(a, b), where
    elif isinstance(a, (list, tuple)):
        assert type(a) is type(b) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    else:
        assert type(a) is type(b) and a == b, f"{where}: {a!r} != {b!r}"


def write(path, states, meta=None):
    with ReplayWriter(str(path), meta or {"config": {"mode": "2v2", "seed": 7}}) as rec:
        for s in states:
            rec.add(s)


def test_round_trip_is_exact(tmp_path):
    states = make_states()
    path = tmp_path / "r.npz"
    write(path, states)
    replay = load_replay(str(path))
    assert len(replay) == 20
    assert replay.meta["config"] == {"mode": "2v2", "seed": 7}
    assert replay.meta["format_version"] == FORMAT_VERSION and replay.meta["tick_rate"] == 120
    assert replay.meta["agents"] == ["blue_0", "orange_0", "blue_1", "orange_1"]
    for i, s in enumerate(states):
        assert_same(s, replay.state(i), f"state[{i}]")
    assert "blue_1" not in replay.state(15).cars and "orange_1" not in replay.state(0).cars
    assert replay.state(-1).tick == states[-1].tick
    with pytest.raises(IndexError):
        replay.state(20)


def test_writer_snapshots_states_it_is_given(tmp_path):
    state = make_states(1)[0]
    path = tmp_path / "s.npz"
    with ReplayWriter(str(path)) as rec:
        rec.add(state)
        state.ball.pos[0] = 1234.0  # a caller reusing its objects must not rewrite history
        state.cars["blue_0"].boost = 1.0
        rec.add(state)
    replay = load_replay(str(path))
    assert replay.state(0).ball.pos[0] != 1234.0 and replay.state(1).ball.pos[0] == 1234.0
    assert replay.state(1).cars["blue_0"].boost == 1.0 != replay.state(0).cars["blue_0"].boost


def test_version_mismatch_and_non_replay_raise(tmp_path):
    path = tmp_path / "r.npz"
    write(path, make_states(3))
    with np.load(str(path)) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["format_version"] = np.asarray(FORMAT_VERSION + 1)
    bad = tmp_path / "bad.npz"
    np.savez(str(bad), **arrays)
    with pytest.raises(ValueError, match="format_version"):
        load_replay(str(bad))
    other = tmp_path / "other.npz"
    np.savez(str(other), x=np.zeros(3))
    with pytest.raises(ValueError, match="not a replay"):
        load_replay(str(other))


def test_meta_must_be_json(tmp_path):
    with pytest.raises(ValueError, match="meta"):
        ReplayWriter(str(tmp_path / "m.npz"), {"f": object()})
    w = ReplayWriter(str(tmp_path / "m.npz"), {"arr": np.arange(3)})
    w.close()
    assert json.loads(json.dumps(load_replay(str(tmp_path / "m.npz")).meta))["arr"] == [0, 1, 2]


def test_render_replay_writes_every_frame(tmp_path):
    import imageio.v2 as iio
    path = tmp_path / "r.npz"
    write(path, make_states())
    out = tmp_path / "r.gif"
    assert render_replay(str(path), str(out), width=160, height=90) == 20
    frames = iio.mimread(str(out))
    assert len(frames) == 20 and np.asarray(frames[0]).shape[:2] == (90, 160)
    assert load_replay(str(path)).states_per_second() == 15.0
