"""Wire format: msgpack maps with a protocol version, numpy arrays as raw bytes + dtype + shape,
game states that survive the trip, every kind of malformed payload refused with a reason; signed server
messages and MAC'd actions that any tampering breaks; the slot secret both sides derive."""
from __future__ import annotations

import dataclasses

import msgpack
import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import PRESETS
from rocketdrl_ma.rules.events import Touch
from rocketdrl_ma.rules.state import Obstacle
from rocketdrl_ma.server.crypto import (KeyExchange, ServerIdentity, ServerKey, SignatureError, action_mac,
                                        open_secret, parse_public_key, random_bytes, request_mac, seal_secret)
from rocketdrl_ma.server.protocol import (PROTOCOL_VERSION, Keys, ProtocolError, VersionError, action_message,
                                          check_name, decode_space, decode_state, encode_space, encode_state,
                                          open_sealed, pack, pack_map, pack_value, seal, split_action, unpack)


@pytest.mark.parametrize("dtype", ["<f4", "<f8", "<i8", "|u1", "|b1", ">i4"])
def test_arrays_travel_as_raw_bytes_with_dtype_and_shape(dtype):
    a = (np.arange(24) % 5).astype(dtype).reshape(2, 3, 4)
    raw = pack({"a": a})
    plain = msgpack.unpackb(raw, raw=False)  # what any msgpack library sees
    assert plain["v"] == PROTOCOL_VERSION
    assert plain["a"] == {"$nd": np.dtype(dtype).str, "shape": [2, 3, 4], "data": a.tobytes()}
    back = unpack(raw)["a"]
    assert back.dtype == np.dtype(dtype) and back.shape == (2, 3, 4) and np.array_equal(back, a)
    back[0, 0, 0] = 1  # a writable copy, not a view of the message
    assert unpack(raw)["a"].flags.writeable


@pytest.mark.parametrize("bad, reason", [
    ({"$nd": "|O", "shape": [1], "data": b"\0" * 8}, "not allowed"),
    ({"$nd": "<U4", "shape": [1], "data": b"\0" * 16}, "not allowed"),
    ({"$nd": "<c16", "shape": [1], "data": b"\0" * 16}, "not allowed"),
    ({"$nd": "nonsense", "shape": [1], "data": b"\0"}, "dtype"),
    ({"$nd": "<f4", "shape": [3], "data": b"\0" * 8}, "do not fill"),
    ({"$nd": "<f4", "shape": [-1], "data": b""}, "shape"),
    ({"$nd": "<f4", "shape": "3", "data": b"\0" * 12}, "shape"),
    ({"$nd": "<f4", "shape": [3], "data": "text"}, "do not fill"),
])
def test_malformed_arrays_are_refused(bad, reason):
    raw = msgpack.packb({"v": PROTOCOL_VERSION, "a": bad}, use_bin_type=True)
    with pytest.raises(ProtocolError, match=reason):
        unpack(raw)


def test_objects_cannot_be_sent():
    with pytest.raises(TypeError):
        pack({"a": np.array([object()])})
    with pytest.raises(TypeError):
        pack({"a": object()})


def test_version_size_and_garbage_checks():
    other = msgpack.packb({"v": PROTOCOL_VERSION + 1, "op": "list"})
    with pytest.raises(VersionError, match=f"version {PROTOCOL_VERSION + 1} is not supported; this server speaks "
                                           f"version {PROTOCOL_VERSION}"):
        unpack(other)
    with pytest.raises(VersionError, match="None"):
        unpack(msgpack.packb({"op": "list"}))
    with pytest.raises(ProtocolError, match="expected a map"):
        unpack(msgpack.packb([1, 2, 3]))
    with pytest.raises(ProtocolError, match="not valid msgpack"):
        unpack(np.random.default_rng(0).bytes(300))
    with pytest.raises(ProtocolError, match="over the limit"):
        unpack(pack({"blob": b"x" * 2000}), max_bytes=1000)


@pytest.mark.parametrize("n_entries", [3, 15, 16, 40])
def test_pack_map_with_prepacked_values_is_an_ordinary_map(n_entries):
    inner = {"x": np.ones(3, np.float32), "n": 4}
    message = {f"k{i}": i for i in range(n_entries - 1)}
    combined = pack_map(message, {"inner": pack_value(inner)})
    plain = msgpack.unpackb(combined, raw=False)  # what any msgpack library sees (fixmap, then map16)
    assert {k: v for k, v in plain.items() if k != "inner"} == message and plain["inner"]["n"] == 4
    assert unpack(pack({"body": combined}))["body"] == combined


