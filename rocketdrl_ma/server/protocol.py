"""The wire protocol of the match server: key expressions, msgpack payloads, signed and MAC'd envelopes.

Every payload is one msgpack map carrying ``"v": PROTOCOL_VERSION``. A numpy array travels as the map
``{"$nd": <dtype string, e.g. "<f4">, "shape": [..], "data": <raw bytes, C order>}``, so any msgpack
library can read it; only numeric and boolean dtypes are accepted. A ``GameState`` travels as a map of
its fields (``encode_state``/``decode_state``), cars keyed by agent.

What the server sends is *sealed*: ``{"v": 2, "body": <bin: a msgpack map>, "sig": <Ed25519 signature>}``
(``seal``/``open_sealed``; ``crypto`` says what is signed). An action is ``{"v": 2, "body": <bin: {match,
slot, decision, action}>, "mac": <HMAC-SHA256 under the slot's secret>}`` (``action_message``).

Key expressions (``<server>`` names the server, ``<user>`` the client's user, ``<id>`` a match, ``<slot>``
an agent such as ``blue_0``). Per-slot traffic lives under its player's prefix ``u/<user>``: with Zenoh
access control on, only that user (and the server) may use it, so the key says who sent a message.

    rocketdrl/<server>/key                                   queryable: the server's public key (signed)
    rocketdrl/<server>/alive                                 liveliness token of the running server
    rocketdrl/<server>/u/<user>/lobby                        queryable: every lobby op, asked by <user>
    rocketdrl/<server>/u/<user>/invite                       queryable of a league entrant's bot
    rocketdrl/<server>/u/<user>/match/<id>/<slot>/obs        server -> bot: observation, reward, state
    rocketdrl/<server>/u/<user>/match/<id>/<slot>/act        bot -> server: decision number, action, MAC
    rocketdrl/<server>/u/<user>/match/<id>/<slot>/error      server -> bot: why an action was refused
    rocketdrl/<server>/u/<user>/match/<id>/<slot>/alive/<lease>   liveliness token of the bot
    rocketdrl/<server>/match/<id>/state                      each decision: the game state, scoreboard, slots
    rocketdrl/<server>/match/<id>/events                     decisions with events; the end-of-match message
"""
from __future__ import annotations

import dataclasses
import math
from enum import StrEnum
from typing import Any

import msgpack
import numpy as np

from rocketdrl_ma.physics import PRESETS, BallState, CarConfig, CarControls, CarState
from rocketdrl_ma.physics.arena_shape import DEFAULT_ARENA_SHAPE, arena_shape_index
from rocketdrl_ma.physics.car_config import WheelPair
from rocketdrl_ma.rules.events import GameEvent, events_from_dicts
from rocketdrl_ma.rules.state import GameState, Obstacle
from rocketdrl_ma.validation import check_name

from .crypto import MAC_BYTES, ServerIdentity, ServerKey, action_mac

PROTOCOL_VERSION = 2
#: the largest action message the server decodes; anything bigger is dropped unread
MAX_ACTION_BYTES = 64 * 1024
#: the largest lobby request, and what Zenoh itself reassembles (``transport/link/rx/max_message_size``)
MAX_REQUEST_BYTES = 1024 * 1024
MAX_MESSAGE_BYTES = MAX_REQUEST_BYTES + 64 * 1024
_ND_KINDS = "biuf"  # bool, signed, unsigned, float: never objects, strings or void
_CAR_FIELDS = tuple(f.name for f in dataclasses.fields(CarState))
_CONTROL_FIELDS = tuple(f.name for f in dataclasses.fields(CarControls))


class MatchStatus(StrEnum):
    """A match is waiting (for its bots), then running, then finished, stopped (by an admin or the server) or
    failed (an internal error). On the wire, the plain string."""
    WAITING = "waiting"
    RUNNING = "running"
    FINISHED = "finished"
    STOPPED = "stopped"
    FAILED = "failed"


ENDED_STATUSES = frozenset({MatchStatus.FINISHED, MatchStatus.STOPPED, MatchStatus.FAILED})


class ProtocolError(ValueError):
    """A payload that does not follow the protocol; the message says which field and why."""


class VersionError(ProtocolError):
    """A message of another protocol version."""


