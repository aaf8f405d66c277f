"""The ball's whole tick, compiled: drag, its contacts with the arena and the cars, Rocket League's extra push,
integration and caps. Rocket League units (uu, uu/s, rad/s, s).

The ball does not live in PyBullet. Its contacts are solved the way RocketSim's patched Bullet solves them, which
PyBullet cannot be made to do (no per-pair materials, a velocity bias on separated contacts, one contact threshold
for everything):

- **Contacts at the start of the tick.** A contact exists when the gap is at most Bullet's contact-breaking
  distance (measured in RocketSim: ``BALL_WORLD_CONTACT_GAP`` against the arena, ``CAR_BALL_CONTACT_GAP`` against a
  car). The arena is ``arena_geometry``'s exact surface (``surface_contacts``: every surface the ball reaches, none
  buried inside another piece of the arena) and a minigame's static boxes; a car is its hitbox, a box whose edges
  are rounded by Bullet's 2 uu collision margin.
- **Ball-arena: one merged contact** (RocketSim's "special" contact): the mean normal of everything the ball
  touches, restitution 0.6 from the approach speed before gravity (none under 10 uu/s), friction 0.35, no
  position correction.
- **Car-ball**: restitution 0, friction 2.0, split-impulse position correction of 0.8 of the overlap (positions
  only, no velocity). Separated contacts get no velocity bias (RocketSim's patch).
- **One friction direction** per contact, along the sliding velocity at setup (Bullet's default solver mode), and
  10 sequential-impulse iterations: every normal row, then every friction row clamped by its normal impulse.
- Velocities in the solve include this tick's gravity, as Bullet's solver bodies do.
- **The extra push** (``Ball::_OnHit``) on each car contact, at most every other tick per car, from the velocities
  before the solve, added after integration (RocketSim's velocity cache).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import literally, njit

from . import constants as C
from .arena_shape import CLASSIC, GAME, shape_surface_contacts
from .mutators import MUT_BALL_DRAG, MUT_BALL_HIT_EXTRA_SCALE, MUT_BALL_MAX_SPEED
from .vec import mat_vec, vcross, vdot

BALL_WORLD_CONTACT_GAP = 1.905  # uu: RocketSim's ball touches the arena from this gap (bisected, 1e-6 uu)
CAR_BALL_CONTACT_GAP = 1.835    # uu: and a car's hitbox from this one
HITBOX_MARGIN = 2.0             # uu: Bullet's convex margin (0.04 in RocketSim's 50 uu units) rounds the box
SOLVER_ITERATIONS = 10
SPLIT_IMPULSE_ERP = 0.8         # RocketSim's erp2: the share of an overlap removed in one tick
RESTITUTION_MIN_SPEED = 10.0    # uu/s: Bullet's restitution threshold (0.2 in RocketSim's units)
BALL_INERTIA = 0.4 * C.BALL_MASS * C.BALL_RADIUS ** 2  # solid sphere, mass x uu^2
_HIT_CURVE = np.array(C.BALL_HIT_SCALE_CURVE)

# Columns of a contact row (one per contact; the world contact comes last in an arena's rows).
_N = 0          # 3: normal, from the car (or the arena) towards the ball
_RB = 3         # 3: lever arm on the ball (contact point - centre)
_RC = 6         # 3: lever arm on the car (contact point - centre of mass); unused for the arena
_T = 9          # 3: friction direction
_MN = 12        # effective mass along the normal
_MT = 13        # effective mass along the friction direction
_TARGET = 14    # the normal velocity the row aims for (restitution)
_JN = 15        # accumulated normal impulse
_JT = 16        # accumulated friction impulse
_MU = 17        # friction coefficient
_DEPTH = 18     # overlap (uu) to push apart, 0 for none
_JP = 19        # accumulated push impulse
_CAR = 20       # car row in the batch arrays; WORLD for the merged arena contact, WORLD_POINT for one arena point
WORLD = -1      # (velocity rows: RocketSim solves the merged contact; each point only pushes the overlap apart)
WORLD_POINT = -2
_ROW = 21


class BallArrays(NamedTuple):
    """Every arena's ball, by arena (uu, uu/s, rad/s)."""
    pos: np.ndarray         # (arenas, 3)
    vel: np.ndarray         # (arenas, 3)
    ang_vel: np.ndarray     # (arenas, 3)
    frozen: np.ndarray      # (arenas,) bool: hangs where it was placed until a touch


