"""What the page receives: a roster once per source, then one compact msgpack frame per shown state.

Every message from the page server to the page is one msgpack map with a ``type``. A *frame* carries only
what the view draws, as float32 (``use_single_float``), so a 4v4 state is a few hundred bytes:

    {"type": "frame", "t": tick, "r": tick_rate, "c": clock_s, "o": overtime, "k": kickoff_pending,
     "s": [blue, orange], "b": [x, y, z] (ball, uu), "a": [car or null, ...] in roster order,
     "p": bit mask of the active boost pads (bit i = pad i in RLBot order), "e": [event, ...],
     "x": [[cx, cy, cz, hx, hy, hz], ...] (obstacles; only when there are some)}

A car is ``[x, y, z, qx, qy, qz, qw, boost, flags]``: position in uu, the quaternion of its rotation matrix
(columns forward, right, up: the page's car model points forward along +x, right along +y, up along +z),
boost 0-100 and ``flags`` (``FLAG_*``). Events are the ones worth a line in the feed (``FEED_EVENTS``),
trimmed to their fields.

The *roster* (``{"type": "roster", "agents", "teams", "hitboxes", ...}``) names the cars and their hitbox
(length, width, height, offset x, y, z in uu) so the page builds each car once, and ``countdown_s``, the
match's kickoff countdown when the page server knows it (the page counts it down).
"""
from __future__ import annotations

from typing import Any, Iterable

import msgpack
import numpy as np

from rocketdrl_ma.physics import PRESETS
from rocketdrl_ma.physics.frames import rot_mat_to_quat_raw
from rocketdrl_ma.rules.events import GameEvent, GameEventKind
from rocketdrl_ma.rules.state import GameState, agent_team

FLAG_DEMOED = 1
FLAG_BOOSTING = 2
FLAG_SUPERSONIC = 4
FLAG_ON_GROUND = 8
FLAG_IN_AIR_MOVE = 16  # jumping or flipping
#: event kinds the page's feed shows, and the fields each keeps
FEED_EVENTS = frozenset({GameEventKind.GOAL, GameEventKind.SAVE, GameEventKind.DEMO, GameEventKind.SHOT,
                         GameEventKind.OVERTIME, GameEventKind.MISS})


def pack_message(message: dict) -> bytes:
    """One page message as msgpack bytes (floats as float32)."""
    return msgpack.packb(message, use_bin_type=True, use_single_float=True)


def rotation_to_quaternion(rot: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a proper rotation matrix (``physics.frames``), with ``w >= 0``."""
    x, y, z, w = rot_mat_to_quat_raw(np.asarray(rot, dtype=np.float64))
    if w < 0.0:  # one sign per rotation, so consecutive frames interpolate the short way more often
        w, x, y, z = -w, -x, -y, -z
    return x, y, z, w


def feed_events(events: Iterable[GameEvent]) -> list[dict]:
    """The events the feed shows (``FEED_EVENTS``), as their wire maps."""
    return [event.as_dict() for event in events if event.kind in FEED_EVENTS]


def roster(state: GameState, names: dict[str, str] | None = None, **extra: Any) -> dict:
    """The cars of ``state`` in a fixed order (blue first), with their team, hitbox and display name."""
    agents = sorted(set(state.cars) | set(state.car_configs), key=lambda a: (agent_team(a), a))
    hitboxes = []
    for agent in agents:
        config = state.car_configs.get(agent, PRESETS["octane"])
        hitboxes.append([float(v) for v in (*config.hitbox_size, *config.hitbox_offset)])
    names = names or {}
    return {"type": "roster", "agents": agents, "teams": [agent_team(a) for a in agents], "hitboxes": hitboxes,
            "names": [names.get(a, a) for a in agents], **extra}


def frame(state: GameState, agents: list[str], events: Iterable[dict] = ()) -> dict:
    """The page's frame of ``state``, cars in ``agents`` order (a missing car is null)."""
    cars: list[Any] = []
    for agent in agents:
        car = state.cars.get(agent)
        if car is None:
            cars.append(None)
            continue
        controls = state.last_controls.get(agent)
        flags = ((FLAG_DEMOED if car.is_demoed else 0)
                 | (FLAG_BOOSTING if controls is not None and controls.boost and car.boost > 0.0 and not car.is_demoed
                    else 0)
                 | (FLAG_SUPERSONIC if car.is_supersonic else 0) | (FLAG_ON_GROUND if car.on_ground else 0)
                 | (FLAG_IN_AIR_MOVE if car.is_jumping or car.is_flipping else 0))
        pos = car.pos
        cars.append([float(pos[0]), float(pos[1]), float(pos[2]), *rotation_to_quaternion(car.rot_mat),
                     float(car.boost), flags])
    active = np.flatnonzero(np.asarray(state.pad_timers).ravel() <= 0.0)
    message = {"type": "frame", "t": int(state.tick), "r": int(state.tick_rate), "c": float(state.clock_s),
               "o": bool(state.is_overtime), "k": bool(state.kickoff_pending),
               "s": [int(state.score[0]), int(state.score[1])], "b": [float(v) for v in state.ball.pos],
               "a": cars, "p": int(sum(1 << int(i) for i in active)), "e": feed_events(events)}
    if state.obstacles:
        message["x"] = [[float(v) for v in (*o.center, *o.half_extents)] for o in state.obstacles]
    return message
