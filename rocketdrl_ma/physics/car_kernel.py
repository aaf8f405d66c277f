"""The per-tick car model, compiled with numba over every car of every arena at once.

PyBullet integrates rigid bodies and resolves body contacts; everything Rocket League adds on top
(raycast suspension, tyres, engine and brakes, boost, jumps, flips, air control, sticky force) is a
velocity change computed here before each ``stepSimulation``. All quantities are in uu, s, rad.

Car state that is not a rigid-body quantity lives in one float matrix ``cs`` (cars x CS_SIZE) whose
columns are named below, so the whole model is one compiled loop with no Python objects per car.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import literally, njit

from . import constants as C
from .arena_shape import CLASSIC, GAME, shape_raycast
from .mutators import (MUT_BOOST_ACCEL_AIR, MUT_BOOST_ACCEL_GROUND, MUT_BOOST_PADS, MUT_BOOST_USED_PER_SECOND,
                       MUT_DODGE_DEADZONE, MUT_JUMP_ACCEL, MUT_JUMP_IMMEDIATE_VEL, MUT_PAD_COOLDOWN_BIG,
                       MUT_PAD_COOLDOWN_SMALL, MUT_UNLIMITED_DOUBLE_JUMPS, MUT_UNLIMITED_FLIPS)
from .vec import mat_t_vec, mat_vec, vcross, vcross_into, vdot

# ---- columns of the car-state matrix
CS_BOOST = 0
CS_HANDBRAKE = 1
CS_IS_JUMPING = 2
CS_HAS_JUMPED = 3
CS_JUMP_TIME = 4
CS_HAS_DOUBLE_JUMPED = 5
CS_HAS_FLIPPED = 6
CS_IS_FLIPPING = 7
CS_FLIP_TIME = 8
CS_FLIP_TORQUE_X = 9
CS_FLIP_TORQUE_Y = 10
CS_AIR_TIME_SINCE_JUMP = 11
CS_BOOSTING_TIME = 12
CS_IS_BOOSTING = 13
CS_LAST_JUMP = 14
CS_ON_GROUND = 15
CS_NUM_WHEELS = 16
CS_WHEEL_0 = 17  # four columns: 1.0 where that wheel's ray hits
CS_IS_SUPERSONIC = 21
CS_SUPERSONIC_TIME = 22
CS_IS_DEMOED = 23
CS_DEMO_TIMER = 24
CS_WORLD_CONTACT = 25  # some wheel touches the arena
CS_STEER_ANGLE = 26  # the wheel set-up of the last tick: Bullet's vehicle applies it one tick late
CS_ENGINE = 27
CS_BRAKE = 28
CS_LAT_FRICTION_0 = 29  # four columns
CS_LONG_FRICTION_0 = 33  # four columns
CS_IS_AUTOFLIPPING = 37
CS_AUTOFLIP_TIMER = 38
CS_AUTOFLIP_SCALE = 39
CS_BODY_CONTACT = 40  # the hitbox touched the arena last tick
CS_BODY_NORMAL_X = 41  # three columns: that contact's normal
CS_PUSHBACK_0 = 44  # four columns: each wheel's hard-stop push-back, kept while the wheel stays on the arena
CS_SIZE = 48
# Memory of earlier ticks that CarState does not carry (the last jump input for edge detection, boost's minimum
# duration, the wheel set-up Bullet applies one tick late, autoflip, body contact): set_state clears it, so a
# state set on a used car plays on exactly as on a new car (RocketSim's CarState carries last_controls likewise).
CS_TICK_MEMORY = (CS_BOOSTING_TIME, CS_IS_BOOSTING, CS_LAST_JUMP, CS_STEER_ANGLE, CS_ENGINE, CS_BRAKE,
                  *range(CS_LAT_FRICTION_0, CS_LAT_FRICTION_0 + 4), *range(CS_LONG_FRICTION_0, CS_LONG_FRICTION_0 + 4),
                  CS_IS_AUTOFLIPPING, CS_AUTOFLIP_TIMER, CS_AUTOFLIP_SCALE, CS_BODY_CONTACT,
                  *range(CS_BODY_NORMAL_X, CS_BODY_NORMAL_X + 3), *range(CS_PUSHBACK_0, CS_PUSHBACK_0 + 4))

_THROTTLE_CURVE = np.array(C.THROTTLE_TORQUE_CURVE)
_STEER_CURVE = np.array(C.STEER_ANGLE_CURVE)
_STEER_CURVE_3W = np.array(C.STEER_ANGLE_CURVE_THREE_WHEEL)
_POWERSLIDE_CURVE = np.array(C.POWERSLIDE_STEER_ANGLE_CURVE)
_LAT_CURVE = np.array(C.LAT_FRICTION_CURVE)
_LAT_CURVE_3W = np.array(C.LAT_FRICTION_CURVE_THREE_WHEEL)
_HB_LONG_CURVE = np.array(C.HANDBRAKE_LONG_FRICTION_CURVE)
_NON_STICKY_CURVE = np.array(C.NON_STICKY_FRICTION_CURVE)
_AIR_TORQUE = np.array(C.CAR_AIR_CONTROL_TORQUE) * C.CAR_TORQUE_SCALE
_AIR_DAMPING = np.array(C.CAR_AIR_CONTROL_DAMPING) * C.CAR_TORQUE_SCALE
_GRAVITY = -C.GRAVITY_Z


def _f32(x: float) -> float:
    return float(np.float32(x))


# RocketSim keeps its car timers in float32, as sums of float32(dt), and compares them with float32 limits: a limit
# that is a whole number of ticks then falls on the side float32 rounding puts it (after 78 ticks a flip's time is
# 0.64999974 < 0.65, so the flip torque acts for a 79th tick; 24 ticks of jump make 0.20000006 >= 0.2). The timers
# below follow that arithmetic (``_tick``) and these limits.
_JUMP_MIN_TIME = _f32(C.JUMP_MIN_TIME)
_JUMP_MAX_TIME = _f32(C.JUMP_MAX_TIME)
_JUMP_RESET_TIME = _f32(np.float32(C.JUMP_MIN_TIME) + np.float32(C.JUMP_RESET_MIN_TIME))
_DOUBLEJUMP_MAX_DELAY = _f32(C.DOUBLEJUMP_MAX_DELAY)
_FLIP_TORQUE_TIME = _f32(C.FLIP_TORQUE_TIME)
_FLIP_PITCHLOCK_TIME = _f32(np.float32(C.FLIP_TORQUE_TIME) + np.float32(C.FLIP_PITCHLOCK_EXTRA_TIME))
_FLIP_Z_DAMP_START = _f32(C.FLIP_Z_DAMP_START)
_FLIP_Z_DAMP_END = _f32(C.FLIP_Z_DAMP_END)
_SUPERSONIC_MAINTAIN_MAX_TIME = _f32(C.SUPERSONIC_MAINTAIN_MAX_TIME)
_BOOST_MIN_TIME = _f32(C.BOOST_MIN_TIME)


@njit(cache=True, nogil=True, inline="always")
def _tick(timer, dt):
    """``timer + dt`` as RocketSim's float32 timers add it (both operands rounded to float32 first)."""
    return float(np.float32(np.float32(timer) + np.float32(dt)))