class CarBodies(NamedTuple):
    """What the ball meets of every car, by batch row: its pose, velocities, hitbox and extra-push memory."""
    pos: np.ndarray              # (cars, 3)
    rot: np.ndarray              # (cars, 3, 3)
    vel: np.ndarray              # (cars, 3)
    ang_vel: np.ndarray          # (cars, 3)
    arena: np.ndarray            # (cars,) int
    live: np.ndarray             # (cars,) bool: active and not demolished
    hitbox_half: np.ndarray      # (cars, 3)
    hitbox_offset: np.ndarray    # (cars, 3)
    inv_inertia: np.ndarray      # (cars, 3)
    last_extra_tick: np.ndarray  # (cars,) int: the last tick the car gave the extra push


class BallTouches(NamedTuple):
    """What ``ball_tick`` reports per car (by batch row), overwritten every tick."""
    touched: np.ndarray     # (cars,) bool
    point: np.ndarray       # (cars, 3) the contact point on the ball
    normal: np.ndarray      # (cars, 3) from the car towards the ball
    extra_vel: np.ndarray   # (cars, 3) the extra push given, zero if none
    car_push: np.ndarray    # (cars, 3) the car's position change of the overlap correction


@njit(cache=True, nogil=True)
def _world_inv_inertia(R, inv_local):
    """R diag(inv_local) R^T: a car's inverse inertia in world axes."""
    out = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            out[a, b] = R[a, 0] * inv_local[0] * R[b, 0] + R[a, 1] * inv_local[1] * R[b, 1] \
                + R[a, 2] * inv_local[2] * R[b, 2]
    return out


@njit(cache=True, nogil=True)
def _box_contact(ball, car_pos, R, offset, half):
    """Bullet's sphere-box test against a car's hitbox: (gap, unit normal box -> ball, point on the box), world."""
    rel = ball - car_pos
    local = np.array([R[0, 0] * rel[0] + R[1, 0] * rel[1] + R[2, 0] * rel[2] - offset[0],
                      R[0, 1] * rel[0] + R[1, 1] * rel[1] + R[2, 1] * rel[2] - offset[1],
                      R[0, 2] * rel[0] + R[1, 2] * rel[1] + R[2, 2] * rel[2] - offset[2]])
    inner = half - HITBOX_MARGIN
    closest = np.minimum(np.maximum(local, -inner), inner)
    d = local - closest
    dist = np.sqrt(vdot(d, d))
    if dist > 1e-9:
        n_local = d / dist
        gap = dist - (C.BALL_RADIUS + HITBOX_MARGIN)
    else:  # the centre is inside the box: out through the nearest face
        axis, depth = 0, inner[0] - abs(local[0])
        for a in range(1, 3):
            if inner[a] - abs(local[a]) < depth:
                axis, depth = a, inner[a] - abs(local[a])
        n_local = np.zeros(3)
        n_local[axis] = 1.0 if local[axis] >= 0.0 else -1.0
        closest[axis] = inner[axis] * n_local[axis]
        gap = -depth - (C.BALL_RADIUS + HITBOX_MARGIN)
    point_local = closest + n_local * HITBOX_MARGIN + offset
    normal = np.empty(3)
    point = np.empty(3)
    for j in range(3):
        normal[j] = R[j, 0] * n_local[0] + R[j, 1] * n_local[1] + R[j, 2] * n_local[2]
        point[j] = car_pos[j] + R[j, 0] * point_local[0] + R[j, 1] * point_local[1] + R[j, 2] * point_local[2]
    return gap, normal, point