class Keys:
    """The key expressions of one server (see the module docstring)."""

    def __init__(self, server: str):
        self.server = check_name("server", server)
        self.root = f"rocketdrl/{server}"
        self.key = f"{self.root}/key"
        self.server_alive = f"{self.root}/alive"
        self.all_lobbies = f"{self.root}/u/*/lobby"
        self.all_bot_alive = f"{self.root}/u/*/match/*/*/alive/*"

    def user(self, user: str) -> str:
        return f"{self.root}/u/{user}"

    def lobby(self, user: str) -> str:
        return f"{self.user(user)}/lobby"

    def invite(self, user: str) -> str:
        return f"{self.user(user)}/invite"

    def match(self, match_id: str) -> str:
        return f"{self.root}/match/{match_id}"

    def state(self, match_id: str) -> str:
        return f"{self.match(match_id)}/state"

    def events(self, match_id: str) -> str:
        return f"{self.match(match_id)}/events"

    def slot(self, user: str, match_id: str, slot: str, leaf: str) -> str:
        return f"{self.user(user)}/match/{match_id}/{slot}/{leaf}"

    def bot_alive(self, user: str, match_id: str, slot: str, lease: str) -> str:
        return self.slot(user, match_id, slot, f"alive/{lease}")

    def _user_parts(self, key: str) -> list[str] | None:
        parts = key.split("/")
        if len(parts) < 4 or "/".join(parts[:2]) != self.root or parts[2] != "u":
            return None
        return parts[3:]

    def parse_lobby_user(self, key: str) -> str | None:
        """The user of a lobby key, None for any other key."""
        parts = self._user_parts(key)
        return parts[0] if parts is not None and len(parts) == 2 and parts[1] == "lobby" else None

    def parse_bot_alive(self, key: str) -> tuple[str, str, str, str] | None:
        """``(user, match_id, slot, lease)`` of a bot liveliness key, None for any other key."""
        parts = self._user_parts(key)
        if parts is None or len(parts) != 6 or parts[1] != "match" or parts[4] != "alive":
            return None
        return parts[0], parts[2], parts[3], parts[5]


# ---------------------------------------------------------------------------------------------- msgpack
def _default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind not in _ND_KINDS:
            raise TypeError(f"arrays of dtype {obj.dtype} cannot travel; use a numeric or bool dtype")
        arr = np.ascontiguousarray(obj)
        return {"$nd": arr.dtype.str, "shape": list(arr.shape), "data": arr.tobytes()}
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, (tuple, set, frozenset)):
        return list(obj)
    raise TypeError(f"{type(obj).__name__} cannot travel in a message")


def _decode_array(d: dict) -> np.ndarray:
    dtype_str, shape, data = d.get("$nd"), d.get("shape"), d.get("data")
    try:
        dtype = np.dtype(dtype_str)
    except TypeError:
        raise ProtocolError(f"array: unknown dtype {dtype_str!r}") from None
    if dtype.kind not in _ND_KINDS or dtype.itemsize > 8:
        raise ProtocolError(f"array: dtype {dtype_str!r} is not allowed (bool, int, uint or float only)")
    if not (isinstance(shape, list) and all(isinstance(n, int) and n >= 0 for n in shape) and len(shape) <= 8):
        raise ProtocolError(f"array: shape must be a list of at most 8 sizes >= 0, got {shape!r}")
    if not isinstance(data, bytes) or len(data) != math.prod(shape) * dtype.itemsize:
        raise ProtocolError(f"array: {len(data) if isinstance(data, bytes) else type(data).__name__} bytes of data"
                            f" do not fill shape {shape} of {dtype_str}")
    return np.frombuffer(data, dtype=dtype).reshape(shape).copy()


def _object_hook(d: dict) -> Any:
    return _decode_array(d) if "$nd" in d else d


def pack_value(value: Any) -> bytes:
    """Any value as msgpack bytes (e.g. a game state encoded once and put into several bodies)."""
    return msgpack.packb(value, default=_default, use_bin_type=True)


def _map_header(n: int) -> bytes:
    return bytes([0x80 | n]) if n <= 15 else b"\xde" + n.to_bytes(2, "big") if n < 1 << 16 else \
        b"\xdf" + n.to_bytes(4, "big")


def pack_map(message: dict, raw: dict[str, bytes] | None = None) -> bytes:
    """A msgpack map of ``message`` plus values already packed (``raw``: key -> msgpack bytes). The result
    is an ordinary msgpack map: ``message`` packed in one call, its header rewritten to count ``raw`` too."""
    packed = pack_value(message)
    if not raw:
        return packed
    head = packed[0]
    skip = 1 if head & 0xF0 == 0x80 else 3 if head == 0xDE else 5
    parts = [_map_header(len(message) + len(raw)), packed[skip:]]
    for key, value in raw.items():
        parts += [msgpack.packb(key), value]
    return b"".join(parts)