@njit(cache=True, nogil=True)
def interp(curve, x):
    """Piecewise-linear curve lookup, clamped at both ends (RocketSim's LinearPieceCurve)."""
    if x <= curve[0, 0]:
        return curve[0, 1]
    for k in range(1, curve.shape[0]):
        if x < curve[k, 0]:
            x0, y0 = curve[k - 1, 0], curve[k - 1, 1]
            x1, y1 = curve[k, 0], curve[k, 1]
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0)
    return curve[curve.shape[0] - 1, 1]


# The helpers below run several times per car and tick: they work on scalars (the arithmetic of
# ``mat_t_vec(R, vcross(...))`` and friends term by term) because a small array per step cost more than the maths.
@njit(cache=True, nogil=True)
def _inv_mass_along(R, inv_inertia, rel, direction):
    """1/m_eff of a unit impulse along ``direction`` applied at offset ``rel`` from the centre of mass."""
    x = rel[1] * direction[2] - rel[2] * direction[1]
    y = rel[2] * direction[0] - rel[0] * direction[2]
    z = rel[0] * direction[1] - rel[1] * direction[0]
    c0 = R[0, 0] * x + R[1, 0] * y + R[2, 0] * z
    c1 = R[0, 1] * x + R[1, 1] * y + R[2, 1] * z
    c2 = R[0, 2] * x + R[1, 2] * y + R[2, 2] * z
    return 1.0 / C.CAR_MASS + inv_inertia[0] * c0 ** 2 + inv_inertia[1] * c1 ** 2 + inv_inertia[2] * c2 ** 2


@njit(cache=True, nogil=True)
def _apply_impulse(R, inv_inertia, v, w, rel, impulse):
    for j in range(3):
        v[j] += impulse[j] / C.CAR_MASS
    x = rel[1] * impulse[2] - rel[2] * impulse[1]
    y = rel[2] * impulse[0] - rel[0] * impulse[2]
    z = rel[0] * impulse[1] - rel[1] * impulse[0]
    s0 = inv_inertia[0] * (R[0, 0] * x + R[1, 0] * y + R[2, 0] * z)
    s1 = inv_inertia[1] * (R[0, 1] * x + R[1, 1] * y + R[2, 1] * z)
    s2 = inv_inertia[2] * (R[0, 2] * x + R[1, 2] * y + R[2, 2] * z)
    for j in range(3):
        w[j] += R[j, 0] * s0 + R[j, 1] * s1 + R[j, 2] * s2


@njit(cache=True, nogil=True)
def _ray_sphere(origin, direction, center, radius):
    """Distance along a unit ray to a sphere, or -1 if missed (origins inside the sphere miss)."""
    ox, oy, oz = origin[0] - center[0], origin[1] - center[1], origin[2] - center[2]
    b = ox * direction[0] + oy * direction[1] + oz * direction[2]
    c = (ox * ox + oy * oy + oz * oz) - radius * radius
    if c < 0.0:
        return -1.0
    disc = b * b - c
    if disc < 0.0:
        return -1.0
    t = -b - np.sqrt(disc)
    return t if t >= 0.0 else -1.0


# ================================================================= one tick of the car model, stage by stage
# The stages are inlined into ``car_pre_tick``'s loop (``inline="always"``): as separate calls they cost a third
# more per car.
class WheelContacts(NamedTuple):
    """Where each of a car's 4 wheel rays hit this tick (scratch reused by every car)."""
    hit: np.ndarray        # (4,) bool: the ray hit the arena or the ball
    hit_world: np.ndarray  # (4,) bool: it hit the arena (sticky force)
    dist: np.ndarray       # (4,) uu along the ray
    normal: np.ndarray     # (4, 3) unit surface normals
    hard_point: np.ndarray  # (4, 3) the wheels' hard points (ray origins), world frame


class Scratch(NamedTuple):
    """Vectors the stages work in: a lever arm, a contact-point velocity, a cross product, an axle, a direction."""
    rel: np.ndarray
    v_cp: np.ndarray
    cross: np.ndarray
    axle: np.ndarray
    f_dir: np.ndarray


class CarFrame(NamedTuple):
    fwd: np.ndarray
    right: np.ndarray
    up: np.ndarray
    down: np.ndarray


class CarArrays(NamedTuple):
    """Every car's state for the car model, by batch row (uu, uu/s, rad/s)."""
    pos: np.ndarray        # (cars, 3)
    rot: np.ndarray        # (cars, 3, 3), columns forward, right, up
    vel: np.ndarray        # (cars, 3), written in place
    ang_vel: np.ndarray    # (cars, 3), written in place
    controls: np.ndarray   # (cars, 8): throttle, steer, pitch, yaw, roll, jump, boost, handbrake
    arena: np.ndarray      # (cars,) int
    active: np.ndarray     # (cars,) bool


class CarModel(NamedTuple):
    """Every car's build (``CarConfig``), by batch row."""
    wheel_conn: np.ndarray      # (cars, 4, 3) the wheels' connection points, car frame (uu)
    wheel_rest: np.ndarray      # (cars, 4) suspension rest lengths (uu)
    wheel_radius: np.ndarray    # (cars, 4) uu
    wheel_ray_len: np.ndarray   # (cars, 4) uu
    wheel_is_front: np.ndarray  # (cars, 4) bool
    inv_inertia: np.ndarray     # (cars, 3) 1 / the inertia diagonal
    three_wheel: np.ndarray     # (cars,) bool


