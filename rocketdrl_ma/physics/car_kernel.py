"""The per-tick car model, compiled with numba over every car of every arena at once.

PyBullet integrates rigid bodies and resolves body contacts; everything Rocket League adds on top
(raycast suspension, tyres, engine and brakes, boost, jumps, flips, air control, sticky force) is a
velocity change computed here before each ``stepSimulation``. All quantities are in uu, s, rad.

Car state that is not a rigid-body quantity lives in one float matrix ``cs`` (cars x CS_SIZE) whose
columns are named below, so the whole model is one compiled loop with no Python objects per car.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from . import constants as C
from .arena_geometry import arena_raycast
from .mutators import (MUT_BOOST_ACCEL_AIR, MUT_BOOST_ACCEL_GROUND, MUT_BOOST_PADS, MUT_BOOST_USED_PER_SECOND,
                       MUT_DODGE_DEADZONE, MUT_JUMP_ACCEL, MUT_JUMP_IMMEDIATE_VEL, MUT_PAD_COOLDOWN_BIG,
                       MUT_PAD_COOLDOWN_SMALL, MUT_UNLIMITED_DOUBLE_JUMPS, MUT_UNLIMITED_FLIPS)

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
CS_AIR_TIME = 11
CS_AIR_TIME_SINCE_JUMP = 12
CS_BOOSTING_TIME = 13
CS_IS_BOOSTING = 14
CS_LAST_JUMP = 15
CS_ON_GROUND = 16
CS_NUM_WHEELS = 17
CS_WHEEL_0 = 18  # four columns: 1.0 where that wheel's ray hits
CS_IS_SUPERSONIC = 22
CS_SUPERSONIC_TIME = 23
CS_IS_DEMOED = 24
CS_DEMO_TIMER = 25
CS_WORLD_CONTACT = 26  # some wheel touches the arena
CS_STEER_ANGLE = 27  # the wheel set-up of the last tick: Bullet's vehicle applies it one tick late
CS_ENGINE = 28
CS_BRAKE = 29
CS_LAT_FRICTION_0 = 30  # four columns
CS_LONG_FRICTION_0 = 34  # four columns
CS_IS_AUTOFLIPPING = 38
CS_AUTOFLIP_TIMER = 39
CS_AUTOFLIP_SCALE = 40
CS_BODY_CONTACT = 41  # the hitbox touched the arena last tick
CS_BODY_NORMAL_X = 42  # three columns: that contact's normal
CS_SIZE = 45
# Memory of earlier ticks that CarState does not carry (the last jump input for edge detection, boost's minimum
# duration, the wheel set-up Bullet applies one tick late, autoflip, body contact): set_state clears it, so a
# state set on a used car plays on exactly as on a new car (RocketSim's CarState carries last_controls likewise).
CS_TICK_MEMORY = (CS_BOOSTING_TIME, CS_IS_BOOSTING, CS_LAST_JUMP, CS_STEER_ANGLE, CS_ENGINE, CS_BRAKE,
                  *range(CS_LAT_FRICTION_0, CS_LAT_FRICTION_0 + 4), *range(CS_LONG_FRICTION_0, CS_LONG_FRICTION_0 + 4),
                  CS_IS_AUTOFLIPPING, CS_AUTOFLIP_TIMER, CS_AUTOFLIP_SCALE, CS_BODY_CONTACT,
                  *range(CS_BODY_NORMAL_X, CS_BODY_NORMAL_X + 3))

_THROTTLE_CURVE = np.array(C.THROTTLE_TORQUE_CURVE)
_STEER_CURVE = np.array(C.STEER_ANGLE_CURVE)
_STEER_CURVE_3W = np.array(((0.0, 0.342473), (2300.0, 0.034837)))
_POWERSLIDE_CURVE = np.array(C.POWERSLIDE_STEER_ANGLE_CURVE)
_LAT_CURVE = np.array(C.LAT_FRICTION_CURVE)
_LAT_CURVE_3W = np.array(((0.0, 0.30), (1.0, 0.25)))
_HB_LONG_CURVE = np.array(C.HANDBRAKE_LONG_FRICTION_CURVE)
_NON_STICKY_CURVE = np.array(C.NON_STICKY_FRICTION_CURVE)
_AIR_TORQUE = np.array(C.CAR_AIR_CONTROL_TORQUE) * C.CAR_TORQUE_SCALE
_AIR_DAMPING = np.array(C.CAR_AIR_CONTROL_DAMPING) * C.CAR_TORQUE_SCALE
_GRAVITY = -C.GRAVITY_Z


@njit(cache=True)
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


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _mv(R, x):
    """R @ x for a 3x3 matrix, without BLAS."""
    return np.array([R[0, 0] * x[0] + R[0, 1] * x[1] + R[0, 2] * x[2],
                     R[1, 0] * x[0] + R[1, 1] * x[1] + R[1, 2] * x[2],
                     R[2, 0] * x[0] + R[2, 1] * x[1] + R[2, 2] * x[2]])


@njit(cache=True)
def _mtv(R, x):
    """R.T @ x for a 3x3 matrix, without BLAS."""
    return np.array([R[0, 0] * x[0] + R[1, 0] * x[1] + R[2, 0] * x[2],
                     R[0, 1] * x[0] + R[1, 1] * x[1] + R[2, 1] * x[2],
                     R[0, 2] * x[0] + R[1, 2] * x[1] + R[2, 2] * x[2]])


@njit(cache=True)
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def _set_cross(a, b, out):
    """out = a x b (``_cross`` without a new array; ``out`` must not be ``a`` or ``b``)."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