def pack(message: dict) -> bytes:
    """One message as msgpack bytes, with the protocol version added."""
    return pack_value({"v": PROTOCOL_VERSION, **message})


def unpack_map(payload: bytes, max_bytes: int, what: str = "message") -> dict:
    """Decode a msgpack map (arrays included), checking its size first."""
    if len(payload) > max_bytes:
        raise ProtocolError(f"{what}: {len(payload)} bytes is over the limit of {max_bytes}")
    try:
        message = msgpack.unpackb(payload, raw=False, object_hook=_object_hook, strict_map_key=False)
    except ProtocolError:
        raise
    except Exception as e:  # msgpack raises several unrelated types for garbage
        raise ProtocolError(f"{what}: not valid msgpack ({type(e).__name__}: {e})") from None
    if not isinstance(message, dict):
        raise ProtocolError(f"{what}: expected a map, got {type(message).__name__}")
    return message


def unpack(payload: bytes, max_bytes: int = MAX_REQUEST_BYTES) -> dict:
    """Decode and check one message: its size, that it is a map, and its protocol version."""
    message = unpack_map(payload, max_bytes)
    version = message.get("v")
    if version != PROTOCOL_VERSION:
        raise VersionError(f"v: protocol version {version!r} is not supported; this server speaks version "
                            f"{PROTOCOL_VERSION}")
    return message


# ---------------------------------------------------------------------------------------------- envelopes
def seal(identity: ServerIdentity, body: dict, raw: dict[str, bytes] | None = None) -> bytes:
    """A server message: the body (a msgpack map, some values possibly pre-packed) and its signature."""
    packed = pack_map(body, raw)
    return pack({"body": packed, "sig": identity.sign(packed)})


def open_sealed(key: ServerKey, payload: bytes, max_bytes: int) -> dict:
    """The body of a server message, once its signature is checked (``SignatureError`` otherwise)."""
    message = unpack(payload, max_bytes)
    body, signature = message.get("body"), message.get("sig")
    if not isinstance(body, bytes) or not isinstance(signature, bytes):
        raise ProtocolError("message: a server message is {v, body: bin, sig: bin}")
    key.verify(body, signature)
    return unpack_map(body, max_bytes, "body")


def action_message(secret: bytes, match_id: str, slot: str, decision: int, action: Any) -> bytes:
    """What a bot publishes on its ``act`` key for ``decision``."""
    body = pack_value({"match": match_id, "slot": slot, "decision": decision, "action": action})
    return pack({"body": body, "mac": action_mac(secret, body)})


def split_action(payload: bytes) -> tuple[bytes, bytes]:
    """``(body, mac)`` of an action message (size and version checked; the MAC is not)."""
    message = unpack(payload, MAX_ACTION_BYTES)
    body, mac = message.get("body"), message.get("mac")
    if not isinstance(body, bytes) or not isinstance(mac, bytes) or len(mac) != MAC_BYTES:
        raise ProtocolError("action: expected {v, body: bin, mac: 32-byte bin}")
    return body, mac


# ---------------------------------------------------------------------------------------------- game state
def _car_to_wire(car: CarState) -> dict:
    return {name: getattr(car, name) for name in _CAR_FIELDS}


def _car_from_wire(d: dict) -> CarState:
    known = {name: d[name] for name in _CAR_FIELDS if name in d}
    if "wheels_in_contact" in known:
        known["wheels_in_contact"] = tuple(bool(w) for w in known["wheels_in_contact"])
    return CarState(**known)


def _config_to_wire(config: CarConfig) -> str | dict:
    # A stock preset travels by name; a custom hitbox in full.
    return config.name if PRESETS.get(config.name) == config else dataclasses.asdict(config)


def _config_from_wire(value: str | dict) -> CarConfig:
    if isinstance(value, str):
        if value not in PRESETS:
            raise ProtocolError(f"car_configs: unknown preset {value!r}; allowed: {sorted(PRESETS)}")
        return PRESETS[value]
    wheels = {k: WheelPair(value[k]["radius"], value[k]["rest_length_config"], tuple(value[k]["connection"]))
              for k in ("front", "back")}
    return CarConfig(value["name"], tuple(value["hitbox_size"]), tuple(value["hitbox_offset"]), wheels["front"],
                     wheels["back"], bool(value.get("three_wheel", False)))