@njit(cache=True, nogil=True)
def car_pre_tick(shape, cars, model, ball_pos, ball_radius, cs, mut, dt):
    """Advance every active, non-demoed car's model by one tick in an arena of ``shape`` (``arena_shape``'s integer,
    compiled per value: call ``car_pre_tick_classic`` or ``car_pre_tick_game``): writes the velocities of ``cars``
    (``CarArrays``; ``model``: their ``CarModel``) in place. ``cs`` is the cars' state rows (``CS_*``), ``mut``
    holds each arena's ``MutatorConfig.as_row()``.

    The stages follow RocketSim's ``Car::_PreTickUpdate``: the vehicle's first half (wheel rays, then the
    suspension and tyre impulses from the state at the start of the tick with last tick's steering and
    friction factors), ``_UpdateWheels``, ``_UpdateAirTorque``, ``_UpdateJump``, ``_UpdateAutoFlip``,
    ``_UpdateDoubleJumpOrFlip``, ``_UpdateAutoRoll``, the vehicle's second half (the wheel impulses applied),
    ``_UpdateBoost``.

    Returns how many cars' velocities must not be written back to PyBullet (inactive or demolished ones).
    """
    literally(shape)
    pos, rot, vel, ang_vel, controls, car_arena, active = cars
    wheel_conn, wheel_rest, wheel_radius, wheel_ray_len, wheel_is_front, inv_inertia, three_wheel = model
    # Scratch reused by every car: fresh small arrays per car and wheel were most of this kernel's time.
    frame = CarFrame(np.empty(3), np.empty(3), np.empty(3), np.empty(3))
    wheels = WheelContacts(np.zeros(4, dtype=np.bool_), np.zeros(4, dtype=np.bool_), np.zeros(4), np.zeros((4, 3)),
                           np.zeros((4, 3)))
    susp_impulse, fric_impulse, fric_rel = np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3))
    v0, w0, v, w = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    force_dv = np.empty(3)  # the part of this tick's velocity change so far that RocketSim applies as forces
    scratch = Scratch(np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3))
    n_unwritable = 0
    for i in range(pos.shape[0]):
        if not active[i] or cs[i, CS_IS_DEMOED] != 0.0:
            n_unwritable += 1
        if not active[i] or cs[i, CS_IS_DEMOED] > 0.5:
            continue
        R = rot[i]
        fwd, right, up, down = frame
        for j in range(3):
            fwd[j], right[j], up[j] = R[j, 0], R[j, 1], R[j, 2]
            down[j] = -up[j]
        p = pos[i]
        v0[:] = vel[i]
        w0[:] = ang_vel[i]
        v[:] = v0
        w[:] = w0
        force_dv[:] = 0.0
        car, c, m = cs[i], controls[i], mut[car_arena[i]]  # this car's state row, controls, arena's mutators
        jump = c[5] > 0.5
        jump_pressed = jump and car[CS_LAST_JUMP] < 0.5

        num_contact, num_world = _cast_wheel_rays(shape, p, R, down, wheel_conn[i], wheel_ray_len[i],
                                                  ball_pos[car_arena[i]], ball_radius, wheels, car, scratch)
        on_ground = num_contact >= C.WHEELS_FOR_ON_GROUND
        _suspension_impulses(p, R, down, v0, w0, inv_inertia[i], wheel_rest[i], wheel_radius[i], wheel_is_front[i],
                             wheels, car, susp_impulse, scratch, dt)
        _friction_impulses(p, R, frame, v0, w0, inv_inertia[i], wheel_is_front[i], wheels, car, fric_impulse,
                           fric_rel, scratch, dt)
        v_fwd = _update_wheels(frame, v0, w0, p, c, wheel_is_front[i], three_wheel[i], num_contact, num_world,
                               wheels, car, v, force_dv, scratch, dt)
        if not on_ground:
            _update_air_torque(R, frame, c, num_contact == 0, car, v, w, force_dv, dt)
        else:
            car[CS_IS_FLIPPING] = 0.0
        _update_jump(on_ground, jump, jump_pressed, up, m, car, v, force_dv, dt)
        _update_auto_flip(jump_pressed, frame, car, v, w, dt)
        _update_double_jump_or_flip(on_ground, jump_pressed, up, fwd, v_fwd, c, m, car, v, force_dv, dt)
        if c[0] != 0.0 and ((0 < num_contact < 4) or car[CS_BODY_CONTACT] > 0.5):
            _update_auto_roll(frame, num_contact, wheels, car, v, w, dt)
        car[CS_BODY_CONTACT] = 0.0
        _apply_wheel_impulses(p, R, down, inv_inertia[i], wheels, susp_impulse, fric_impulse, fric_rel, v, w,
                              scratch)
        _update_boost(c[6] > 0.5, on_ground, fwd, m, car, v, dt)
        car[CS_LAST_JUMP] = 1.0 if jump else 0.0
        vel[i] = v
        ang_vel[i] = w
    return n_unwritable


# The entry points take plain tuples in the records' field order and make the records inside: numba types a plain
# tuple argument in compiled code, a NamedTuple in Python code, which cost microseconds a call.
@njit(cache=True, nogil=True)
def car_pre_tick_classic(cars, model, ball_pos, ball_radius, cs, mut, dt):
    """``car_pre_tick`` in the "classic" arena; ``cars``, ``model``: tuples of ``CarArrays``' and ``CarModel``'s
    fields."""
    return car_pre_tick(CLASSIC, CarArrays(*cars), CarModel(*model), ball_pos, ball_radius, cs, mut, dt)


@njit(cache=True, nogil=True)
def car_pre_tick_game(cars, model, ball_pos, ball_radius, cs, mut, dt):
    """``car_pre_tick`` in the "game" arena (arguments as ``car_pre_tick_classic``'s)."""
    return car_pre_tick(GAME, CarArrays(*cars), CarModel(*model), ball_pos, ball_radius, cs, mut, dt)


@njit(cache=True, nogil=True, inline="always")
def _cast_wheel_rays(shape, p, R, down, conn, ray_len, ball_pos, ball_radius, wheels, car, scratch):
    """Each wheel's ray from its hard point along car-down, against the arena (analytically) and this arena's
    ball; records the contacts in ``car``. Returns (wheels in contact, wheels on the arena)."""
    hit, hit_world, dist, normal, hard = wheels
    rel = scratch.rel
    hit[:] = False
    hit_world[:] = False
    dist[:] = 0.0
    normal[:] = 0.0
    hard[:] = 0.0
    for k in range(4):
        c = conn[k]
        hp = hard[k]
        for j in range(3):
            hp[j] = p[j] + (R[j, 0] * c[0] + R[j, 1] * c[1] + R[j, 2] * c[2])
        ok, t, nx, ny, nz = shape_raycast(shape, hp[0], hp[1], hp[2], down[0], down[1], down[2], ray_len[k])
        tb = _ray_sphere(hp, down, ball_pos, ball_radius)
        if tb >= 0.0 and tb <= ray_len[k] and (not ok or tb < t):
            for j in range(3):
                rel[j] = hp[j] + down[j] * tb - ball_pos[j]
            norm = np.sqrt(vdot(rel, rel))
            for j in range(3):
                normal[k, j] = rel[j] / norm
            dist[k] = tb
            hit[k] = True
        elif ok:
            normal[k, 0], normal[k, 1], normal[k, 2] = nx, ny, nz
            dist[k] = t
            hit[k] = True
            hit_world[k] = True
    num_contact = 0
    num_world = 0
    for k in range(4):
        car[CS_WHEEL_0 + k] = 1.0 if hit[k] else 0.0
        num_contact += hit[k]
        num_world += hit_world[k]
    car[CS_NUM_WHEELS] = num_contact
    car[CS_ON_GROUND] = 1.0 if num_contact >= C.WHEELS_FOR_ON_GROUND else 0.0
    car[CS_WORLD_CONTACT] = 1.0 if num_world > 0 else 0.0
    return num_contact, num_world


