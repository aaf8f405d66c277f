"""What happened in a decision, as typed game events: the rules make them, ``GameState.events`` and the env's
``infos["events"]`` carry them, the match server sends them (``as_dict``: the documented msgpack map, ``kind``
first) and its clients read them back (``event_from_dict``).

Game events are the rules' reading of the physics' events (``physics.events``): a ball contact that starts is
a ``Touch`` (a dribble is one touch, not one per tick), and ``Shot``, ``Save``, ``Goal``, ``Miss`` and
``Overtime`` are the game mode's own.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, ClassVar


class GameEventKind(StrEnum):
    TOUCH = "touch"
    SHOT = "shot"
    SAVE = "save"
    GOAL = "goal"
    MISS = "miss"
    DEMO = "demo"
    BUMP = "bump"
    BOOST_PICKUP = "boost_pickup"
    OVERTIME = "overtime"
    AERIAL_TOUCH = "aerial_touch"


@dataclass(frozen=True)
class GameEvent:
    """``tick``: the arena's tick count when it happened."""
    tick: int
    kind: ClassVar[GameEventKind]

    @property
    def credited_to(self) -> str | None:
        """The agent the event counts for in per-agent stats (the toucher, the scorer, the attacker)."""
        return getattr(self, "agent", None)

    def as_dict(self) -> dict[str, Any]:
        """``{"kind": ..., "tick": ..., <fields>}``: the wire and replay form."""
        return {"kind": self.kind.value, **{f.name: getattr(self, f.name) for f in dataclasses.fields(self)}}


@dataclass(frozen=True)
class Touch(GameEvent):
    """``agent``'s car started a contact with the ball."""
    agent: str
    kind: ClassVar[GameEventKind] = GameEventKind.TOUCH


@dataclass(frozen=True)
class Shot(GameEvent):
    """A touch after which the ball heads into the opponents' goal."""
    agent: str
    kind: ClassVar[GameEventKind] = GameEventKind.SHOT


@dataclass(frozen=True)
class Save(GameEvent):
    """A touch that took a ball heading into the toucher's own goal off target."""
    agent: str
    kind: ClassVar[GameEventKind] = GameEventKind.SAVE


@dataclass(frozen=True)
class Goal(GameEvent):
    """``team`` (``"blue"``/``"orange"``) scored; ``scorer``: the last toucher, if any."""
    team: str
    scorer: str | None
    own_goal: bool
    kind: ClassVar[GameEventKind] = GameEventKind.GOAL

    @property
    def credited_to(self) -> str | None:
        return self.scorer


@dataclass(frozen=True)
class Miss(GameEvent):
    """A minigame round ended without a goal; ``reason`` says how (``timeout``, ``wide``, ``retreat``, ...)."""
    reason: str | None
    kind: ClassVar[GameEventKind] = GameEventKind.MISS


@dataclass(frozen=True)
class CarHit(GameEvent):
    """``agent``'s car hit ``victim``'s (the physics' ``BumperHit``): a ``Demo`` or a ``Bump``."""
    agent: str
    victim: str


@dataclass(frozen=True)
class Demo(CarHit):
    """``agent`` demolished ``victim``."""
    kind: ClassVar[GameEventKind] = GameEventKind.DEMO


@dataclass(frozen=True)
class Bump(CarHit):
    """``agent`` bumped ``victim``."""
    kind: ClassVar[GameEventKind] = GameEventKind.BUMP


@dataclass(frozen=True)
class BoostPickup(GameEvent):
    """``agent`` took boost pad ``pad`` (RocketSim's pad order)."""
    agent: str
    pad: int
    kind: ClassVar[GameEventKind] = GameEventKind.BOOST_PICKUP


@dataclass(frozen=True)
class Overtime(GameEvent):
    """The clock ran out on a tie: golden-goal overtime begins."""
    kind: ClassVar[GameEventKind] = GameEventKind.OVERTIME


@dataclass(frozen=True)
class AerialTouch(GameEvent):
    """Aerial's scoring touch: ``agent`` touched the ball airborne, its car's centre ``car_z_uu`` high."""
    agent: str
    car_z_uu: float
    kind: ClassVar[GameEventKind] = GameEventKind.AERIAL_TOUCH


def describe_event(event: GameEvent, tick_rate: int = 120) -> str:
    """One line for a console: game time, then what happened."""
    t = f"{event.tick / tick_rate:7.1f} s"
    if isinstance(event, Goal):
        return f"{t}  GOAL {event.team} ({event.scorer or 'nobody'}{', own goal' if event.own_goal else ''})"
    if isinstance(event, CarHit):
        return f"{t}  {event.kind.value}: {event.agent} hit {event.victim}"
    if isinstance(event, Miss):
        return f"{t}  miss ({event.reason})"
    if isinstance(event, Overtime):
        return f"{t}  overtime"
    return f"{t}  {event.kind.value} by {event.credited_to}"


EVENT_TYPES: dict[GameEventKind, type[GameEvent]] = {
    cls.kind: cls for cls in (Touch, Shot, Save, Goal, Miss, Demo, Bump, BoostPickup, Overtime, AerialTouch)}

_FIELD_TYPES = {"tick": int, "agent": str, "victim": str, "team": str, "scorer": (str, type(None)),
                "own_goal": bool, "reason": (str, type(None)), "pad": int, "car_z_uu": (int, float)}


def event_from_dict(d: Any) -> GameEvent | None:
    """The typed event of an ``as_dict`` map; None for a kind this version does not know (a newer peer may send
    more kinds). A map that names a known kind but lacks or mistypes a field is a ValueError naming the field."""
    if not isinstance(d, dict):
        raise ValueError(f"event: expected a map, got {type(d).__name__}")
    try:
        cls = EVENT_TYPES[GameEventKind(d.get("kind"))]
    except ValueError:
        return None
    values = {}
    for field in dataclasses.fields(cls):
        value = d.get(field.name)
        allowed = _FIELD_TYPES[field.name]
        if isinstance(value, bool) and allowed in (int, (int, float)) or not isinstance(value, allowed):
            raise ValueError(f"event {cls.kind.value}.{field.name}: expected {allowed}, got {value!r}")
        values[field.name] = value
    return cls(**values)


def events_from_dicts(maps: Any) -> list[GameEvent]:
    """``event_from_dict`` of each map, kinds this version does not know left out; a ValueError as it says."""
    if not isinstance(maps, (list, tuple)):
        raise ValueError(f"events: expected a list, got {type(maps).__name__}")
    return [event for event in map(event_from_dict, maps) if event is not None]