@njit(cache=True, nogil=True)
def _static_box_sdf(p, box):
    """Distance from ``p`` to an axis-aligned box (centre box[1:4], half extents box[4:7]), positive outside, and
    its unit gradient."""
    q = np.empty(3)
    s = np.empty(3)
    for j in range(3):
        d = p[j] - box[1 + j]
        s[j] = 1.0 if d >= 0.0 else -1.0
        q[j] = abs(d) - box[4 + j]
    out = np.maximum(q, 0.0)
    outside = np.sqrt(vdot(out, out))
    if outside > 0.0:
        return outside, out * s / outside
    a = 0
    for j in range(1, 3):
        if q[j] > q[a]:
            a = j
    n = np.zeros(3)
    n[a] = s[a]
    return q[a], n


@njit(cache=True, nogil=True)
def _inv_mass(n, rb, rc, has_car, inv_ic, car_inv_mass):
    """1 / effective mass of a unit impulse along ``n`` at the levers ``rb`` (ball) and ``rc`` (car)."""
    ab = vcross(rb, n)
    k = 1.0 / C.BALL_MASS + vdot(ab, ab) / BALL_INERTIA
    if has_car:
        ac = vcross(rc, n)
        iac = mat_vec(inv_ic, ac)
        k += car_inv_mass + vdot(ac, iac)
    return k


@njit(cache=True, nogil=True)
def _rel_vel(d, rb, rc, has_car, vb, wb, vc, wc):
    """Velocity of the ball's contact point relative to the car's (or the arena's) along ``d``."""
    v = vdot(d, vb) + vdot(d, vcross(wb, rb))
    if has_car:
        v -= vdot(d, vc) + vdot(d, vcross(wc, rc))
    return v


@njit(cache=True, nogil=True)
def _apply(d, j, rb, rc, has_car, vb, wb, vc, wc, inv_ic):
    """Impulse ``j`` along ``d`` on the ball, and its opposite on the car."""
    ab = vcross(rb, d)
    for a in range(3):
        vb[a] += d[a] * j / C.BALL_MASS
        wb[a] += ab[a] * j / BALL_INERTIA
    if has_car:
        iac = mat_vec(inv_ic, vcross(rc, d))
        for a in range(3):
            vc[a] -= d[a] * j / C.CAR_MASS
            wc[a] -= iac[a] * j


@njit(cache=True, nogil=True)
def _friction_direction(n, rel):
    """The sliding direction (relative velocity less its normal part), or any direction along the surface."""
    t = rel - n * vdot(rel, n)
    length2 = vdot(t, t)
    if length2 > 1.1920929e-07:  # Bullet's SIMD_EPSILON
        return t / np.sqrt(length2)
    # btPlaneSpace1's first axis
    if abs(n[2]) > 0.7071067811865476:
        a = n[1] * n[1] + n[2] * n[2]
        k = 1.0 / np.sqrt(a)
        return np.array([0.0, -n[2] * k, n[1] * k])
    a = n[0] * n[0] + n[1] * n[1]
    k = 1.0 / np.sqrt(a)
    return np.array([-n[1] * k, n[0] * k, 0.0])


