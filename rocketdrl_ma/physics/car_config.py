"""Hitbox presets: body box, wheel placement and suspension rest lengths per car family (uu)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .constants import CAR_MASS, SUSPENSION_MAX_TRAVEL, SUSPENSION_SUBTRACTION, UU_PER_M


@dataclass(frozen=True)
class WheelPair:
    radius: float
    rest_length_config: float  # the game's value; the vehicle uses it minus the max travel
    connection: tuple[float, float, float]  # right wheel; the left one mirrors y


@dataclass(frozen=True)
class CarConfig:
    name: str
    hitbox_size: tuple[float, float, float]  # full length, width, height
    hitbox_offset: tuple[float, float, float]  # box centre relative to the centre of mass
    front: WheelPair
    back: WheelPair
    three_wheel: bool = False

    @property
    def inertia_diag(self) -> np.ndarray:
        """Box inertia in kg*m^2 about the box centre; RocketSim adds no parallel-axis term for the offset."""
        lx, ly, lz = (v / UU_PER_M for v in self.hitbox_size)
        return CAR_MASS / 12.0 * np.array([ly**2 + lz**2, lx**2 + lz**2, lx**2 + ly**2])

    def wheel_table(self) -> dict[str, np.ndarray]:
        """Per-wheel arrays in the order front-left, front-right, back-left, back-right."""
        pairs = (self.front, self.front, self.back, self.back)
        y_sign = (-1.0, 1.0, -1.0, 1.0)  # local +y is the car's right
        conn = np.array([[p.connection[0], s * p.connection[1], p.connection[2]] for p, s in zip(pairs, y_sign)])
        rest = np.array([p.rest_length_config - SUSPENSION_MAX_TRAVEL for p in pairs])
        radius = np.array([p.radius for p in pairs])
        return {
            "connection": conn,
            "rest_length": rest,
            "radius": radius,
            "ray_length": rest + SUSPENSION_MAX_TRAVEL + radius - SUSPENSION_SUBTRACTION,
            "is_front": np.array([True, True, False, False]),
        }


def _cfg(name, size, offset, front, back, three_wheel=False) -> CarConfig:
    return CarConfig(name, size, offset, WheelPair(*front), WheelPair(*back), three_wheel)


PRESETS: dict[str, CarConfig] = {c.name: c for c in (
    _cfg("octane", (120.507, 86.6994, 38.6591), (13.8757, 0.0, 20.755),
         (12.50, 38.755, (51.25, 25.90, 20.755)), (15.00, 37.055, (-33.75, 29.50, 20.755))),
    _cfg("dominus", (130.427, 85.7799, 33.8), (9.0, 0.0, 15.75),
         (12.00, 33.95, (50.30, 31.10, 15.75)), (13.50, 33.85, (-34.75, 33.00, 15.75))),
    _cfg("plank", (131.32, 87.1704, 31.8944), (9.00857, 0.0, 12.0942),
         (12.50, 31.9242, (49.97, 27.80, 12.0942)), (17.00, 27.9242, (-35.43, 20.28, 12.0942))),
    _cfg("breakout", (133.992, 83.021, 32.8), (12.5, 0.0, 11.75),
         (13.50, 29.7, (51.50, 26.67, 11.75)), (15.00, 29.666, (-35.75, 35.00, 11.75))),
    _cfg("hybrid", (129.519, 84.6879, 36.6591), (13.8757, 0.0, 20.755),
         (12.50, 38.755, (51.25, 25.90, 20.755)), (15.00, 37.055, (-34.00, 29.50, 20.755))),
    _cfg("merc", (123.22, 79.2103, 44.1591), (11.3757, 0.0, 21.505),
         (15.00, 39.505, (51.25, 25.90, 21.505)), (15.00, 39.105, (-33.75, 29.50, 21.505))),
    _cfg("psyclops", (120.641, 86.8334, 38.7931), (13.8757, 0.0, 15.0),
         (12.50, 33.0, (51.25, 5.00, 15.0)), (15.00, 31.3, (-33.75, 29.50, 15.0)), three_wheel=True),
)}


def get_preset(name: str) -> CarConfig:
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"preset: unknown car preset {name!r}; allowed: {sorted(PRESETS)}") from None