def _assert_states_equal(a, b):
    assert (a.tick, a.tick_rate, a.score, a.clock_s, a.is_overtime, a.kickoff_pending, a.last_touch) == \
           (b.tick, b.tick_rate, b.score, b.clock_s, b.is_overtime, b.kickoff_pending, b.last_touch)
    assert a.cars.keys() == b.cars.keys()
    for agent in a.cars:
        for f in dataclasses.fields(a.cars[agent]):
            assert np.array_equal(getattr(a.cars[agent], f.name), getattr(b.cars[agent], f.name)), (agent, f.name)
    for f in ("pos", "vel", "ang_vel"):
        assert np.array_equal(getattr(a.ball, f), getattr(b.ball, f))
    assert np.array_equal(a.pad_timers, b.pad_timers)
    assert a.last_controls == b.last_controls
    assert a.car_configs == b.car_configs
    assert a.events == b.events and a.mode_state == b.mode_state
    assert a.arena_shape == b.arena_shape
    assert len(a.obstacles) == len(b.obstacles)
    for x, y in zip(a.obstacles, b.obstacles):
        assert np.array_equal(x.center, y.center) and np.array_equal(x.half_extents, y.half_extents)


def test_game_state_round_trip():
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", kickoff_countdown_s=0.0)
    env.reset(seed=3)
    for _ in range(40):  # moving cars, used pads, touches
        env.step({a: env.action_space(a).sample() for a in env.agents})
    state = env.rules.game_state()
    custom = dataclasses.replace(PRESETS["octane"], name="tall_octane", hitbox_size=(120.0, 86.0, 60.0))
    state = dataclasses.replace(
        state, obstacles=(Obstacle(np.array([0.0, 100.0, 50.0]), np.array([10.0, 20.0, 30.0])),),
        car_configs={**state.car_configs, "blue_1": custom}, mode_state={"round": 2, "flags": [True, False]},
        events=[Touch(5, "blue_0")])
    back = decode_state(unpack(pack({"state": encode_state(state)}))["state"])
    _assert_states_equal(state, back)
    assert back.car_configs["blue_0"] is PRESETS["octane"]  # a stock preset travels by name
    env.close()


def test_the_arena_shape_travels_with_the_state():
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", arena_shape="game")
    env.reset(seed=0)
    wire = unpack(pack({"s": encode_state(env.rules.game_state())}))["s"]
    env.close()
    assert decode_state(wire).arena_shape == "game"
    assert decode_state({k: v for k, v in wire.items() if k != "arena_shape"}).arena_shape == "classic"  # older
    with pytest.raises(ProtocolError, match=r"arena_shape: must be one of 'classic', 'game'"):
        decode_state(dict(wire, arena_shape="round"))


def test_malformed_state_is_a_protocol_error():
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml")
    env.reset(seed=0)
    wire = unpack(pack({"s": encode_state(env.rules.game_state())}))["s"]
    env.close()
    broken = dict(wire, cars={"blue_0": {**wire["cars"]["blue_0"], "rot_mat": np.eye(3) * 2}})
    with pytest.raises(ProtocolError, match="rot_mat"):
        decode_state(broken)
    with pytest.raises(ProtocolError, match="tick"):
        decode_state({k: v for k, v in wire.items() if k != "tick"})
    with pytest.raises(ProtocolError, match="unknown preset"):
        decode_state(dict(wire, car_configs={"blue_0": "batmobile"}))


def test_spaces_round_trip():
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", action="lookup")
    for space in (env.observation_space("blue_0"), env.action_space("blue_0")):
        back = decode_space(unpack(pack({"s": encode_space(space)}))["s"])
        assert back == space
    env.close()


def test_keys_and_names():
    keys = Keys("lab")
    assert keys.slot("alice", "m1", "blue_0", "obs") == "rocketdrl/lab/u/alice/match/m1/blue_0/obs"
    assert keys.lobby("alice") == "rocketdrl/lab/u/alice/lobby" and keys.parse_lobby_user(keys.lobby("bob")) == "bob"
    assert keys.parse_lobby_user("rocketdrl/lab/u/bob/invite") is None
    assert keys.parse_lobby_user("rocketdrl/other/u/bob/lobby") is None
    alive = keys.bot_alive("alice", "m1", "orange_2", "ab12")
    assert alive == "rocketdrl/lab/u/alice/match/m1/orange_2/alive/ab12"
    assert keys.parse_bot_alive(alive) == ("alice", "m1", "orange_2", "ab12")
    assert keys.parse_bot_alive("rocketdrl/other/u/alice/match/m1/blue_0/alive/x") is None
    for bad in ("a/b", "*", "**", "", "x" * 65, "a$b", 3):
        with pytest.raises(ValueError, match="server"):
            check_name("server", bad)


