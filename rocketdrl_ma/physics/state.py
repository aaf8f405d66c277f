"""Public value types of the physics API: controls in, car and ball states out (Rocket League units)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from .constants import BALL_REST_Z, BOOST_MAX, BOOST_SPAWN_AMOUNT, CAR_SPAWN_REST_Z


def _vec3(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,):
        raise ValueError(f"{name}: expected 3 numbers, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: must be finite, got {arr.tolist()}")
    return arr.copy()


def _axis(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or not -1.0 <= v <= 1.0:
        raise ValueError(f"{name}: must be a finite number in [-1, 1], got {value!r}")
    return v


def yaw_rot_mat(yaw_rad: float) -> np.ndarray:
    """Rotation matrix (columns forward, right, up) of a level car facing ``yaw_rad``."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.column_stack(([c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]))


@dataclass
class CarControls:
    """One tick's inputs. Axes in [-1, 1]; buttons are booleans. Out-of-range input is an error, never clamped."""
    throttle: float = 0.0
    steer: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0
    roll: float = 0.0
    jump: bool = False
    boost: bool = False
    handbrake: bool = False

    def __post_init__(self) -> None:
        # Field by field rather than a loop over names: controls are made for every agent and decision.
        self.throttle = _axis("throttle", self.throttle)
        self.steer = _axis("steer", self.steer)
        self.pitch = _axis("pitch", self.pitch)
        self.yaw = _axis("yaw", self.yaw)
        self.roll = _axis("roll", self.roll)
        self.jump, self.boost, self.handbrake = bool(self.jump), bool(self.boost), bool(self.handbrake)

    def as_array(self) -> np.ndarray:
        return np.array([self.throttle, self.steer, self.pitch, self.yaw, self.roll,
                         float(self.jump), float(self.boost), float(self.handbrake)])


def _trusted(cls, values: dict):
    """An instance from values the physics produced (already valid): skips ``__post_init__``'s checks, which
    cost more than the rest of a state read. Arrays must be fresh copies."""
    obj = cls.__new__(cls)
    obj.__dict__.update(values)
    return obj


@dataclass
class BallState:
    pos: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, BALL_REST_Z]))
    vel: np.ndarray = field(default_factory=lambda: np.zeros(3))
    ang_vel: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        for f in fields(self):
            setattr(self, f.name, _vec3(f.name, getattr(self, f.name)))


@dataclass
class CarState:
    """Car state in uu; ``rot_mat`` columns are forward, right, up (forward x right = up)."""
    pos: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, CAR_SPAWN_REST_Z]))
    vel: np.ndarray = field(default_factory=lambda: np.zeros(3))
    ang_vel: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rot_mat: np.ndarray = field(default_factory=lambda: yaw_rot_mat(0.0))
    boost: float = BOOST_SPAWN_AMOUNT
    on_ground: bool = False
    wheels_in_contact: tuple[bool, bool, bool, bool] = (False, False, False, False)
    has_jumped: bool = False
    has_double_jumped: bool = False
    has_flipped: bool = False
    is_jumping: bool = False
    is_flipping: bool = False
    is_supersonic: bool = False
    is_demoed: bool = False
    handbrake_value: float = 0.0
    # Timers a faithful save/restore needs (s); zero for a fresh car.
    jump_time: float = 0.0
    flip_time: float = 0.0
    air_time_since_jump: float = 0.0
    supersonic_time: float = 0.0
    demo_respawn_timer: float = 0.0

    def __post_init__(self) -> None:
        for name in ("pos", "vel", "ang_vel"):
            setattr(self, name, _vec3(name, getattr(self, name)))
        rot = np.asarray(self.rot_mat, dtype=np.float64)
        if rot.shape != (3, 3) or not np.all(np.isfinite(rot)):
            raise ValueError(f"rot_mat: expected a finite 3x3 matrix, got shape {rot.shape}")
        if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-4) or np.linalg.det(rot) < 0.0:
            raise ValueError("rot_mat: must be a rotation matrix (orthonormal columns forward, right, up, det +1)")
        self.rot_mat = rot.copy()
        if not math.isfinite(self.boost) or not 0.0 <= self.boost <= BOOST_MAX:
            raise ValueError(f"boost: must be in [0, {BOOST_MAX:g}], got {self.boost!r}")
        self.boost = float(self.boost)
        wheels = tuple(bool(w) for w in self.wheels_in_contact)
        if len(wheels) != 4:
            raise ValueError(f"wheels_in_contact: expected 4 booleans, got {len(wheels)}")
        self.wheels_in_contact = wheels
        for name in ("handbrake_value", "jump_time", "flip_time", "air_time_since_jump", "supersonic_time",
                     "demo_respawn_timer"):
            v = float(getattr(self, name))
            if not math.isfinite(v) or v < 0.0:
                raise ValueError(f"{name}: must be a finite number >= 0, got {v!r}")
            setattr(self, name, v)
        if self.handbrake_value > 1.0:
            raise ValueError(f"handbrake_value: must be in [0, 1], got {self.handbrake_value!r}")
