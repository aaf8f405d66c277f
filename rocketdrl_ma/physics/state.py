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


@dataclass(frozen=True)
class CarExtraState:
    """The rest of what RocketSim's ``CarState`` carries: the car model's memory of earlier ticks and its bump
    cooldown, which ``CarState`` (our wire and replay format) leaves out. ``Car.set_state`` clears all of it, so a
    state set on a used car plays on as on a new one; ``Car.set_extra_state`` afterwards restores it exactly."""
    holding_jump: bool = False            # last tick's jump button: a held jump is not a new press
    boost_active_time_s: float = 0.0      # how long the current boost has lasted (boosting lasts at least 0.1 s)
    flip_torque: tuple[float, float, float] = (0.0, 0.0, 0.0)  # RocketSim's flip_rel_torque: (roll, pitch, 0)
    is_auto_flipping: bool = False
    auto_flip_timer_s: float = 0.0
    auto_flip_direction: float = 0.0      # +1 or -1: which way the auto-flip rolls
    car_contact_id: int | None = None     # the car this one last bumped or demolished (RocketSim's car_contact_id)
    car_contact_cooldown_s: float = 0.0   # seconds until it may bump that car again

    def __post_init__(self) -> None:
        for name in ("boost_active_time_s", "auto_flip_timer_s", "car_contact_cooldown_s"):
            v = float(getattr(self, name))
            if not math.isfinite(v) or v < 0.0:
                raise ValueError(f"{name}: must be a finite number >= 0, got {getattr(self, name)!r}")
            object.__setattr__(self, name, v)
        torque = tuple(float(v) for v in self.flip_torque)
        if len(torque) != 3 or not all(math.isfinite(v) for v in torque):
            raise ValueError(f"flip_torque: expected 3 finite numbers, got {self.flip_torque!r}")
        object.__setattr__(self, "flip_torque", torque)
        if self.auto_flip_direction not in (-1.0, 0.0, 1.0):
            raise ValueError(f"auto_flip_direction: must be -1, 0 or 1, got {self.auto_flip_direction!r}")
        object.__setattr__(self, "auto_flip_direction", float(self.auto_flip_direction))
        for name in ("holding_jump", "is_auto_flipping"):
            object.__setattr__(self, name, bool(getattr(self, name)))


@dataclass(frozen=True)
class BallHitInfo:
    """A car's last touch of the ball (RocketSim's ``BallHitInfo``); ``Car.get_ball_hit_info()`` is None before the
    first. Positions and velocities in uu and uu/s, arena frame."""
    tick: int                              # the tick of the last contact
    extra_impulse_tick: int                # the last tick Rocket League's extra push was applied
    relative_pos_on_ball: tuple[float, float, float]  # the contact point relative to the ball's centre
    ball_pos: tuple[float, float, float]   # the ball's centre when it was touched
    extra_hit_vel: tuple[float, float, float]  # the velocity the extra push added (zero on ticks without one)


@dataclass(frozen=True)
class BoostPadState:
    """A pad's state: seconds until it is active again (0: active). RocketSim's ``BoostPadState.cooldown``."""
    cooldown_s: float = 0.0

    def __post_init__(self) -> None:
        v = float(self.cooldown_s)
        if not math.isfinite(v) or v < 0.0:
            raise ValueError(f"cooldown_s: must be a finite number >= 0, got {self.cooldown_s!r}")
        object.__setattr__(self, "cooldown_s", v)

    @property
    def is_active(self) -> bool:
        return self.cooldown_s == 0.0