def test_sealed_messages_verify_and_any_change_breaks_them():
    identity, other = ServerIdentity.generate(), ServerIdentity.generate()
    key = ServerKey.parse(identity.public_text)
    assert key.raw == parse_public_key(identity.public_text) and len(key.raw) == 32
    state = pack_value({"tick": 8})
    sealed = seal(identity, {"kind": "obs", "seq": 3, "obs": np.arange(4, dtype=np.float32)}, {"state": state})
    body = open_sealed(key, sealed, 1 << 20)
    assert body["kind"] == "obs" and body["seq"] == 3 and body["state"] == {"tick": 8}
    assert np.array_equal(body["obs"], np.arange(4, dtype=np.float32))
    with pytest.raises(SignatureError):  # someone else's key
        open_sealed(key, seal(other, {"kind": "obs", "seq": 3}), 1 << 20)
    envelope = msgpack.unpackb(sealed, raw=False)
    for i in range(0, len(envelope["body"]), 7):  # flip any byte of the body: the signature no longer holds
        tampered = bytearray(envelope["body"])
        tampered[i] ^= 0x01
        with pytest.raises(SignatureError):
            open_sealed(key, pack({"body": bytes(tampered), "sig": envelope["sig"]}), 1 << 20)
    with pytest.raises(ProtocolError, match="v, body: bin, sig: bin"):
        open_sealed(key, pack({"kind": "obs", "seq": 4}), 1 << 20)  # an unsigned message
    for bad in ("ed25519:abc", "rsa:" + identity.public_text[8:], identity.public_text[:-4]):
        with pytest.raises(ValueError, match="server_key"):
            parse_public_key(bad)


def test_action_mac_covers_match_slot_decision_and_action():
    secret = random_bytes(32)
    message = action_message(secret, "m1", "blue_0", 7, np.ones(8, np.float32))
    body, mac = split_action(message)
    assert mac == action_mac(secret, body)
    assert msgpack.unpackb(body, raw=False).keys() == {"match", "slot", "decision", "action"}
    others = [action_message(secret, "m2", "blue_0", 7, np.ones(8, np.float32)),
              action_message(secret, "m1", "orange_0", 7, np.ones(8, np.float32)),
              action_message(secret, "m1", "blue_0", 8, np.ones(8, np.float32)),
              action_message(secret, "m1", "blue_0", 7, np.zeros(8, np.float32))]
    assert len({split_action(m)[1] for m in others} | {mac}) == 5  # each field changes the MAC
    assert action_mac(random_bytes(32), body) != mac
    with pytest.raises(ProtocolError, match="mac"):
        split_action(pack({"body": body, "mac": mac[:16]}))
    assert request_mac(secret, "join", "lab", "alice", b"c" * 16, b"\x80") != \
        request_mac(secret, "join", "lab", "bob", b"c" * 16, b"\x80")  # bound to the asking user


def test_both_sides_derive_the_same_slot_keys_and_nobody_else_can():
    bot, server, eve = KeyExchange(), KeyExchange(), KeyExchange()
    nonce = random_bytes()
    ours, rejoin_key = bot.slot_keys(server.public_bytes, nonce, "lab", "m1", "blue_0")
    assert (ours, rejoin_key) == server.slot_keys(bot.public_bytes, nonce, "lab", "m1", "blue_0")
    assert len(ours) == len(rejoin_key) == 32 and ours != rejoin_key  # a rejoin token never signs an action
    # someone who saw both public keys (and the nonce) but holds neither private key gets other keys
    assert eve.slot_keys(server.public_bytes, nonce, "lab", "m1", "blue_0")[0] != ours
    assert server.slot_keys(bot.public_bytes, nonce, "lab", "m1", "orange_0")[0] != ours  # bound to the slot
    with pytest.raises(ValueError, match="client_key"):
        server.slot_keys(bytes(32), nonce, "lab", "m1", "blue_0")  # a low-order point gives no secret
    with pytest.raises(ValueError, match="client_key"):
        server.slot_keys(b"short", nonce, "lab", "m1", "blue_0")


def test_tickets_are_sealed_to_the_creators_key():
    creator, server, relay = KeyExchange(), KeyExchange(), KeyExchange()
    nonce = random_bytes()
    sealed = seal_secret(server.tickets_key(creator.public_bytes, nonce, "lab", "m1"), b"tickets")
    assert open_secret(creator.tickets_key(server.public_bytes, nonce, "lab", "m1"), sealed) == b"tickets"
    with pytest.raises(ValueError, match="not sealed to this request's key"):
        open_secret(relay.tickets_key(server.public_bytes, nonce, "lab", "m1"), sealed)