@njit(cache=True, nogil=True, inline="always")
def _suspension_impulses(p, R, down, v0, w0, inv_i, rest_len, radius, is_front, wheels, car, susp_impulse, scratch,
                         dt):
    """btVehicleRL's suspension from the start-of-tick velocity: a spring-damper that never pulls, plus the hard
    stop, an inelastic push-back of a wheel on the arena that comes closer than its rest length plus radius."""
    hit, hit_world, dist, normal, hard = wheels
    rel, v_cp, cross, _, _ = scratch
    susp_impulse[:] = 0.0
    for k in range(4):
        if not hit[k]:
            car[CS_PUSHBACK_0 + k] = 0.0
            continue
        n = normal[k]
        _contact_point_velocity(hard[k], down, dist[k], p, v0, w0, rel, cross, v_cp)
        rest = rest_len[k]
        gap = dist[k] - (rest + radius[k] - C.SUSPENSION_SUBTRACTION)
        if hit_world[k] and gap < 0.0:
            # btVehicleRL keeps the last push-back while the wheel stays in contact above the threshold
            m_eff = 1.0 / _inv_mass_along(R, inv_i, rel, n)
            car[CS_PUSHBACK_0 + k] = max(m_eff * (-C.SOLVER_ERP * gap / dt - vdot(n, v_cp)), 0.0) / 4.0
        susp_len = min(max(dist[k] - radius[k], rest - C.SUSPENSION_MAX_TRAVEL), rest + C.SUSPENSION_MAX_TRAVEL)
        n_up = -vdot(n, down)  # how squarely the surface faces the suspension
        if n_up > 0.1:
            clipped_inv = 1.0 / n_up
            rel_vel = vdot(n, v_cp) * clipped_inv
        else:  # a surface almost along the suspension: btVehicleRL's clip (RocketSim)
            rel_vel = 0.0
            clipped_inv = 10.0
        scale = C.SUSPENSION_FORCE_SCALE_FRONT if is_front[k] else C.SUSPENSION_FORCE_SCALE_BACK
        damping = C.SUSPENSION_DAMP_COMPRESSION if rel_vel < 0.0 else C.SUSPENSION_DAMP_RELAXATION
        force = (C.SUSPENSION_STIFFNESS * (rest - susp_len) * clipped_inv - damping * rel_vel) * scale
        if force <= 0.0:
            continue  # the suspension never pulls
        amount = force * dt + car[CS_PUSHBACK_0 + k]
        for j in range(3):
            susp_impulse[k, j] = n[j] * amount


@njit(cache=True, nogil=True, inline="always")
def _contact_point_velocity(hard_point, down, dist, p, v0, w0, rel, cross, v_cp):
    """A wheel's contact point relative to the centre of mass (``rel``) and the start-of-tick velocity there."""
    for j in range(3):
        rel[j] = hard_point[j] + down[j] * dist - p[j]
    vcross_into(w0, rel, cross)
    for j in range(3):
        v_cp[j] = v0[j] + cross[j]


@njit(cache=True, nogil=True, inline="always")
def _friction_impulses(p, R, frame, v0, w0, inv_i, is_front, wheels, car, fric_impulse, fric_rel, scratch, dt):
    """btVehicleRL's tyre impulses from the start-of-tick velocity with LAST tick's steering angle, engine, brake
    and friction factors (Bullet's vehicle applies a wheel set-up one tick late)."""
    fwd, right, up, down = frame
    hit, _, dist, normal, hard = wheels
    rel, v_cp, cross, axle, f_dir = scratch
    fric_impulse[:] = 0.0
    fric_rel[:] = 0.0
    last_angle = car[CS_STEER_ANGLE]
    cos_l, sin_l = np.cos(last_angle), np.sin(last_angle)
    for k in range(4):
        if not hit[k]:
            continue
        n = normal[k]
        _contact_point_velocity(hard[k], down, dist[k], p, v0, w0, rel, cross, v_cp)
        along_up = vdot(rel, up)
        for j in range(3):  # applied in the centre-of-mass plane: no pitch from braking
            fric_rel[k, j] = rel[j] - up[j] * along_up
        _wheel_axle(is_front[k], fwd, right, cos_l, sin_l, axle)
        along_n = vdot(axle, n)
        for j in range(3):
            axle[j] = axle[j] - n[j] * along_n
        a_len = np.sqrt(vdot(axle, axle))
        if a_len < 1e-9:
            continue
        for j in range(3):
            axle[j] /= a_len
        vcross_into(axle, n, f_dir)
        m_lat = 1.0 / _inv_mass_along(R, inv_i, rel, axle)
        side = -0.2 * vdot(v_cp, axle) * m_lat
        engine = car[CS_ENGINE]
        if engine != 0.0:
            rolling = engine
        elif car[CS_BRAKE] != 0.0:
            b = car[CS_BRAKE]
            rolling = min(max(-vdot(v_cp, f_dir) * C.BRAKE_SLIP_SCALE, -b), b)
        else:
            rolling = 0.0
        long_amount = rolling * car[CS_LONG_FRICTION_0 + k]
        lat_amount = side * car[CS_LAT_FRICTION_0 + k]
        for j in range(3):
            fric_impulse[k, j] = (f_dir[j] * long_amount + axle[j] * lat_amount) * (C.CAR_MASS / 3.0) * dt


@njit(cache=True, nogil=True, inline="always")
def _wheel_axle(is_front, fwd, right, cos_a, sin_a, out):
    """A wheel's axle: the car's right, turned by the steering angle on the front wheels."""
    if is_front:
        for j in range(3):
            out[j] = right[j] * cos_a - fwd[j] * sin_a
    else:
        out[:] = right


