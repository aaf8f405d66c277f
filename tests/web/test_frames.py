"""What the page receives, without a browser: frames of real game states, the exported arena, replays."""
from __future__ import annotations

import msgpack
import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.physics.arena_geometry import arena_mesh
from rocketdrl_ma.rules.events import Goal, Touch
from rocketdrl_ma.web.arena import PAGE_FILLET_SEGMENTS, arena_json
from rocketdrl_ma.web.frames import FLAG_BOOSTING, FLAG_DEMOED, frame, pack_message, roster, rotation_to_quaternion
from rocketdrl_ma.web.replays import ReplayLibrary
from web_helpers import write_replay

MAX_4V4_FRAME_BYTES = 2000


def quaternion_matrix(q) -> np.ndarray:
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_quaternion_is_the_rotation_for_every_branch():
    rng = np.random.default_rng(0)
    mats = [np.eye(3), np.diag([1.0, -1.0, -1.0]), np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])]
    for _ in range(300):
        q, r = np.linalg.qr(rng.normal(size=(3, 3)))
        mats.append(q * np.sign(np.linalg.det(q)))
    for m in mats:
        quat = rotation_to_quaternion(m)
        assert quat[3] >= 0.0
        assert np.allclose(quaternion_matrix(quat), m, atol=1e-9)


def _played_4v4(decisions: int = 40):
    env = rocketdrl_ma.parallel_env("matches/4v4.yaml", kickoff_countdown_s=0.0)
    env.reset(seed=5)
    boost = env.action_parser.encode(CarControls(throttle=1.0, boost=True))
    for _ in range(decisions):
        env.step({agent: boost for agent in env.agents})
    return env


def test_a_4v4_frame_is_compact_and_carries_the_state():
    env = _played_4v4()
    state = env.game_state
    cast = roster(state)
    assert cast["agents"] == [f"blue_{i}" for i in range(4)] + [f"orange_{i}" for i in range(4)]
    assert cast["teams"] == [0] * 4 + [1] * 4
    message = frame(state, cast["agents"], [Goal(9, "blue", "blue_0", False), Touch(9, "blue_1")])
    payload = pack_message(message)
    assert len(payload) < MAX_4V4_FRAME_BYTES
    decoded = msgpack.unpackb(payload)
    assert decoded["t"] == state.tick and decoded["s"] == list(state.score)
    assert np.allclose(decoded["b"], state.ball.pos, atol=1e-3 * np.abs(state.ball.pos).max() + 1e-3)
    for agent, car in zip(cast["agents"], decoded["a"]):
        truth = state.cars[agent]
        assert np.allclose(car[:3], truth.pos, rtol=1e-6, atol=1e-2)
        assert np.allclose(quaternion_matrix(car[3:7]), truth.rot_mat, atol=1e-5)
        assert car[7] == pytest.approx(truth.boost, abs=1e-3)
        assert bool(car[8] & FLAG_BOOSTING) == (truth.boost > 0.0 and not truth.is_demoed)
        assert bool(car[8] & FLAG_DEMOED) == truth.is_demoed
    active = np.asarray(state.pad_timers) <= 0.0
    assert [bool(decoded["p"] >> i & 1) for i in range(len(active))] == list(active)
    assert not active.all()  # 40 decisions of boosting through the field took some pads
    assert [e["kind"] for e in decoded["e"]] == ["goal"]  # touches are not feed events
    env.close()


def test_the_arena_is_the_physics_mesh():
    import json
    arena = json.loads(arena_json())
    vertices, triangles = arena_mesh(PAGE_FILLET_SEGMENTS)
    assert np.allclose(np.reshape(arena["vertices"], (-1, 3)), vertices, atol=0.01)
    assert np.array_equal(np.reshape(arena["triangles"], (-1, 3)), triangles)
    assert len(arena["pads"]) == 34 and sum(p[3] for p in arena["pads"]) == 6


def test_replay_library_lists_and_refuses_what_it_does_not_offer(tmp_path):
    folder = tmp_path / "runs"
    (folder / "a").mkdir(parents=True)
    path = write_replay(folder / "a" / "game.npz", "matches/1v1.yaml", decisions=12)
    outside = write_replay(tmp_path / "outside.npz", "matches/1v1.yaml", decisions=3)
    library = ReplayLibrary([folder])
    assert [r["id"] for r in library.list()] == ["runs/a/game.npz"]
    message = library.open("runs/a/game.npz")
    assert message["roster"]["agents"] == ["blue_0", "orange_0"]
    assert len(message["frames"]) == 13  # the reset state and 12 decisions
    for name in (str(outside), "../outside.npz", "runs/../outside.npz", "runs/a/missing.npz", 7):
        with pytest.raises(ValueError, match="not one of the replays"):
            library.open(name)
    assert path.is_file()
