"""Game-mode switches and numbers of an arena, modelled on RocketSim's ``MutatorConfig``.

``MutatorConfig()`` is a standard soccar game. A game mode changes what it needs and hands the result to
``Arena.set_mutator_config`` (or ``ArenaBatch.set_mutator_config`` for several arenas): demos off, boost pads off,
low gravity, a faster ball, unlimited flips. The kernels read one float row per arena (``as_row``), so every
arena of a batch can play its own variant; only gravity is shared, PyBullet having one gravity per world.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import StrEnum

import numpy as np

from . import constants as C


class DemoMode(StrEnum):
    """RocketSim's ``DemoMode``: when a car hitting another with its bumper demolishes it."""
    NORMAL = "normal"          # a supersonic attacker demolishes an opponent (teammates too with ``team_demos``)
    ON_CONTACT = "on_contact"  # any bumper hit that would bump demolishes instead
    DISABLED = "disabled"      # never; supersonic hits bump like any other


@dataclass(frozen=True)
class MutatorConfig:
    """An arena's game-mode settings (Rocket League units: uu, uu/s, uu/s², s). Invalid values raise
    ``ValueError`` naming the field; nothing is clamped."""
    gravity_z_uu_s2: float = C.GRAVITY_Z
    demo_mode: DemoMode = DemoMode.NORMAL
    team_demos: bool = False
    boost_pads: bool = True                      # False: pads neither refill boost nor count down
    boost_used_per_second: float = C.BOOST_USED_PER_SECOND
    boost_accel_ground_uu_s2: float = C.BOOST_ACCEL_GROUND
    boost_accel_air_uu_s2: float = C.BOOST_ACCEL_AIR
    car_spawn_boost: float = C.BOOST_SPAWN_AMOUNT
    jump_accel_uu_s2: float = C.JUMP_ACCEL
    jump_immediate_vel_uu_s: float = C.JUMP_IMMEDIATE_VEL  # the first jump's impulse (a double jump keeps the game's)
    dodge_deadzone: float = C.DODGE_DEADZONE     # RocketSim has it per car; here per arena, as RLGym's GameConfig
    unlimited_flips: bool = False
    unlimited_double_jumps: bool = False
    respawn_delay_s: float = C.DEMO_RESPAWN_TIME
    bump_cooldown_s: float = C.BUMP_COOLDOWN_TIME
    bump_force_scale: float = 1.0                # scales the bump's upward part, as RocketSim's does
    boost_pad_cooldown_big_s: float = C.BOOST_PAD_BIG_COOLDOWN
    boost_pad_cooldown_small_s: float = C.BOOST_PAD_SMALL_COOLDOWN
    ball_max_speed_uu_s: float = C.BALL_MAX_SPEED
    ball_drag: float = C.BALL_DRAG               # fraction of speed lost per second (Bullet's linear damping)
    ball_hit_extra_force_scale: float = 1.0      # scales Rocket League's extra push on a car touch
    goal_threshold_y: float = C.GOAL_SCORE_THRESHOLD_Y  # plus the ball radius: where a goal counts

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.type == "DemoMode":
                try:
                    object.__setattr__(self, f.name, DemoMode(value))
                except ValueError:
                    raise ValueError(f"{f.name}: must be one of {[m.value for m in DemoMode]}, "
                                     f"got {value!r}") from None
            elif f.type == "bool":
                if not isinstance(value, (bool, np.bool_)):
                    raise ValueError(f"{f.name}: must be true or false, got {value!r}")
                object.__setattr__(self, f.name, bool(value))
            else:
                if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)) \
                        or not math.isfinite(value):
                    raise ValueError(f"{f.name}: must be a finite number, got {value!r}")
                object.__setattr__(self, f.name, float(value))
        for name in ("boost_used_per_second", "boost_accel_ground_uu_s2", "boost_accel_air_uu_s2", "jump_accel_uu_s2",
                     "jump_immediate_vel_uu_s", "respawn_delay_s", "bump_cooldown_s", "bump_force_scale",
                     "boost_pad_cooldown_big_s", "boost_pad_cooldown_small_s", "ball_hit_extra_force_scale",
                     "dodge_deadzone", "ball_drag"):
            if getattr(self, name) < 0.0:
                raise ValueError(f"{name}: must be >= 0, got {getattr(self, name)!r}")
        if not 0.0 <= self.car_spawn_boost <= C.BOOST_MAX:
            raise ValueError(f"car_spawn_boost: must be in [0, {C.BOOST_MAX:g}], got {self.car_spawn_boost!r}")
        if self.ball_max_speed_uu_s <= 0.0:
            raise ValueError(f"ball_max_speed_uu_s: must be > 0, got {self.ball_max_speed_uu_s!r}")
        if self.ball_drag >= 1.0:
            raise ValueError(f"ball_drag: must be in [0, 1), got {self.ball_drag!r}")
        if self.goal_threshold_y <= 0.0:
            raise ValueError(f"goal_threshold_y: must be > 0, got {self.goal_threshold_y!r}")

    def as_row(self) -> np.ndarray:
        """The numbers the compiled kernels read, at the ``MUT_*`` columns."""
        row = np.zeros(MUT_SIZE)
        row[MUT_BOOST_PADS] = self.boost_pads
        row[MUT_BOOST_USED_PER_SECOND] = self.boost_used_per_second
        row[MUT_BOOST_ACCEL_GROUND] = self.boost_accel_ground_uu_s2
        row[MUT_BOOST_ACCEL_AIR] = self.boost_accel_air_uu_s2
        row[MUT_JUMP_ACCEL] = self.jump_accel_uu_s2
        row[MUT_JUMP_IMMEDIATE_VEL] = self.jump_immediate_vel_uu_s
        row[MUT_DODGE_DEADZONE] = self.dodge_deadzone
        row[MUT_UNLIMITED_FLIPS] = self.unlimited_flips
        row[MUT_UNLIMITED_DOUBLE_JUMPS] = self.unlimited_double_jumps
        row[MUT_PAD_COOLDOWN_BIG] = self.boost_pad_cooldown_big_s
        row[MUT_PAD_COOLDOWN_SMALL] = self.boost_pad_cooldown_small_s
        row[MUT_BALL_MAX_SPEED] = self.ball_max_speed_uu_s
        row[MUT_BALL_DRAG] = self.ball_drag
        row[MUT_BALL_HIT_EXTRA_SCALE] = self.ball_hit_extra_force_scale
        return row


# Columns of ``MutatorConfig.as_row`` (one row per arena in the kernels).
MUT_BOOST_PADS = 0
MUT_BOOST_USED_PER_SECOND = 1
MUT_BOOST_ACCEL_GROUND = 2
MUT_BOOST_ACCEL_AIR = 3
MUT_JUMP_ACCEL = 4
MUT_JUMP_IMMEDIATE_VEL = 5
MUT_DODGE_DEADZONE = 6
MUT_UNLIMITED_FLIPS = 7
MUT_UNLIMITED_DOUBLE_JUMPS = 8
MUT_PAD_COOLDOWN_BIG = 9
MUT_PAD_COOLDOWN_SMALL = 10
MUT_BALL_MAX_SPEED = 11
MUT_BALL_DRAG = 12
MUT_BALL_HIT_EXTRA_SCALE = 13
MUT_SIZE = 14