@njit(cache=True, nogil=True, inline="always")
def _update_wheels(frame, v0, w0, p, c, is_front, three_wheel, num_contact, num_world, wheels, car, v, force_dv,
                   scratch, dt):
    """RocketSim's ``_UpdateWheels``: this tick's handbrake, engine and brake, steering angle and tyre friction
    factors (applied next tick), and the sticky force. Returns the forward speed at the start of the tick."""
    fwd, right, _, _ = frame
    hit, _, _, normal, hard = wheels
    rel, v_cp, cross, axle, f_dir = scratch
    throttle, steer, handbrake = c[0], c[1], c[7] > 0.5
    hb = car[CS_HANDBRAKE]
    hb = hb + C.POWERSLIDE_RISE_RATE * dt if handbrake else hb - C.POWERSLIDE_FALL_RATE * dt
    hb = min(max(hb, 0.0), 1.0)
    car[CS_HANDBRAKE] = hb
    v_fwd = vdot(v0, fwd)
    abs_v_fwd = abs(v_fwd)
    real_throttle = 1.0 if (c[6] > 0.5 and car[CS_BOOST] > 0.0) else throttle
    engine_throttle = real_throttle
    brake = 0.0
    if not handbrake:
        if abs(real_throttle) >= C.THROTTLE_DEADZONE:
            if abs_v_fwd > C.STOPPING_FORWARD_VEL and real_throttle * v_fwd < 0.0:
                brake = 1.0
                engine_throttle = 0.0
        else:
            engine_throttle = 0.0
            brake = 1.0 if abs_v_fwd < C.STOPPING_FORWARD_VEL else C.COAST_BRAKE_FACTOR
    drive_scale = interp(_THROTTLE_CURVE, abs_v_fwd)
    if num_contact < 3:
        drive_scale *= 0.25
    # Per-wheel values in "impulse per (mass/3) per second", RocketSim's friction scale.
    car[CS_ENGINE] = engine_throttle * C.THROTTLE_TORQUE_AMOUNT * 3.0 * drive_scale
    car[CS_BRAKE] = brake * C.BRAKE_ACCEL / 4.0 * 3.0
    angle = interp(_STEER_CURVE_3W if three_wheel else _STEER_CURVE, abs_v_fwd)
    if hb > 0.0:
        angle += (interp(_POWERSLIDE_CURVE, abs_v_fwd) - angle) * hb
    # The axles below still turn by last tick's angle: friction factors are measured on the wheel as it is.
    cos_l, sin_l = np.cos(car[CS_STEER_ANGLE]), np.sin(car[CS_STEER_ANGLE])
    car[CS_STEER_ANGLE] = angle * steer
    for k in range(4):
        if not hit[k]:
            continue
        n = normal[k]
        _wheel_axle(is_front[k], fwd, right, cos_l, sin_l, axle)
        vcross_into(axle, n, f_dir)  # the wheel's rolling direction
        for j in range(3):
            rel[j] = hard[k, j] - p[j]
        vcross_into(w0, rel, cross)
        for j in range(3):
            v_cp[j] = v0[j] + cross[j]  # the velocity at the wheel's hard point
        lat_speed = abs(vdot(v_cp, axle))
        slip = 0.0
        if lat_speed > 5.0:
            slip = lat_speed / (abs(vdot(v_cp, f_dir)) + lat_speed)
        lat_fric = interp(_LAT_CURVE_3W if three_wheel else _LAT_CURVE, slip)
        long_fric = 1.0
        if hb > 0.0:
            lat_fric *= (C.HANDBRAKE_LAT_FRICTION_FACTOR - 1.0) * hb + 1.0
            long_fric *= (interp(_HB_LONG_CURVE, slip) - 1.0) * hb + 1.0
        if real_throttle == 0.0:
            non_sticky = interp(_NON_STICKY_CURVE, n[2])
            lat_fric *= non_sticky
            long_fric *= non_sticky
        car[CS_LAT_FRICTION_0 + k] = lat_fric
        car[CS_LONG_FRICTION_0 + k] = long_fric
    if num_world > 0:
        n_avg = _mean_normal(wheels)
        sticky = 0.0 if three_wheel else C.STICKY_FORCE_GROUND
        if real_throttle != 0.0 or abs_v_fwd > C.STOPPING_FORWARD_VEL:
            sticky += C.STICKY_FORCE_FULL_STICK_EXTRA * (1.0 - abs(n_avg[2]))
        v -= n_avg * (sticky * _GRAVITY * dt)
        force_dv -= n_avg * (sticky * _GRAVITY * dt)
    return v_fwd


@njit(cache=True, nogil=True, inline="always")
def _mean_normal(wheels):
    """The normalised mean of the contact normals of the wheels in contact (btVehicleRL's upwards direction)."""
    hit, _, _, normal, _ = wheels
    n_avg = np.zeros(3)
    for k in range(4):
        if hit[k]:
            n_avg += normal[k]
    n_avg /= np.sqrt(vdot(n_avg, n_avg))
    return n_avg


@njit(cache=True, nogil=True, inline="always")
def _update_air_torque(R, frame, c, air_control_allowed, car, v, w, force_dv, dt):
    """RocketSim's ``_UpdateAirTorque``, with fewer than 3 wheels down: a flip's torque while it lasts (a flip ends
    once its time reaches 0.65 s at the start of a tick; pulling against it scales its pitch by 1 - |pitch|), air
    control (pitch, yaw, roll with damping; pitch locked during and just after a flip) with no wheel down, and air
    throttle."""
    pitch_in, yaw_in, roll_in = c[2], c[3], c[4]
    wl = mat_t_vec(R, w)
    alpha = np.zeros(3)
    if car[CS_IS_FLIPPING] > 0.5:
        car[CS_IS_FLIPPING] = 1.0 if car[CS_HAS_FLIPPED] > 0.5 and car[CS_FLIP_TIME] < _FLIP_TORQUE_TIME else 0.0
    flipping = car[CS_IS_FLIPPING] > 0.5
    air_control = True
    if flipping:
        tx = car[CS_FLIP_TORQUE_X]
        ty = car[CS_FLIP_TORQUE_Y]
        if tx != 0.0 or ty != 0.0:  # not a stall
            air_control = False
            if ty != 0.0 and pitch_in != 0.0 and (ty > 0.0) == (pitch_in > 0.0):
                ty *= 1.0 - min(abs(pitch_in), 1.0)  # flip cancel: frees air control, pitch stays locked
                air_control = True
            alpha[0] += C.FLIP_TORQUE_X * tx
            alpha[1] += C.FLIP_TORQUE_Y * ty
    air_control = air_control and car[CS_IS_AUTOFLIPPING] < 0.5 and air_control_allowed
    if air_control:
        pitch_scale = 1.0
        if flipping or (car[CS_HAS_FLIPPED] > 0.5 and car[CS_FLIP_TIME] < _FLIP_PITCHLOCK_TIME):
            pitch_scale = 0.0
        up_p = pitch_in * pitch_scale
        alpha[0] -= _AIR_TORQUE[2] * roll_in + _AIR_DAMPING[2] * wl[0]
        alpha[1] -= _AIR_TORQUE[0] * up_p + _AIR_DAMPING[0] * wl[1] * (1.0 - abs(up_p))
        alpha[2] += _AIR_TORQUE[1] * yaw_in - _AIR_DAMPING[1] * wl[2] * (1.0 - abs(yaw_in))
    w += mat_vec(R, alpha) * dt
    if c[0] != 0.0:
        v += frame.fwd * (C.THROTTLE_AIR_ACCEL * c[0] * dt)
        force_dv += frame.fwd * (C.THROTTLE_AIR_ACCEL * c[0] * dt)