# The helpers below run several times per car and tick: they work on scalars (the arithmetic of
# ``_mtv(R, _cross(...))`` and friends term by term) because a small array per step cost more than the maths.
@njit(cache=True)
def _inv_mass_along(R, inv_inertia, rel, direction):
    """1/m_eff of a unit impulse along ``direction`` applied at offset ``rel`` from the centre of mass."""
    x = rel[1] * direction[2] - rel[2] * direction[1]
    y = rel[2] * direction[0] - rel[0] * direction[2]
    z = rel[0] * direction[1] - rel[1] * direction[0]
    c0 = R[0, 0] * x + R[1, 0] * y + R[2, 0] * z
    c1 = R[0, 1] * x + R[1, 1] * y + R[2, 1] * z
    c2 = R[0, 2] * x + R[1, 2] * y + R[2, 2] * z
    return 1.0 / C.CAR_MASS + inv_inertia[0] * c0 ** 2 + inv_inertia[1] * c1 ** 2 + inv_inertia[2] * c2 ** 2


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def car_pre_tick(pos, rot, vel, ang_vel, controls, wheel_conn, wheel_rest, wheel_radius, wheel_ray_len,
                 wheel_is_front, inv_inertia, three_wheel, car_arena, active, ball_pos, ball_radius, cs, mut, dt):
    """Advance every active, non-demoed car's model by one tick: writes ``vel``/``ang_vel`` in place.

    ``pos``/``vel``/``ang_vel`` are (N, 3), ``rot`` is (N, 3, 3) with columns forward/right/up,
    ``controls`` is (N, 8): throttle, steer, pitch, yaw, roll, jump, boost, handbrake; ``mut`` holds each arena's
    ``MutatorConfig.as_row()``.
    The order follows RocketSim's car update: wheel impulses are computed from the state at the start
    of the tick with last tick's steering and friction factors, then inputs act, then impulses apply.

    Returns how many cars' velocities must not be written back to PyBullet (inactive or demolished ones).
    """
    # Scratch reused by every car (reset per car where the model relies on zeros): fresh small arrays per car
    # and wheel were most of this kernel's time.
    fwd, right, up, down = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    v0, w0, v, w = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    hit = np.zeros(4, dtype=np.bool_)
    hit_world = np.zeros(4, dtype=np.bool_)
    hit_t = np.zeros(4)
    hit_n = np.zeros((4, 3))
    hard = np.zeros((4, 3))
    susp_impulse = np.zeros((4, 3))
    fric_impulse = np.zeros((4, 3))
    fric_rel = np.zeros((4, 3))
    rel, v_cp, axle, f_dir, cross = np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    n_unwritable = 0
    for i in range(pos.shape[0]):
        if not active[i] or cs[i, CS_IS_DEMOED] != 0.0:
            n_unwritable += 1
        if not active[i] or cs[i, CS_IS_DEMOED] > 0.5:
            continue
        R = rot[i]
        for j in range(3):
            fwd[j], right[j], up[j] = R[j, 0], R[j, 1], R[j, 2]
            down[j] = -up[j]
        p = pos[i]
        v0[:] = vel[i]
        w0[:] = ang_vel[i]
        v[:] = v0
        w[:] = w0
        throttle, steer = controls[i, 0], controls[i, 1]
        pitch_in, yaw_in, roll_in = controls[i, 2], controls[i, 3], controls[i, 4]
        jump = controls[i, 5] > 0.5
        boost_btn = controls[i, 6] > 0.5
        handbrake = controls[i, 7] > 0.5
        jump_pressed = jump and cs[i, CS_LAST_JUMP] < 0.5
        inv_i = inv_inertia[i]
        m = mut[car_arena[i]]

        # ---- wheel rays against the arena (analytically) and this arena's ball
        bpos = ball_pos[car_arena[i]]
        hit[:] = False
        hit_world[:] = False
        hit_t[:] = 0.0
        hit_n[:] = 0.0
        hard[:] = 0.0
        for k in range(4):
            c = wheel_conn[i, k]
            hp = hard[k]
            for j in range(3):
                hp[j] = p[j] + (R[j, 0] * c[0] + R[j, 1] * c[1] + R[j, 2] * c[2])
            ok, t, nx, ny, nz = arena_raycast(hp[0], hp[1], hp[2], down[0], down[1], down[2], wheel_ray_len[i, k])
            tb = _ray_sphere(hp, down, bpos, ball_radius)
            if tb >= 0.0 and tb <= wheel_ray_len[i, k] and (not ok or tb < t):
                for j in range(3):
                    rel[j] = hp[j] + down[j] * tb - bpos[j]
                norm = np.sqrt(_dot(rel, rel))
                for j in range(3):
                    hit_n[k, j] = rel[j] / norm
                hit_t[k] = tb
                hit[k] = True
            elif ok:
                hit_n[k, 0], hit_n[k, 1], hit_n[k, 2] = nx, ny, nz
                hit_t[k] = t
                hit[k] = True
                hit_world[k] = True
        num_contact = 0
        num_world = 0
        for k in range(4):
            cs[i, CS_WHEEL_0 + k] = 1.0 if hit[k] else 0.0
            num_contact += hit[k]
            num_world += hit_world[k]
        on_ground = num_contact >= C.WHEELS_FOR_ON_GROUND
        cs[i, CS_NUM_WHEELS] = num_contact
        cs[i, CS_ON_GROUND] = 1.0 if on_ground else 0.0
        cs[i, CS_WORLD_CONTACT] = 1.0 if num_world > 0 else 0.0

        # ---- suspension impulses, from the start-of-tick velocity
        susp_impulse[:] = 0.0
        for k in range(4):
            if not hit[k]:
                continue
            n = hit_n[k]
            for j in range(3):
                rel[j] = hard[k, j] + down[j] * hit_t[k] - p[j]
            rest = wheel_rest[i, k]
            susp_len = min(max(hit_t[k] - wheel_radius[i, k], rest - C.SUSPENSION_MAX_TRAVEL),
                           rest + C.SUSPENSION_MAX_TRAVEL)
            denom = _dot(n, down)
            _set_cross(w0, rel, cross)
            for j in range(3):
                v_cp[j] = v0[j] + cross[j]
            if denom >= 0.1 or denom > -1e-3:
                rel_vel = 0.0
                clipped_inv = 10.0
            else:
                clipped_inv = -1.0 / denom
                rel_vel = _dot(n, v_cp) * clipped_inv
            scale = C.SUSPENSION_FORCE_SCALE_FRONT if wheel_is_front[i, k] else C.SUSPENSION_FORCE_SCALE_BACK
            damping = C.SUSPENSION_DAMP_COMPRESSION if rel_vel < 0.0 else C.SUSPENSION_DAMP_RELAXATION
            force = (C.SUSPENSION_STIFFNESS * (rest - susp_len) * clipped_inv - damping * rel_vel) * scale
            if force <= 0.0:
                continue  # the suspension never pulls
            # Hard stop: an inelastic push-back once the wheel is near the end of its short soft travel.
            gap = hit_t[k] - (wheel_ray_len[i, k] - wheel_radius[i, k])
            m_eff = 1.0 / _inv_mass_along(R, inv_i, rel, n)
            push = max(m_eff * (-0.2 * gap / dt - _dot(n, v_cp)), 0.0) * (1.0 / 1.5) / 4.0
            amount = force * dt + push
            for j in range(3):
                susp_impulse[k, j] = n[j] * amount

        # ---- tyre impulses, with last tick's steering, engine, brake and friction factors
        fric_impulse[:] = 0.0
        fric_rel[:] = 0.0
        last_angle = cs[i, CS_STEER_ANGLE]
        cos_l, sin_l = np.cos(last_angle), np.sin(last_angle)
        for k in range(4):
            if not hit[k]:
                continue
            n = hit_n[k]
            for j in range(3):
                rel[j] = hard[k, j] + down[j] * hit_t[k] - p[j]
            along_up = _dot(rel, up)
            for j in range(3):  # applied in the centre-of-mass plane: no pitch from braking
                fric_rel[k, j] = rel[j] - up[j] * along_up
            if wheel_is_front[i, k]:
                for j in range(3):
                    axle[j] = right[j] * cos_l - fwd[j] * sin_l
            else:
                axle[:] = right
            along_n = _dot(axle, n)
            for j in range(3):
                axle[j] = axle[j] - n[j] * along_n
            a_len = np.sqrt(_dot(axle, axle))
            if a_len < 1e-9:
                continue
            for j in range(3):
                axle[j] /= a_len
            _set_cross(axle, n, f_dir)
            _set_cross(w0, rel, cross)
            for j in range(3):
                v_cp[j] = v0[j] + cross[j]
            m_lat = 1.0 / _inv_mass_along(R, inv_i, rel, axle)
            side = -0.2 * _dot(v_cp, axle) * m_lat
            engine = cs[i, CS_ENGINE]
            if engine != 0.0:
                rolling = engine
            elif cs[i, CS_BRAKE] != 0.0:
                b = cs[i, CS_BRAKE]
                rolling = min(max(-_dot(v_cp, f_dir) * C.BRAKE_SLIP_SCALE, -b), b)
            else:
                rolling = 0.0
            long_amount = rolling * cs[i, CS_LONG_FRICTION_0 + k]
            lat_amount = side * cs[i, CS_LAT_FRICTION_0 + k]
            for j in range(3):
                fric_impulse[k, j] = (f_dir[j] * long_amount + axle[j] * lat_amount) * (C.CAR_MASS / 3.0) * dt

        # ---- this tick's wheel set-up: throttle, brake, steering, friction factors; sticky force
        hb = cs[i, CS_HANDBRAKE]
        hb = hb + C.POWERSLIDE_RISE_RATE * dt if handbrake else hb - C.POWERSLIDE_FALL_RATE * dt
        hb = min(max(hb, 0.0), 1.0)
        cs[i, CS_HANDBRAKE] = hb
        v_fwd = _dot(v0, fwd)
        abs_v_fwd = abs(v_fwd)
        real_throttle = 1.0 if (boost_btn and cs[i, CS_BOOST] > 0.0) else throttle
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
        cs[i, CS_ENGINE] = engine_throttle * C.THROTTLE_TORQUE_AMOUNT * 3.0 * drive_scale
        cs[i, CS_BRAKE] = brake * C.BRAKE_ACCEL / 4.0 * 3.0
        angle = interp(_STEER_CURVE_3W if three_wheel[i] else _STEER_CURVE, abs_v_fwd)
        if hb > 0.0:
            angle += (interp(_POWERSLIDE_CURVE, abs_v_fwd) - angle) * hb
        cs[i, CS_STEER_ANGLE] = angle * steer
        for k in range(4):
            if not hit[k]:
                continue
            n = hit_n[k]
            if wheel_is_front[i, k]:
                for j in range(3):
                    axle[j] = right[j] * cos_l - fwd[j] * sin_l
            else:
                axle[:] = right
            _set_cross(axle, n, f_dir)  # the wheel's rolling direction
            for j in range(3):
                rel[j] = hard[k, j] - p[j]
            _set_cross(w0, rel, cross)
            for j in range(3):
                v_cp[j] = v0[j] + cross[j]  # the velocity at the wheel's hard point
            lat_speed = abs(_dot(v_cp, axle))
            slip = 0.0
            if lat_speed > 5.0:
                slip = lat_speed / (abs(_dot(v_cp, f_dir)) + lat_speed)
            lat_fric = interp(_LAT_CURVE_3W if three_wheel[i] else _LAT_CURVE, slip)
            long_fric = 1.0
            if hb > 0.0:
                lat_fric *= (C.HANDBRAKE_LAT_FRICTION_FACTOR - 1.0) * hb + 1.0
                long_fric *= (interp(_HB_LONG_CURVE, slip) - 1.0) * hb + 1.0
            if real_throttle == 0.0:
                non_sticky = interp(_NON_STICKY_CURVE, n[2])
                lat_fric *= non_sticky
                long_fric *= non_sticky
            cs[i, CS_LAT_FRICTION_0 + k] = lat_fric
            cs[i, CS_LONG_FRICTION_0 + k] = long_fric
        if num_world > 0:
            n_avg = np.zeros(3)
            for k in range(4):
                if hit[k]:
                    n_avg += hit_n[k]
            n_avg /= np.sqrt(_dot(n_avg, n_avg))
            sticky = 0.0 if three_wheel[i] else C.STICKY_FORCE_GROUND
            if real_throttle != 0.0 or abs_v_fwd > C.STOPPING_FORWARD_VEL:
                sticky += C.STICKY_FORCE_FULL_STICK_EXTRA * (1.0 - abs(n_avg[2]))
            v -= n_avg * (sticky * _GRAVITY * dt)

        # ---- air control and flip torque: only with no wheel down
        if num_contact == 0:
            wl = _mtv(R, w)
            alpha = np.zeros(3)
            air_control = True
            flip_time = cs[i, CS_FLIP_TIME]
            if cs[i, CS_HAS_FLIPPED] > 0.5 and flip_time < C.FLIP_TORQUE_TIME:
                tx = cs[i, CS_FLIP_TORQUE_X]
                ty = cs[i, CS_FLIP_TORQUE_Y]
                if tx != 0.0 or ty != 0.0:
                    air_control = False
                    if ty != 0.0 and pitch_in != 0.0 and (ty > 0.0) == (pitch_in > 0.0):
                        ty = 0.0  # flip cancel: pulling against the flip stops its pitch and frees air control
                        air_control = True
                    alpha[0] += C.FLIP_TORQUE_X * tx
                    alpha[1] += C.FLIP_TORQUE_Y * ty
            air_control = air_control and cs[i, CS_IS_AUTOFLIPPING] < 0.5
            if air_control:
                pitch_scale = 1.0
                if cs[i, CS_HAS_FLIPPED] > 0.5 and flip_time < C.FLIP_TORQUE_TIME + C.FLIP_PITCHLOCK_EXTRA_TIME:
                    pitch_scale = 0.0
                up_p = pitch_in * pitch_scale
                alpha[0] -= _AIR_TORQUE[2] * roll_in + _AIR_DAMPING[2] * wl[0]
                alpha[1] -= _AIR_TORQUE[0] * up_p + _AIR_DAMPING[0] * wl[1] * (1.0 - abs(up_p))
                alpha[2] += _AIR_TORQUE[1] * yaw_in - _AIR_DAMPING[1] * wl[2] * (1.0 - abs(yaw_in))
            w += _mv(R, alpha) * dt
            v += fwd * (C.THROTTLE_AIR_ACCEL * throttle * dt)

        # ---- first jump: an impulse on the press, then a hold force for 0.025 to 0.2 s
        if on_ground and cs[i, CS_IS_JUMPING] < 0.5:
            if not (cs[i, CS_HAS_JUMPED] > 0.5
                    and cs[i, CS_JUMP_TIME] < C.JUMP_MIN_TIME + C.JUMP_RESET_MIN_TIME):
                cs[i, CS_HAS_JUMPED] = 0.0
        if cs[i, CS_IS_JUMPING] > 0.5:
            # 1e-6: after 24 ticks the float sum of 1/120 lands a hair under 0.2; the game stops at 24 ticks.
            still = cs[i, CS_JUMP_TIME] < C.JUMP_MIN_TIME or (jump and cs[i, CS_JUMP_TIME] + 1e-6 < C.JUMP_MAX_TIME)
            cs[i, CS_IS_JUMPING] = 1.0 if still else 0.0
        elif on_ground and jump_pressed:
            cs[i, CS_IS_JUMPING] = 1.0
            cs[i, CS_JUMP_TIME] = 0.0
            v += up * m[MUT_JUMP_IMMEDIATE_VEL]
        if cs[i, CS_IS_JUMPING] > 0.5:
            cs[i, CS_HAS_JUMPED] = 1.0
            accel = m[MUT_JUMP_ACCEL]
            if cs[i, CS_JUMP_TIME] < C.JUMP_MIN_TIME:
                accel *= C.JUMP_PRE_MIN_ACCEL_SCALE
            v += up * (accel * dt)
            cs[i, CS_JUMP_TIME] += dt

        # ---- auto-flip: jump while lying on the roof rights the car
        if jump_pressed and cs[i, CS_BODY_CONTACT] > 0.5 and cs[i, CS_BODY_NORMAL_X + 2] > C.AUTOFLIP_NORM_Z_THRESH:
            roll_angle = np.arctan2(-right[2], up[2])
            if abs(roll_angle) > C.AUTOFLIP_ROLL_THRESH:
                cs[i, CS_AUTOFLIP_TIMER] = C.AUTOFLIP_TIME * abs(roll_angle) / np.pi
                cs[i, CS_AUTOFLIP_SCALE] = 1.0 if roll_angle > 0.0 else -1.0
                cs[i, CS_IS_AUTOFLIPPING] = 1.0
                v -= up * C.AUTOFLIP_IMPULSE
        if cs[i, CS_IS_AUTOFLIPPING] > 0.5:
            if cs[i, CS_AUTOFLIP_TIMER] <= 0.0:
                cs[i, CS_IS_AUTOFLIPPING] = 0.0
                cs[i, CS_AUTOFLIP_TIMER] = 0.0
            else:
                w += fwd * (C.AUTOFLIP_TORQUE * cs[i, CS_AUTOFLIP_SCALE] * dt)
                cs[i, CS_AUTOFLIP_TIMER] -= dt

        # ---- double jump or flip
        if on_ground:
            cs[i, CS_HAS_DOUBLE_JUMPED] = 0.0
            cs[i, CS_HAS_FLIPPED] = 0.0
            cs[i, CS_IS_FLIPPING] = 0.0
            cs[i, CS_AIR_TIME_SINCE_JUMP] = 0.0
        else:
            if cs[i, CS_HAS_JUMPED] > 0.5 and cs[i, CS_IS_JUMPING] < 0.5:
                cs[i, CS_AIR_TIME_SINCE_JUMP] += dt
            else:
                cs[i, CS_AIR_TIME_SINCE_JUMP] = 0.0
            if jump_pressed and cs[i, CS_AIR_TIME_SINCE_JUMP] < C.DOUBLEJUMP_MAX_DELAY \
                    and cs[i, CS_IS_AUTOFLIPPING] < 0.5:
                unused = cs[i, CS_HAS_DOUBLE_JUMPED] < 0.5 and cs[i, CS_HAS_FLIPPED] < 0.5
                if max(abs(yaw_in), abs(pitch_in), abs(roll_in)) >= m[MUT_DODGE_DEADZONE]:
                    if unused or m[MUT_UNLIMITED_FLIPS] != 0.0:
                        _start_flip(i, cs, v, fwd, v_fwd, pitch_in, yaw_in, roll_in)
                elif unused or m[MUT_UNLIMITED_DOUBLE_JUMPS] != 0.0:
                    v += up * C.JUMP_IMMEDIATE_VEL  # RocketSim's double jump ignores the mutator's jump impulse
                    cs[i, CS_HAS_DOUBLE_JUMPED] = 1.0
        if cs[i, CS_HAS_FLIPPED] > 0.5:
            cs[i, CS_FLIP_TIME] += dt
            ft = cs[i, CS_FLIP_TIME]
            cs[i, CS_IS_FLIPPING] = 1.0 if ft <= C.FLIP_TORQUE_TIME else 0.0
            if ft <= C.FLIP_TORQUE_TIME and ft >= C.FLIP_Z_DAMP_START and (v[2] < 0.0 or ft < C.FLIP_Z_DAMP_END):
                v[2] *= (1.0 - C.FLIP_Z_DAMP_120) ** (dt * 120.0)

        # ---- auto-roll: driving with some wheels (or the body) on a surface turns the car onto it
        body_contact = cs[i, CS_BODY_CONTACT] > 0.5
        if throttle != 0.0 and ((0 < num_contact < 4) or body_contact):
            if num_contact > 0:
                g_up = np.zeros(3)
                for k in range(4):
                    if hit[k]:
                        g_up += hit_n[k]
                g_up /= np.sqrt(_dot(g_up, g_up))
            else:
                g_up = cs[i, CS_BODY_NORMAL_X:CS_BODY_NORMAL_X + 3].copy()
            cross_right = _cross(g_up, fwd)
            cross_fwd = _cross(-g_up, cross_right)
            right_factor = 1.0 - min(max(_dot(right, cross_right), 0.0), 1.0)
            fwd_factor = 1.0 - min(max(_dot(fwd, cross_fwd), 0.0), 1.0)
            torque_right = fwd * (-1.0 if _dot(right, g_up) >= 0.0 else 1.0) * right_factor
            torque_fwd = right * (1.0 if _dot(fwd, g_up) >= 0.0 else -1.0) * fwd_factor
            v -= g_up * (C.AUTOROLL_FORCE * dt)
            w += (torque_fwd + torque_right) * (C.AUTOROLL_TORQUE * dt)
        cs[i, CS_BODY_CONTACT] = 0.0

        # ---- the wheel impulses computed at the start of the tick
        for k in range(4):
            if hit[k]:
                for j in range(3):
                    rel[j] = hard[k, j] + down[j] * hit_t[k] - p[j]
                _apply_impulse(R, inv_i, v, w, rel, susp_impulse[k])
        for k in range(4):
            if hit[k]:
                _apply_impulse(R, inv_i, v, w, fric_rel[k], fric_impulse[k])

        # ---- boost: once started it lasts at least 0.1 s
        t_boost = cs[i, CS_BOOSTING_TIME]
        if t_boost > 0.0:
            t_boost = 0.0 if (not boost_btn and t_boost >= C.BOOST_MIN_TIME) else t_boost + dt
        elif boost_btn:
            t_boost = dt
        cs[i, CS_BOOSTING_TIME] = t_boost
        boosting = cs[i, CS_BOOST] > 0.0 and t_boost > 0.0
        if boosting:
            cs[i, CS_BOOST] = max(cs[i, CS_BOOST] - m[MUT_BOOST_USED_PER_SECOND] * dt, 0.0)
            v += fwd * ((m[MUT_BOOST_ACCEL_GROUND] if on_ground else m[MUT_BOOST_ACCEL_AIR]) * dt)
        cs[i, CS_IS_BOOSTING] = 1.0 if boosting else 0.0

        cs[i, CS_LAST_JUMP] = 1.0 if jump else 0.0
        vel[i] = v
        ang_vel[i] = w
    return n_unwritable