@njit(cache=True, nogil=True)
def ball_tick(shape, balls, cars, boxes, mut, gravity_z, tick, dt, touches):
    """One tick of every arena's ball (see the module docstring) in an arena of ``shape`` (``arena_shape``'s
    integer, compiled per value: call ``ball_tick_classic`` or ``ball_tick_game``); writes ``balls`` (``BallArrays``)
    in place and changes the velocities of the cars (``CarBodies``) that touch a ball. Per car it reports
    ``touches`` (``BallTouches``). ``boxes`` are the static boxes' rows (arena, centre, half extents).

    The cars' ``vel`` holds their velocities before this tick's gravity (PyBullet adds it during its step); the
    solve adds it and takes it off again. Returns the number of touching cars."""
    literally(shape)
    ball_pos, ball_vel, ball_ang_vel, frozen = balls
    (car_pos, car_rot, car_vel, car_ang_vel, car_arena, car_live, hitbox_half, hitbox_offset, car_inv_inertia,
     last_extra_tick) = cars
    touched, touch_point, touch_normal, extra_vel, car_push = touches
    n_cars = car_pos.shape[0]
    n_touch = 0
    rows = np.zeros((n_cars + 10 + boxes.shape[0], _ROW))
    arena_touches = np.zeros(ball_pos.shape[0], dtype=np.int64)
    surface = np.zeros((8, 4))
    for i in range(n_cars):
        touched[i] = False
        car_push[i, :] = 0.0
        extra_vel[i, :] = 0.0
        if not car_live[i]:
            continue
        k = car_arena[i]
        gap, normal, point = _box_contact(ball_pos[k], car_pos[i], car_rot[i], hitbox_offset[i], hitbox_half[i])
        if gap <= CAR_BALL_CONTACT_GAP:
            touched[i] = True
            n_touch += 1
            arena_touches[k] += 1
            touch_normal[i] = normal
            touch_point[i] = ball_pos[k] - normal * C.BALL_RADIUS
            car_push[i, 0] = gap  # parked here until the arena's solve
    grav = np.array([0.0, 0.0, gravity_z * dt])
    for k in range(ball_pos.shape[0]):
        m = mut[k]
        if frozen[k]:
            if arena_touches[k] == 0:
                continue
            frozen[k] = False  # a touch wakes a ball hanging where it was placed
        vb = ball_vel[k] * (1.0 - m[MUT_BALL_DRAG]) ** dt  # Bullet's damping, before contacts
        wb = ball_ang_vel[k].copy()
        n_rows = 0
        cache = np.zeros(3)
        # ---- car contacts
        for i in range(n_cars if arena_touches[k] > 0 else 0):
            if not touched[i] or car_arena[i] != k:
                continue
            row = rows[n_rows]
            row[:] = 0.0
            n = touch_normal[i]
            gap = car_push[i, 0]
            car_push[i, 0] = 0.0
            _, _, point = _box_contact(ball_pos[k], car_pos[i], car_rot[i], hitbox_offset[i], hitbox_half[i])
            row[_N:_N + 3] = n
            row[_RB:_RB + 3] = -n * C.BALL_RADIUS
            row[_RC:_RC + 3] = point - car_pos[i]
            row[_MU] = C.CAR_BALL_FRICTION
            row[_TARGET] = C.CAR_BALL_RESTITUTION  # 0: no bounce-back velocity to aim for
            row[_DEPTH] = -gap if gap < 0.0 else 0.0
            row[_CAR] = i
            n_rows += 1
            extra = _extra_hit(ball_pos[k], vb, car_pos[i], car_vel[i], car_rot[i], last_extra_tick, i, tick,
                               m[MUT_BALL_HIT_EXTRA_SCALE])
            extra_vel[i] = extra
            cache += extra
        # ---- the arena (and static boxes): one merged contact for the velocities, and each point's overlap
        merged = n_rows
        n_points = shape_surface_contacts(shape, ball_pos[k, 0], ball_pos[k, 1], ball_pos[k, 2],
                                          C.BALL_RADIUS + BALL_WORLD_CONTACT_GAP, surface)
        for c in range(n_points):
            _world_point(rows[merged + 1 + c], surface[c, 1:4], surface[c, 0] - C.BALL_RADIUS)
        for b in range(boxes.shape[0]):
            if int(boxes[b, 0]) == k:
                db, nb = _static_box_sdf(ball_pos[k], boxes[b])
                if db - C.BALL_RADIUS <= BALL_WORLD_CONTACT_GAP:
                    _world_point(rows[merged + 1 + n_points], nb, db - C.BALL_RADIUS)
                    n_points += 1
        if n_points > 0:
            n = np.zeros(3)
            for r in range(merged + 1, merged + 1 + n_points):
                n += rows[r, _N:_N + 3]
            n /= n_points  # RocketSim averages the normals without normalising them
            row = rows[merged]
            row[:] = 0.0
            row[_N:_N + 3] = n
            row[_RB:_RB + 3] = -n * C.BALL_RADIUS
            row[_MU] = C.BALL_FRICTION
            approach = vdot(n, vb) + vdot(n, vcross(wb, row[_RB:_RB + 3]))  # before gravity, as Bullet's restitution
            row[_TARGET] = max(C.BALL_RESTITUTION * -approach, 0.0) if abs(approach) >= RESTITUTION_MIN_SPEED else 0.0
            row[_CAR] = WORLD
            n_rows = merged + 1 + n_points
        vb += grav
        if n_rows > 0:
            _solve(rows, n_rows, vb, wb, car_vel, car_ang_vel, car_rot, car_inv_inertia, grav, dt)
        pos = ball_pos[k]
        for j in range(3):
            pos[j] += vb[j] * dt
        for r in range(n_rows):  # the overlap correction moves positions only
            row = rows[r]
            jp = row[_JP]
            if jp > 0.0:
                i = int(row[_CAR])
                for j in range(3):
                    pos[j] += row[_N + j] * jp / C.BALL_MASS * dt
                    if i >= 0:
                        car_push[i, j] = -row[_N + j] * jp / C.CAR_MASS * dt
        vb += cache
        speed = np.sqrt(vdot(vb, vb))
        if speed > m[MUT_BALL_MAX_SPEED]:
            vb *= m[MUT_BALL_MAX_SPEED] / speed
        spin = np.sqrt(vdot(wb, wb))
        if spin > C.BALL_MAX_ANG_SPEED:
            wb *= C.BALL_MAX_ANG_SPEED / spin
        ball_vel[k] = vb
        ball_ang_vel[k] = wb
    return n_touch


