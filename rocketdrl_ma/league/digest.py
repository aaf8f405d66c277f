"""Fingerprints of a played match, so a replay can be compared with the original bit for bit.

``match_digests`` gives the arena's tick count at the end, a sha256 of the final physics state (every car's
``CarState`` and ``CarExtraState``, the ball, the boost pad timers, score, clock and last touch) and a sha256 of
the match's game events in order. Values are hashed through their JSON text, whose floats are Python's ``repr``:
exact for float64 and float32, so equal digests mean equal bits.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from enum import Enum
from typing import Any

import numpy as np

from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.rules.events import GameEvent


def sha256_of(value: Any) -> str:
    """The sha256 of ``value``'s canonical JSON (sorted keys; arrays, dataclasses and enums as plain values)."""
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), default=_plain)
    return hashlib.sha256(text.encode()).hexdigest()


def _plain(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Enum):
        return obj.value
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    raise TypeError(f"{type(obj).__name__} has no canonical form to hash")


def final_state(env: RocketDRLParallelEnv) -> dict[str, Any]:
    """Everything the physics and the rules hold at the end of an episode, as plain values."""
    state = env.game_state
    cars = {agent: {"state": car.get_state(), "extra": car.get_extra_state()}
            for agent, car in sorted(env.rules.cars.items())}
    return {"tick": state.tick, "cars": cars, "ball": state.ball, "pad_timers": state.pad_timers,
            "score": list(state.score), "clock_s": state.clock_s, "is_overtime": state.is_overtime,
            "last_touch": state.last_touch}


def match_digests(env: RocketDRLParallelEnv, events: list[GameEvent]) -> dict[str, Any]:
    """``ticks``, ``state_sha256`` (of ``final_state``), ``events`` (how many) and ``events_sha256`` of a match
    ``env`` has just played to its end, ``events`` being every decision's game events in order."""
    return {"ticks": int(env.game_state.tick), "state_sha256": sha256_of(final_state(env)),
            "events": len(events), "events_sha256": sha256_of([event.as_dict() for event in events])}
