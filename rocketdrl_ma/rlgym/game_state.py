"""RLGym's ``Car`` / ``PhysicsObject`` to and from our physics' states, field for field as RocketSimEngine maps
RocketSim's (float32 arrays, rotation matrices with the columns forward, right, up)."""
from __future__ import annotations

from typing import Any, Hashable

import numpy as np
from rlgym.rocket_league.api import Car, PhysicsObject

from rocketdrl_ma.physics import BallState, CarExtraState, CarState
from rocketdrl_ma.physics import Car as PhysicsCar

# RLGym's hitbox ids (rlgym.rocket_league.common_values OCTANE..MERC) to our car presets.
HITBOX_PRESETS: tuple[str, ...] = ("octane", "dominus", "plank", "breakout", "hybrid", "merc")


def _required(obj: Any, name: str, where: str) -> Any:
    value = getattr(obj, name)
    if value is None:
        raise ValueError(f"{where}.{name}: not set (the state mutators must set every field the engine reads)")
    return value


def preset_of(car: Car, agent: Hashable) -> str:
    hitbox = _required(car, "hitbox_type", f"cars[{agent!r}]")
    if isinstance(hitbox, bool) or not isinstance(hitbox, (int, np.integer)) or not 0 <= hitbox < len(HITBOX_PRESETS):
        raise ValueError(f"cars[{agent!r}].hitbox_type: must be one of 0..{len(HITBOX_PRESETS) - 1} "
                         f"({', '.join(HITBOX_PRESETS)}), got {hitbox!r}")
    return HITBOX_PRESETS[int(hitbox)]


def team_of(car: Car, agent: Hashable) -> int:
    team = _required(car, "team_num", f"cars[{agent!r}]")
    if team not in (0, 1):
        raise ValueError(f"cars[{agent!r}].team_num: must be 0 (blue) or 1 (orange), got {team!r}")
    return int(team)


def ball_state(ball: PhysicsObject) -> BallState:
    return BallState(pos=_required(ball, "position", "ball"), vel=_required(ball, "linear_velocity", "ball"),
                     ang_vel=_required(ball, "angular_velocity", "ball"))


def car_state(car: Car, agent: Hashable) -> CarState:
    where = f"cars[{agent!r}]"
    physics = _required(car, "physics", where)
    try:
        rot_mat = physics.rotation_mtx
    except ValueError:
        raise ValueError(f"{where}.physics: no orientation set (rotation_mtx, quaternion or euler_angles)") from None
    flags = {name: bool(_required(car, name, where))
             for name in ("has_jumped", "has_double_jumped", "has_flipped", "is_jumping")}
    times = {name: float(_required(car, name, where))
             for name in ("jump_time", "flip_time", "air_time_since_jump", "supersonic_time", "demo_respawn_timer")}
    wheels = tuple(bool(w) for w in _required(car, "wheels_with_contact", where))
    return CarState(
        pos=_required(physics, "position", f"{where}.physics"),
        vel=_required(physics, "linear_velocity", f"{where}.physics"),
        ang_vel=_required(physics, "angular_velocity", f"{where}.physics"),
        rot_mat=rot_mat, boost=float(_required(car, "boost_amount", where)),
        on_ground=sum(wheels) >= 3, wheels_in_contact=wheels,  # RLGym's Car.on_ground
        is_flipping=car.is_flipping, is_supersonic=times["supersonic_time"] > 0.0,
        is_demoed=times["demo_respawn_timer"] > 0.0, handbrake_value=float(_required(car, "handbrake", where)),
        **flags, **times)


def car_extra_state(car: Car, agent: Hashable, victim_car_id: int | None) -> CarExtraState:
    """RocketSimEngine sets the bump victim but not its cooldown, so a freshly set car reports no bump victim."""
    where = f"cars[{agent!r}]"
    return CarExtraState(
        holding_jump=bool(_required(car, "is_holding_jump", where)),
        boost_active_time_s=float(_required(car, "boost_active_time", where)),
        flip_torque=tuple(float(v) for v in _required(car, "flip_torque", where)),
        is_auto_flipping=bool(_required(car, "is_autoflipping", where)),
        auto_flip_timer_s=float(_required(car, "autoflip_timer", where)),
        auto_flip_direction=float(_required(car, "autoflip_direction", where)),
        car_contact_id=victim_car_id)


def physics_object(pos: np.ndarray, vel: np.ndarray, ang_vel: np.ndarray, rot_mat: np.ndarray) -> PhysicsObject:
    obj = PhysicsObject()
    obj.position = pos.astype(np.float32)
    obj.linear_velocity = vel.astype(np.float32)
    obj.angular_velocity = ang_vel.astype(np.float32)
    obj.rotation_mtx = np.ascontiguousarray(rot_mat, dtype=np.float32)
    return obj


def rlgym_car(car: PhysicsCar, hitbox_type: int, ball_touches: int, agent_of_car: dict[int, Hashable]) -> Car:
    state, extra = car.get_state(), car.get_extra_state()
    out = Car()
    out.team_num = car.team
    out.hitbox_type = hitbox_type
    out.ball_touches = ball_touches
    out.bump_victim_id = (agent_of_car.get(extra.car_contact_id)
                          if extra.car_contact_id is not None and extra.car_contact_cooldown_s > 0.0 else None)
    out.physics = physics_object(state.pos, state.vel, state.ang_vel, state.rot_mat)
    out.demo_respawn_timer = state.demo_respawn_timer
    out.wheels_with_contact = state.wheels_in_contact
    out.supersonic_time = state.supersonic_time
    out.boost_amount = state.boost
    out.boost_active_time = extra.boost_active_time_s
    out.handbrake = state.handbrake_value
    out.has_jumped = state.has_jumped
    out.is_holding_jump = extra.holding_jump
    out.is_jumping = state.is_jumping
    out.jump_time = state.jump_time
    out.has_flipped = state.has_flipped
    out.has_double_jumped = state.has_double_jumped
    out.air_time_since_jump = state.air_time_since_jump
    out.flip_time = state.flip_time
    out.flip_torque = np.array(extra.flip_torque, dtype=np.float32)
    out.is_autoflipping = extra.is_auto_flipping
    out.autoflip_timer = extra.auto_flip_timer_s
    out.autoflip_direction = extra.auto_flip_direction
    return out
