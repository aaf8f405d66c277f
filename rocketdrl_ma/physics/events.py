"""What happened during a tick, for game logic: typed physics events, drained with ``Arena.drain_events()``.

RocketSim reports these through callbacks (ball touch, car bump / demo, boost pickup); here every tick appends
them to its arena's list, in the order the tick produced them, and game logic takes them when it wants them.
Every event names its arena (the index in the batch) and the tick it happened on (``Arena.tick_count`` after
that tick). They describe contacts; the rules' events (``rules.events``: ``Touch``, ``Bump``, ``Demo``,
``BoostPickup``...) are their game meaning, and are named apart from these.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from enum import StrEnum
from typing import ClassVar

Vec3 = tuple[float, float, float]


class PhysicsEventKind(StrEnum):
    BALL_TOUCH = "ball_touch"
    BUMP = "bump"
    DEMO = "demo"
    BOOST_PICKUP = "boost_pickup"


@dataclass(frozen=True, slots=True)
class BallTouch:
    """A car in contact with the ball on this tick. Like RocketSim's touch callback it fires on every tick of a
    contact (a car carrying the ball touches it 120 times a second); ``extra_impulse`` tells the ticks on which
    Rocket League's extra push was applied."""
    tick: int
    arena: int
    car_id: int
    contact_point: Vec3     # uu, arena frame: the contact point on the ball's surface
    contact_normal: Vec3    # unit, from the car towards the ball
    extra_impulse: bool
    kind: ClassVar[PhysicsEventKind] = PhysicsEventKind.BALL_TOUCH


@dataclass(frozen=True, slots=True)
class BumperHit:
    """``attacker_id`` hit ``victim_id`` with its front bumper (RocketSim's car bump callback): ``CarBumped`` or
    ``CarDemolished``."""
    tick: int
    arena: int
    attacker_id: int
    victim_id: int


@dataclass(frozen=True, slots=True)
class CarBumped(BumperHit):
    """The victim was pushed away (not demolished)."""
    kind: ClassVar[PhysicsEventKind] = PhysicsEventKind.BUMP


@dataclass(frozen=True, slots=True)
class CarDemolished(BumperHit):
    """The victim was demolished (RocketSim's bump callback with ``is_demo``)."""
    kind: ClassVar[PhysicsEventKind] = PhysicsEventKind.DEMO


@dataclass(frozen=True, slots=True)
class BoostPadTaken:
    """``car_id`` took boost pad ``pad_index`` (``Arena.get_boost_pads()`` order) and gained ``amount``."""
    tick: int
    arena: int
    car_id: int
    pad_index: int
    amount: float
    kind: ClassVar[PhysicsEventKind] = PhysicsEventKind.BOOST_PICKUP


PhysicsEvent = BallTouch | CarBumped | CarDemolished | BoostPadTaken

#: the names these events had when they shared them with the rules' events
RENAMED = {"CarHit": "BumperHit", "Bump": "CarBumped", "Demo": "CarDemolished", "BoostPickup": "BoostPadTaken"}


def renamed(module: str, name: str) -> type:
    """An event class asked for by its old name (``RENAMED``), with a DeprecationWarning naming the new one."""
    if name not in RENAMED:
        raise AttributeError(f"module {module!r} has no attribute {name!r}")
    new = RENAMED[name]
    warnings.warn(f"{module}.{name} is now {new} (the rules' events keep the name {name})", DeprecationWarning,
                  stacklevel=3)
    return globals()[new]


def __getattr__(name: str) -> type:
    return renamed(__name__, name)