# The entry points take plain tuples in the records' field order and make the records inside: numba types a plain
# tuple argument in compiled code, a NamedTuple in Python code, which cost microseconds a call.
@njit(cache=True, nogil=True)
def ball_tick_classic(balls, cars, boxes, mut, gravity_z, tick, dt, touches):
    """``ball_tick`` in the "classic" arena; ``balls``, ``cars``, ``touches``: tuples of ``BallArrays``',
    ``CarBodies``' and ``BallTouches``' fields."""
    return ball_tick(CLASSIC, BallArrays(*balls), CarBodies(*cars), boxes, mut, gravity_z, tick, dt,
                     BallTouches(*touches))


@njit(cache=True, nogil=True)
def ball_tick_game(balls, cars, boxes, mut, gravity_z, tick, dt, touches):
    """``ball_tick`` in the "game" arena (arguments as ``ball_tick_classic``'s)."""
    return ball_tick(GAME, BallArrays(*balls), CarBodies(*cars), boxes, mut, gravity_z, tick, dt,
                     BallTouches(*touches))


@njit(cache=True, nogil=True)
def _world_point(row, normal, gap):
    """One point where the ball touches the arena: a row that only pushes an overlap apart."""
    row[:] = 0.0
    row[_N:_N + 3] = normal
    row[_RB:_RB + 3] = -normal * C.BALL_RADIUS
    row[_DEPTH] = -gap if gap < 0.0 else 0.0
    row[_CAR] = WORLD_POINT


@njit(cache=True, nogil=True)
def _extra_hit(ball_pos, ball_vel, car_pos, car_vel, R, last_extra_tick, i, tick, scale):
    """Rocket League's extra push of car ``i`` (``Ball::_OnHit``): at most once every other tick per car."""
    out = np.zeros(3)
    if not (tick > last_extra_tick[i] + 1 or last_extra_tick[i] > tick):
        return out
    last_extra_tick[i] = tick
    rel_pos = ball_pos - car_pos
    rel_vel = ball_vel - car_vel
    rel_speed = min(np.sqrt(vdot(rel_vel, rel_vel)), C.BALL_HIT_MAX_REL_SPEED)
    if rel_speed <= 0.0:
        return out
    hit_dir = np.array([rel_pos[0], rel_pos[1], rel_pos[2] * C.BALL_HIT_Z_SCALE])
    hit_dir /= np.sqrt(vdot(hit_dir, hit_dir))
    fwd = R[:, 0].copy()
    hit_dir -= fwd * ((1.0 - C.BALL_HIT_FORWARD_SCALE) * vdot(hit_dir, fwd))
    hit_dir /= np.sqrt(vdot(hit_dir, hit_dir))
    factor = _HIT_CURVE[_HIT_CURVE.shape[0] - 1, 1]
    for r in range(1, _HIT_CURVE.shape[0]):
        if rel_speed < _HIT_CURVE[r, 0]:
            x0, y0, x1, y1 = _HIT_CURVE[r - 1, 0], _HIT_CURVE[r - 1, 1], _HIT_CURVE[r, 0], _HIT_CURVE[r, 1]
            factor = y0 + (y1 - y0) * (rel_speed - x0) / (x1 - x0)
            break
    return hit_dir * rel_speed * factor * scale


