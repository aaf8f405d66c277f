"""The wire protocol of the match server: key expressions, msgpack payloads, the protocol version.

Every payload is one msgpack map carrying ``"v": PROTOCOL_VERSION``. A numpy array travels as the map
``{"$nd": <dtype string, e.g. "<f4">, "shape": [..], "data": <raw bytes, C order>}``, so any msgpack
library can read it; only numeric and boolean dtypes are accepted. A ``GameState`` travels as a map of
its fields (``encode_state``/``decode_state``), cars keyed by agent.

Key expressions (``<server>`` names the server, ``<id>`` a match, ``<slot>`` an agent such as ``blue_0``):

    rocketdrl/<server>/lobby                     queryable: create, list, inspect, stop, join, leave
    rocketdrl/<server>/alive                     liveliness token of the running server
    rocketdrl/<server>/match/<id>/state          each decision: the game state, scoreboard and slots
    rocketdrl/<server>/match/<id>/events         each decision with events; the end-of-match summary
    rocketdrl/<server>/match/<id>/<slot>/obs     server -> bot: observation, reward, info, state
    rocketdrl/<server>/match/<id>/<slot>/act     bot -> server: token, decision number, action
    rocketdrl/<server>/match/<id>/<slot>/error   server -> bot: why an action was refused
    rocketdrl/<server>/match/<id>/<slot>/alive/<lease>   liveliness token of the bot holding the slot
"""
from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import msgpack
import numpy as np

from rocketdrl_ma.physics import PRESETS, BallState, CarConfig, CarControls, CarState
from rocketdrl_ma.physics.car_config import WheelPair
from rocketdrl_ma.rules.state import GameState, Obstacle

PROTOCOL_VERSION = 1
#: the largest action message the server decodes; anything bigger is dropped unread
MAX_ACTION_BYTES = 64 * 1024
#: the largest lobby request (create carries a config)
MAX_REQUEST_BYTES = 1024 * 1024
_NAME = re.compile(r"^[A-Za-z0-9_\-]{1,64}$")
_ND_KINDS = "biuf"  # bool, signed, unsigned, float: never objects, strings or void
_CAR_FIELDS = tuple(f.name for f in dataclasses.fields(CarState))
_CONTROL_FIELDS = tuple(f.name for f in dataclasses.fields(CarControls))


class ProtocolError(ValueError):
    """A payload that does not follow the protocol; the message says which field and why."""


class VersionError(ProtocolError):
    """A message of another protocol version."""


def check_name(field: str, value: Any) -> str:
    """Server names, match ids and slots become key-expression chunks: letters, digits, ``_`` and ``-``."""
    if not isinstance(value, str) or not _NAME.match(value):
        raise ValueError(f"{field}: expected 1-64 letters, digits, '_' or '-', got {value!r}")
    return value


class Keys:
    """The key expressions of one server (see the module docstring)."""

    def __init__(self, server: str):
        self.server = check_name("server", server)
        self.root = f"rocketdrl/{server}"
        self.lobby = f"{self.root}/lobby"
        self.server_alive = f"{self.root}/alive"
        self.all_bot_alive = f"{self.root}/match/*/*/alive/*"

    def match(self, match_id: str) -> str:
        return f"{self.root}/match/{match_id}"

    def state(self, match_id: str) -> str:
        return f"{self.match(match_id)}/state"

    def events(self, match_id: str) -> str:
        return f"{self.match(match_id)}/events"

    def slot(self, match_id: str, slot: str, leaf: str) -> str:
        return f"{self.match(match_id)}/{slot}/{leaf}"

    def all_actions(self, match_id: str) -> str:
        return f"{self.match(match_id)}/*/act"

    def bot_alive(self, match_id: str, slot: str, lease: str) -> str:
        return f"{self.match(match_id)}/{slot}/alive/{lease}"

    def parse_bot_alive(self, key: str) -> tuple[str, str, str] | None:
        """``(match_id, slot, lease)`` of a bot liveliness key, None for any other key."""
        parts = key.split("/")
        if len(parts) != 7 or "/".join(parts[:2]) != self.root or parts[2] != "match" or parts[5] != "alive":
            return None
        return parts[3], parts[4], parts[6]

    def parse_action_slot(self, match_id: str, key: str) -> str | None:
        prefix = self.match(match_id) + "/"
        if not key.startswith(prefix) or not key.endswith("/act"):
            return None
        return key[len(prefix):-len("/act")]


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
    """Any value as msgpack bytes (no version: for ``pack_with_raw``'s pre-packed parts)."""
    return msgpack.packb(value, default=_default, use_bin_type=True)


def pack(message: dict) -> bytes:
    """One message as msgpack bytes, with the protocol version added."""
    return msgpack.packb({"v": PROTOCOL_VERSION, **message}, default=_default, use_bin_type=True)


def pack_with_raw(message: dict, raw: dict[str, bytes]) -> bytes:
    """``pack`` with some values already packed (``raw``: key -> msgpack bytes), e.g. one game state sent
    to several bots is encoded once. The result is an ordinary msgpack map."""
    n = len(message) + len(raw) + 1
    if n > 15:
        raise ValueError(f"message: {n} entries; pack_with_raw builds fixmaps of at most 15")
    parts = [bytes([0x80 | n]), msgpack.packb("v"), msgpack.packb(PROTOCOL_VERSION)]
    for key, value in message.items():
        parts += [msgpack.packb(key), msgpack.packb(value, default=_default, use_bin_type=True)]
    for key, value in raw.items():
        parts += [msgpack.packb(key), value]
    return b"".join(parts)


def unpack(payload: bytes, max_bytes: int = MAX_REQUEST_BYTES) -> dict:
    """Decode and check one message: its size, that it is a map, and its protocol version."""
    if len(payload) > max_bytes:
        raise ProtocolError(f"message: {len(payload)} bytes is over the limit of {max_bytes}")
    try:
        message = msgpack.unpackb(payload, raw=False, object_hook=_object_hook, strict_map_key=False)
    except ProtocolError:
        raise
    except Exception as e:  # msgpack raises several unrelated types for garbage
        raise ProtocolError(f"message: not valid msgpack ({type(e).__name__}: {e})") from None
    if not isinstance(message, dict):
        raise ProtocolError(f"message: expected a map, got {type(message).__name__}")
    version = message.get("v")
    if version != PROTOCOL_VERSION:
        raise VersionError(f"v: protocol version {version!r} is not supported; this server speaks version "
                            f"{PROTOCOL_VERSION}")
    return message


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
        "events": state.events,
        "car_configs": {agent: _config_to_wire(c) for agent, c in state.car_configs.items()},
        "mode_state": state.mode_state,
    }


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
            events=list(d["events"]),
            car_configs={agent: _config_from_wire(c) for agent, c in d["car_configs"].items()},
            mode_state=dict(d["mode_state"]))
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