@njit(cache=True, nogil=True, inline="always")
def _update_jump(on_ground, jump, jump_pressed, up, m, car, v, force_dv, dt):
    """RocketSim's ``_UpdateJump``: an impulse on the press, then a hold force for 0.025 to 0.2 s. The jump's
    time counts on after the jump until the car lands (has_jumped is cleared then, unless the jump is younger than
    0.05 s: it may still be leaving the ground)."""
    if on_ground and car[CS_IS_JUMPING] < 0.5:
        if not (car[CS_HAS_JUMPED] > 0.5 and car[CS_JUMP_TIME] < _JUMP_RESET_TIME):
            car[CS_HAS_JUMPED] = 0.0
            car[CS_JUMP_TIME] = 0.0
    if car[CS_IS_JUMPING] > 0.5:
        still = car[CS_JUMP_TIME] < _JUMP_MIN_TIME or (jump and car[CS_JUMP_TIME] < _JUMP_MAX_TIME)
        car[CS_IS_JUMPING] = 1.0 if still else 0.0
    elif on_ground and jump_pressed:
        car[CS_IS_JUMPING] = 1.0
        car[CS_JUMP_TIME] = 0.0
        v += up * m[MUT_JUMP_IMMEDIATE_VEL]
    if car[CS_IS_JUMPING] > 0.5:
        car[CS_HAS_JUMPED] = 1.0
        accel = m[MUT_JUMP_ACCEL]
        if car[CS_JUMP_TIME] < _JUMP_MIN_TIME:
            accel *= C.JUMP_PRE_MIN_ACCEL_SCALE
        v += up * (accel * dt)
        force_dv += up * (accel * dt)
    if car[CS_IS_JUMPING] > 0.5 or car[CS_HAS_JUMPED] > 0.5:
        car[CS_JUMP_TIME] = _tick(car[CS_JUMP_TIME], dt)


@njit(cache=True, nogil=True, inline="always")
def _update_auto_flip(jump_pressed, frame, car, v, w, dt):
    """RocketSim's ``_UpdateAutoFlip``: jump while lying on the roof rights the car."""
    fwd, right, up, _ = frame
    if jump_pressed and car[CS_BODY_CONTACT] > 0.5 and car[CS_BODY_NORMAL_X + 2] > C.AUTOFLIP_NORM_Z_THRESH:
        roll_angle = np.arctan2(-right[2], up[2])
        if abs(roll_angle) > C.AUTOFLIP_ROLL_THRESH:
            car[CS_AUTOFLIP_TIMER] = C.AUTOFLIP_TIME * abs(roll_angle) / np.pi
            car[CS_AUTOFLIP_SCALE] = 1.0 if roll_angle > 0.0 else -1.0
            car[CS_IS_AUTOFLIPPING] = 1.0
            v -= up * C.AUTOFLIP_IMPULSE
    if car[CS_IS_AUTOFLIPPING] > 0.5:
        if car[CS_AUTOFLIP_TIMER] <= 0.0:
            car[CS_IS_AUTOFLIPPING] = 0.0
            car[CS_AUTOFLIP_TIMER] = 0.0
        else:
            w += fwd * (C.AUTOFLIP_TORQUE * car[CS_AUTOFLIP_SCALE] * dt)
            car[CS_AUTOFLIP_TIMER] -= dt


@njit(cache=True, nogil=True, inline="always")
def _update_double_jump_or_flip(on_ground, jump_pressed, up, fwd, v_fwd, c, m, car, v, force_dv, dt):
    """RocketSim's ``_UpdateDoubleJumpOrFlip``: landing restores both and clears the flip's time; in the air a new
    press within 1.25 s of the jump is a flip (|pitch| + |yaw| + |roll| past the dodge deadzone) or a double
    jump; a flip's Z-damping (of the velocity before this tick's forces, which Bullet adds after it)."""
    pitch_in, yaw_in, roll_in = c[2], c[3], c[4]
    if on_ground:
        car[CS_HAS_DOUBLE_JUMPED] = 0.0
        car[CS_HAS_FLIPPED] = 0.0
        car[CS_AIR_TIME_SINCE_JUMP] = 0.0
        car[CS_FLIP_TIME] = 0.0
    else:
        if car[CS_HAS_JUMPED] > 0.5 and car[CS_IS_JUMPING] < 0.5:
            car[CS_AIR_TIME_SINCE_JUMP] = _tick(car[CS_AIR_TIME_SINCE_JUMP], dt)
        else:
            car[CS_AIR_TIME_SINCE_JUMP] = 0.0
        if jump_pressed and car[CS_AIR_TIME_SINCE_JUMP] < _DOUBLEJUMP_MAX_DELAY \
                and car[CS_IS_AUTOFLIPPING] < 0.5:
            unused = car[CS_HAS_DOUBLE_JUMPED] < 0.5 and car[CS_HAS_FLIPPED] < 0.5
            if abs(yaw_in) + abs(pitch_in) + abs(roll_in) >= m[MUT_DODGE_DEADZONE]:
                if unused or m[MUT_UNLIMITED_FLIPS] != 0.0:
                    _start_flip(car, v, fwd, v_fwd, pitch_in, yaw_in, roll_in)
            elif unused or m[MUT_UNLIMITED_DOUBLE_JUMPS] != 0.0:
                v += up * C.JUMP_IMMEDIATE_VEL  # RocketSim's double jump ignores the mutator's jump impulse
                car[CS_HAS_DOUBLE_JUMPED] = 1.0
    if car[CS_IS_FLIPPING] > 0.5:
        car[CS_FLIP_TIME] = ft = _tick(car[CS_FLIP_TIME], dt)
        if ft <= _FLIP_TORQUE_TIME:
            vz = v[2] - force_dv[2]
            if ft >= _FLIP_Z_DAMP_START and (vz < 0.0 or ft < _FLIP_Z_DAMP_END):
                v[2] = vz * (1.0 - C.FLIP_Z_DAMP_120) ** (dt * 120.0) + force_dv[2]
    elif car[CS_HAS_FLIPPED] > 0.5:
        car[CS_FLIP_TIME] = _tick(car[CS_FLIP_TIME], dt)  # counts on for the pitch lock after the flip