@njit(cache=True, nogil=True)
def _solve(rows, n_rows, vb, wb, car_vel, car_ang_vel, car_rot, car_inv_inertia, grav, dt):
    """Sequential impulses over one ball's contact rows; ``vb``/``wb`` and the touching cars' velocities change."""
    inv_ic = np.zeros((n_rows, 3, 3))
    vcs = np.zeros((n_rows, 3))
    wcs = np.zeros((n_rows, 3))
    for r in range(n_rows):
        row = rows[r]
        i = int(row[_CAR])
        has_car = i >= 0
        row[_JN] = row[_JT] = row[_JP] = 0.0
        if i == WORLD_POINT:
            row[_MN] = C.BALL_MASS  # the lever is along the normal: no spin term
            continue
        if has_car:
            inv_ic[r] = _world_inv_inertia(car_rot[i], car_inv_inertia[i])
            vcs[r] = car_vel[i] + grav
            wcs[r] = car_ang_vel[i]
        n, rb, rc = row[_N:_N + 3], row[_RB:_RB + 3], row[_RC:_RC + 3]
        row[_MN] = 1.0 / _inv_mass(n, rb, rc, has_car, inv_ic[r], 1.0 / C.CAR_MASS)
        rel = vb + vcross(wb, rb)
        if has_car:
            rel = rel - vcs[r] - vcross(wcs[r], rc)
        t = _friction_direction(n, rel)
        row[_T:_T + 3] = t
        row[_MT] = 1.0 / _inv_mass(t, rb, rc, has_car, inv_ic[r], 1.0 / C.CAR_MASS)
    for _ in range(SOLVER_ITERATIONS):
        for r in range(n_rows):
            row = rows[r]
            if row[_CAR] == WORLD_POINT:
                continue
            has_car = row[_CAR] >= 0.0
            n, rb, rc = row[_N:_N + 3], row[_RB:_RB + 3], row[_RC:_RC + 3]
            vn = _rel_vel(n, rb, rc, has_car, vb, wb, vcs[r], wcs[r])
            old = row[_JN]
            row[_JN] = max(old + (row[_TARGET] - vn) * row[_MN], 0.0)
            _apply(n, row[_JN] - old, rb, rc, has_car, vb, wb, vcs[r], wcs[r], inv_ic[r])
        for r in range(n_rows):
            row = rows[r]
            limit = row[_MU] * row[_JN]
            if limit <= 0.0:  # no normal impulse (and the arena's points have none)
                continue
            has_car = row[_CAR] >= 0.0
            t, rb, rc = row[_T:_T + 3], row[_RB:_RB + 3], row[_RC:_RC + 3]
            vt = _rel_vel(t, rb, rc, has_car, vb, wb, vcs[r], wcs[r])
            old = row[_JT]
            row[_JT] = min(max(old - vt * row[_MT], -limit), limit)
            _apply(t, row[_JT] - old, rb, rc, has_car, vb, wb, vcs[r], wcs[r], inv_ic[r])
    # The overlap correction: impulses on push velocities only (no effect on the real ones).
    push_b = np.zeros(3)
    push_c = np.zeros((n_rows, 3))
    for _ in range(SOLVER_ITERATIONS):
        for r in range(n_rows):
            row = rows[r]
            if row[_DEPTH] <= 0.0:
                continue
            n = row[_N:_N + 3]
            vn = vdot(n, push_b) - vdot(n, push_c[r])  # the arena's points leave push_c at zero
            old = row[_JP]
            row[_JP] = max(old + (SPLIT_IMPULSE_ERP * row[_DEPTH] / dt - vn) * row[_MN], 0.0)
            dj = row[_JP] - old
            push_b += n * dj / C.BALL_MASS
            if row[_CAR] >= 0.0:
                push_c[r] -= n * dj / C.CAR_MASS
    for r in range(n_rows):
        i = int(rows[r, _CAR])
        if i >= 0:
            car_vel[i] = vcs[r] - grav
            car_ang_vel[i] = wcs[r]