def encode_state(state: GameState) -> dict:
    """A ``GameState`` as a msgpack-ready map (arrays stay numpy and travel as raw bytes)."""
    return {
        "tick": state.tick, "tick_rate": state.tick_rate,
        "cars": {agent: _car_to_wire(car) for agent, car in state.cars.items()},
        "ball": {"pos": state.ball.pos, "vel": state.ball.vel, "ang_vel": state.ball.ang_vel},
        "pad_timers": np.asarray(state.pad_timers, dtype=np.float64),
        "last_controls": {agent: c.as_array() for agent, c in state.last_controls.items()},
        "score": list(state.score), "clock_s": state.clock_s, "is_overtime": state.is_overtime,
        "kickoff_pending": state.kickoff_pending, "last_touch": state.last_touch,
        "obstacles": [[np.asarray(o.center), np.asarray(o.half_extents)] for o in state.obstacles],
        "events": [event.as_dict() for event in state.events],
        "car_configs": {agent: _config_to_wire(c) for agent, c in state.car_configs.items()},
        "mode_state": state.mode_state, "arena_shape": state.arena_shape,
    }


def decode_events(events: Any) -> list[GameEvent]:
    """Typed events from their wire maps; kinds this version does not know are left out (a newer server may send
    more), a known kind with a bad field is a ProtocolError."""
    try:
        return events_from_dicts(events)
    except (TypeError, ValueError) as e:
        raise ProtocolError(str(e)) from None


def _arena_shape_from_wire(d: dict) -> str:
    """The state's arena shape; a server older than the key plays in the classic arena."""
    shape = d.get("arena_shape", DEFAULT_ARENA_SHAPE)
    arena_shape_index(shape)  # a ValueError (a ProtocolError below) naming the shapes
    return shape


def decode_state(d: Any) -> GameState:
    """Rebuild a ``GameState`` from ``encode_state``'s map; a malformed one is a ProtocolError."""
    try:
        controls = {}
        for agent, values in d["last_controls"].items():
            kw = dict(zip(_CONTROL_FIELDS, (float(v) for v in values)))
            for button in ("jump", "boost", "handbrake"):
                kw[button] = kw[button] > 0.0
            controls[agent] = CarControls(**kw)
        return GameState(
            tick=int(d["tick"]), tick_rate=int(d["tick_rate"]),
            cars={agent: _car_from_wire(car) for agent, car in d["cars"].items()},
            ball=BallState(**d["ball"]), pad_timers=np.asarray(d["pad_timers"], dtype=np.float64),
            last_controls=controls, score=(int(d["score"][0]), int(d["score"][1])), clock_s=float(d["clock_s"]),
            is_overtime=bool(d["is_overtime"]), kickoff_pending=bool(d["kickoff_pending"]),
            last_touch=d["last_touch"],
            obstacles=tuple(Obstacle(np.asarray(c, dtype=np.float64), np.asarray(h, dtype=np.float64))
                            for c, h in d["obstacles"]),
            events=decode_events(d["events"]),
            car_configs={agent: _config_from_wire(c) for agent, c in d["car_configs"].items()},
            mode_state=dict(d["mode_state"]), arena_shape=_arena_shape_from_wire(d))
    except ProtocolError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as e:
        raise ProtocolError(f"state: malformed game state ({type(e).__name__}: {e})") from None


# ---------------------------------------------------------------------------------------------- spaces
def encode_space(space) -> dict:
    """A gymnasium Box or Discrete as a map a bot can rebuild (``decode_space``)."""
    from gymnasium import spaces
    if isinstance(space, spaces.Box):
        return {"kind": "box", "low": space.low, "high": space.high, "dtype": space.dtype.str}
    if isinstance(space, spaces.Discrete):
        return {"kind": "discrete", "n": int(space.n), "start": int(space.start)}
    raise ValueError(f"space: {type(space).__name__} has no wire form (Box or Discrete)")


def decode_space(d: dict):
    from gymnasium import spaces
    if d.get("kind") == "box":
        return spaces.Box(d["low"], d["high"], dtype=np.dtype(d["dtype"]))
    if d.get("kind") == "discrete":
        return spaces.Discrete(d["n"], start=d.get("start", 0))
    raise ProtocolError(f"space: unknown kind {d.get('kind')!r}")