@njit(cache=True, nogil=True, inline="always")
def _update_auto_roll(frame, num_contact, wheels, car, v, w, dt):
    """RocketSim's ``_UpdateAutoRoll``: driving with some wheels (or the body) on a surface turns the car onto it."""
    fwd, right, _, _ = frame
    if num_contact > 0:
        g_up = _mean_normal(wheels)
    else:
        g_up = car[CS_BODY_NORMAL_X:CS_BODY_NORMAL_X + 3].copy()
    cross_right = vcross(g_up, fwd)
    cross_fwd = vcross(-g_up, cross_right)
    right_factor = 1.0 - min(max(vdot(right, cross_right), 0.0), 1.0)
    fwd_factor = 1.0 - min(max(vdot(fwd, cross_fwd), 0.0), 1.0)
    torque_right = fwd * (-1.0 if vdot(right, g_up) >= 0.0 else 1.0) * right_factor
    torque_fwd = right * (1.0 if vdot(fwd, g_up) >= 0.0 else -1.0) * fwd_factor
    v -= g_up * (C.AUTOROLL_FORCE * dt)
    w += (torque_fwd + torque_right) * (C.AUTOROLL_TORQUE * dt)


@njit(cache=True, nogil=True, inline="always")
def _apply_wheel_impulses(p, R, down, inv_i, wheels, susp_impulse, fric_impulse, fric_rel, v, w, scratch):
    """The vehicle's second half: the suspension impulses at the contact points, then the tyre impulses."""
    hit, _, dist, _, hard = wheels
    rel = scratch.rel
    for k in range(4):
        if hit[k]:
            for j in range(3):
                rel[j] = hard[k, j] + down[j] * dist[k] - p[j]
            _apply_impulse(R, inv_i, v, w, rel, susp_impulse[k])
    for k in range(4):
        if hit[k]:
            _apply_impulse(R, inv_i, v, w, fric_rel[k], fric_impulse[k])


@njit(cache=True, nogil=True, inline="always")
def _update_boost(boost_btn, on_ground, fwd, m, car, v, dt):
    """RocketSim's ``_UpdateBoost``: once started, boosting lasts at least 0.1 s while boost remains; an empty tank
    stops it and clears its timer at once."""
    t_boost = car[CS_BOOSTING_TIME]
    if t_boost > 0.0:
        t_boost = 0.0 if (not boost_btn and t_boost >= _BOOST_MIN_TIME) else _tick(t_boost, dt)
    elif boost_btn:
        t_boost = _tick(0.0, dt)
    has_boost = car[CS_BOOST] > 0.0
    t_boost = t_boost if has_boost else 0.0
    car[CS_BOOSTING_TIME] = t_boost
    boosting = t_boost > 0.0
    if boosting:
        car[CS_BOOST] = max(car[CS_BOOST] - m[MUT_BOOST_USED_PER_SECOND] * dt, 0.0)
        v += fwd * ((m[MUT_BOOST_ACCEL_GROUND] if on_ground else m[MUT_BOOST_ACCEL_AIR]) * dt)
    car[CS_IS_BOOSTING] = 1.0 if boosting else 0.0


@njit(cache=True, nogil=True)
def _start_flip(car, v, fwd, v_fwd, pitch_in, yaw_in, roll_in):
    """A dodge: its direction and torque from the stick, its impulse in the horizontal plane (RocketSim)."""
    car[CS_HAS_FLIPPED] = 1.0
    car[CS_IS_FLIPPING] = 1.0
    car[CS_FLIP_TIME] = 0.0
    dx, dy = -pitch_in, yaw_in + roll_in
    if abs(dx) < 0.1 and abs(dy) < 0.1:  # a stall: no impulse, no torque, air control stays on
        car[CS_FLIP_TORQUE_X] = 0.0
        car[CS_FLIP_TORQUE_Y] = 0.0
        return
    norm = np.sqrt(dx * dx + dy * dy)
    dx /= norm
    dy /= norm
    car[CS_FLIP_TORQUE_X] = -dy
    car[CS_FLIP_TORQUE_Y] = dx
    if abs(dx) < 0.1:
        dx = 0.0
    if abs(dy) < 0.1:
        dy = 0.0
    abs_v = abs(v_fwd)
    speed_ratio = abs_v / C.CAR_MAX_SPEED
    backwards = dx < 0.0 if abs_v < 100.0 else (dx * v_fwd < 0.0 and dx != 0.0)
    imp_x = dx * C.FLIP_INITIAL_VEL_SCALE
    imp_y = dy * C.FLIP_INITIAL_VEL_SCALE
    if backwards:
        imp_x *= (1.0 + (C.FLIP_BACKWARD_IMPULSE_MAX_SPEED_SCALE - 1.0) * speed_ratio) \
            * C.FLIP_BACKWARD_IMPULSE_SCALE_X
    else:
        imp_x *= 1.0 + (C.FLIP_FORWARD_IMPULSE_MAX_SPEED_SCALE - 1.0) * speed_ratio
    imp_y *= 1.0 + (C.FLIP_SIDE_IMPULSE_MAX_SPEED_SCALE - 1.0) * speed_ratio
    fh = np.array([fwd[0], fwd[1], 0.0])
    fh_len = np.sqrt(vdot(fh, fh))
    if fh_len < 1e-9:
        return
    fh /= fh_len
    rh = np.array([-fh[1], fh[0], 0.0])  # world up x forward: the car's right in the horizontal plane
    v += fh * imp_x + rh * imp_y