@njit(cache=True)
def _start_flip(i, cs, v, fwd, v_fwd, pitch_in, yaw_in, roll_in):
    cs[i, CS_HAS_FLIPPED] = 1.0
    cs[i, CS_IS_FLIPPING] = 1.0
    cs[i, CS_FLIP_TIME] = 0.0
    dx, dy = -pitch_in, yaw_in + roll_in
    if abs(dx) < 0.1 and abs(dy) < 0.1:  # a stall: no impulse, no torque, air control stays on
        cs[i, CS_FLIP_TORQUE_X] = 0.0
        cs[i, CS_FLIP_TORQUE_Y] = 0.0
        return
    norm = np.sqrt(dx * dx + dy * dy)
    dx /= norm
    dy /= norm
    cs[i, CS_FLIP_TORQUE_X] = -dy
    cs[i, CS_FLIP_TORQUE_Y] = dx
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
    fh_len = np.sqrt(_dot(fh, fh))
    if fh_len < 1e-9:
        return
    fh /= fh_len
    rh = np.array([-fh[1], fh[0], 0.0])  # world up x forward: the car's right in the horizontal plane
    v += fh * imp_x + rh * imp_y


@njit(cache=True)
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
        speed = np.sqrt(_dot(vel[i], vel[i]))
        if speed > C.CAR_MAX_SPEED:
            vel[i] *= C.CAR_MAX_SPEED / speed
            speed = C.CAR_MAX_SPEED
        ang = np.sqrt(_dot(ang_vel[i], ang_vel[i]))
        if ang > C.CAR_MAX_ANG_SPEED:
            ang_vel[i] *= C.CAR_MAX_ANG_SPEED / ang
        if cs[i, CS_IS_SUPERSONIC] > 0.5 and cs[i, CS_SUPERSONIC_TIME] < C.SUPERSONIC_MAINTAIN_MAX_TIME:
            supersonic = speed >= C.SUPERSONIC_MAINTAIN_MIN_SPEED
        else:
            supersonic = speed >= C.SUPERSONIC_START_SPEED
        if supersonic:
            cs[i, CS_SUPERSONIC_TIME] = cs[i, CS_SUPERSONIC_TIME] + dt if cs[i, CS_IS_SUPERSONIC] > 0.5 else 0.0
        else:
            cs[i, CS_SUPERSONIC_TIME] = 0.0
        cs[i, CS_IS_SUPERSONIC] = 1.0 if supersonic else 0.0
    return respawn_due


@njit(cache=True)
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