@njit(cache=True, nogil=True)
def _gyroscopic_step(w0, w1, w2, R, i0, i1, i2, h):
    """The angular-velocity change Bullet's implicit gyroscopic term gives a body turning at ``w`` over ``h``
    (``btRigidBody::computeGyroscopicImpulseImplicit_Body``: one Newton step of Euler's equations in body axes),
    for principal inertia ``i0, i1, i2``. In scalars: it runs 8 times a car a tick, where small arrays cost more than
    the arithmetic (each operation in the order the array form had, so the results are the same bit for bit)."""
    wb0 = R[0, 0] * w0 + R[1, 0] * w1 + R[2, 0] * w2
    wb1 = R[0, 1] * w0 + R[1, 1] * w1 + R[2, 1] * w2
    wb2 = R[0, 2] * w0 + R[1, 2] * w1 + R[2, 2] * w2
    iw0, iw1, iw2 = i0 * wb0, i1 * wb1, i2 * wb2
    f0, f1, f2 = (wb1 * iw2 - wb2 * iw1) * h, (wb2 * iw0 - wb0 * iw2) * h, (wb0 * iw1 - wb1 * iw0) * h
    # Columns a, b, c of the Jacobian J = I + (skew(wb) I - skew(I wb)) h, then J^-1 f by Cramer's rule (Bullet's
    # solve33).
    a0, a1, a2 = i0, (wb2 * i0 - iw2) * h, (-wb1 * i0 + iw1) * h
    b0, b1, b2 = (-wb2 * i1 + iw2) * h, i1, (wb0 * i1 - iw0) * h
    c0, c1, c2 = (wb1 * i2 - iw1) * h, (-wb0 * i2 + iw0) * h, i2
    x0, x1, x2 = b1 * c2 - b2 * c1, b2 * c0 - b0 * c2, b0 * c1 - b1 * c0  # b x c
    inv_det = 1.0 / (a0 * x0 + a1 * x1 + a2 * x2)
    wb0 -= inv_det * (f0 * x0 + f1 * x1 + f2 * x2)
    y0, y1, y2 = f1 * c2 - f2 * c1, f2 * c0 - f0 * c2, f0 * c1 - f1 * c0  # f x c
    wb1 -= inv_det * (a0 * y0 + a1 * y1 + a2 * y2)
    z0, z1, z2 = b1 * f2 - b2 * f1, b2 * f0 - b0 * f2, b0 * f1 - b1 * f0  # b x f
    wb2 -= inv_det * (a0 * z0 + a1 * z1 + a2 * z2)
    return (R[0, 0] * wb0 + R[0, 1] * wb1 + R[0, 2] * wb2 - w0,
            R[1, 0] * wb0 + R[1, 1] * wb1 + R[1, 2] * wb2 - w1,
            R[2, 0] * wb0 + R[2, 1] * wb1 + R[2, 2] * wb2 - w2)


@njit(cache=True, nogil=True)
def cancel_gyroscopic(ang_vel, rot, inv_inertia, writable, dt, out):
    """The angular velocities to hand PyBullet so that, after the gyroscopic step it adds to every rigid body
    (and cannot be switched off from Python), each car turns at ``ang_vel``: RocketSim's cars have no gyroscopic
    term (``m_rigidbodyFlags = 0``). Solves w + gyro(w) = target by fixed-point iteration (the map contracts by
    about dt |w| on a car's inertia ratios, below 0.1 at the 5.5 rad/s cap)."""
    for i in range(ang_vel.shape[0]):
        out[i] = ang_vel[i]
        if not writable[i]:
            continue
        i0, i1, i2 = 1.0 / inv_inertia[i, 0], 1.0 / inv_inertia[i, 1], 1.0 / inv_inertia[i, 2]
        for _ in range(8):
            d0, d1, d2 = _gyroscopic_step(out[i, 0], out[i, 1], out[i, 2], rot[i], i0, i1, i2, dt)
            out[i, 0] = ang_vel[i, 0] - d0
            out[i, 1] = ang_vel[i, 1] - d1
            out[i, 2] = ang_vel[i, 2] - d2


@njit(cache=True, nogil=True)
def car_post_tick(vel, ang_vel, active, cs, dt):
    """Speed caps, the supersonic state and demolition timers, after the rigid-body step.

    Returns how many demolished cars are due to respawn.
    """
    respawn_due = 0
    for i in range(vel.shape[0]):
        if not active[i]:
            continue
        if cs[i, CS_IS_DEMOED] > 0.5:
            cs[i, CS_DEMO_TIMER] = max(cs[i, CS_DEMO_TIMER] - dt, 0.0)
            if cs[i, CS_DEMO_TIMER] <= 0.0:
                respawn_due += 1
            continue
        speed = np.sqrt(vdot(vel[i], vel[i]))
        if speed > C.CAR_MAX_SPEED:
            vel[i] *= C.CAR_MAX_SPEED / speed
            speed = C.CAR_MAX_SPEED
        ang = np.sqrt(vdot(ang_vel[i], ang_vel[i]))
        if ang > C.CAR_MAX_ANG_SPEED:
            ang_vel[i] *= C.CAR_MAX_ANG_SPEED / ang
        if cs[i, CS_IS_SUPERSONIC] > 0.5 and cs[i, CS_SUPERSONIC_TIME] < _SUPERSONIC_MAINTAIN_MAX_TIME:
            supersonic = speed >= C.SUPERSONIC_MAINTAIN_MIN_SPEED
        else:
            supersonic = speed >= C.SUPERSONIC_START_SPEED
        if supersonic:
            cs[i, CS_SUPERSONIC_TIME] = _tick(cs[i, CS_SUPERSONIC_TIME], dt)  # from dt on the first tick, as RocketSim
        else:
            cs[i, CS_SUPERSONIC_TIME] = 0.0
        cs[i, CS_IS_SUPERSONIC] = 1.0 if supersonic else 0.0
    return respawn_due


@njit(cache=True, nogil=True)
def boost_pad_tick(car_pos, car_arena, active, cs, pad_pos, pad_is_big, pad_timer, picked, gained, mut, dt):
    """Count pad cooldowns down and let cars pick up active pads, in the arenas with pads on (``mut``);
    ``picked[i]`` gets the pad index or -1 and ``gained[i]`` the boost it added.

    Returns the number of pickups this tick.
    """
    n_picked = 0
    for a in range(pad_timer.shape[0]):
        if mut[a, MUT_BOOST_PADS] == 0.0:
            continue
        for k in range(pad_timer.shape[1]):
            if pad_timer[a, k] > 0.0:
                pad_timer[a, k] = max(pad_timer[a, k] - dt, 0.0)
    for i in range(car_pos.shape[0]):
        picked[i] = -1
        a = car_arena[i]
        if (not active[i] or cs[i, CS_IS_DEMOED] > 0.5 or cs[i, CS_BOOST] >= C.BOOST_MAX
                or mut[a, MUT_BOOST_PADS] == 0.0):
            continue
        for k in range(pad_pos.shape[0]):
            if pad_timer[a, k] > 0.0:
                continue
            radius = C.BOOST_PAD_BIG_RADIUS if pad_is_big[k] else C.BOOST_PAD_SMALL_RADIUS
            dx = car_pos[i, 0] - pad_pos[k, 0]
            dy = car_pos[i, 1] - pad_pos[k, 1]
            if dx * dx + dy * dy < radius * radius and abs(car_pos[i, 2] - pad_pos[k, 2]) < C.BOOST_PAD_MAX_Z_DIFF:
                amount = C.BOOST_PAD_BIG_AMOUNT if pad_is_big[k] else C.BOOST_PAD_SMALL_AMOUNT
                before = cs[i, CS_BOOST]
                cs[i, CS_BOOST] = min(before + amount, C.BOOST_MAX)
                gained[i] = cs[i, CS_BOOST] - before
                pad_timer[a, k] = mut[a, MUT_PAD_COOLDOWN_BIG] if pad_is_big[k] else mut[a, MUT_PAD_COOLDOWN_SMALL]
                picked[i] = k
                n_picked += 1
                break
    return n_picked
