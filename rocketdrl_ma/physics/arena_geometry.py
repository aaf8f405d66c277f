"""The soccar arena's shape: a signed distance field, ray casts against it, and its surface mesh (uu, z up).

**Shape.** The field is an octagonal prism (side walls |x| = 4096, back walls |y| = 5120, 45 degree corners
|x| + |y| = 8064, floor z = 0, ceiling z = 2048) whose edges are all rounded with ``ARENA_FILLET_RADIUS``: it is
modelled as a *rounded polytope*, the inner prism (every face moved in by r) grown by a ball of radius r. This
gives the floor-to-wall and wall-to-ceiling ramps (quarter circles of radius r), and also rounds the vertical
edges where a side or back wall meets a 45 degree corner plane (a cylinder of radius r) and the corners
where three faces meet (a sphere). The two goals are boxes (|x| <= 892.755, 0 <= z <= 642.775) that run from
inside the field (|y| = 5120 - r - ``GOAL_BOX_OVERLAP``) to the back of the net (|y| = 6000), united with the
field: the floor stays flat through each goal mouth and the back wall has a rectangular opening. Beside each post a
*fairing* (convex, also united) cuts the back-wall ramp down to a quarter pipe of radius r that leaves the floor
tangentially at the post's line and rises away from the goal: the floor runs on across the line and curves up
onto the ramp, where a flat cut face used to stand (22 uu tall at |y| = 4850, 114 at 5000).

**Distance.** The field's distance is exact Euclidean distance everywhere (a rounded convex polytope); so is
each goal box's. The union is their maximum (inside positive), which is exact in the solid and on and near the
surface; deep inside, close to the seams where a goal box meets the field (at the posts), it can be a little
smaller than the true distance (a safe under-estimate). Normals are analytic gradients, not finite differences.

**Ray casts.** The field and both goal boxes are convex, so a ray meets each in a single interval; the signed
distance of a convex set is concave along a ray, so the field's interval ends are found with monotone Newton
iterations (no overshoot, quadratic convergence on the curved parts, one step on flat ones), the boxes' with
the slab test. The hit is the end of the chain of overlapping intervals that starts at the origin. This is
exact to ~1e-6 uu and needs no step budget for grazing rays (unlike sphere tracing).

**Mesh.** ``arena_mesh`` samples the same surface: every vertex of a curved part lies on the distance field's
zero level, so the chords of the fillets lie at most r (1 - cos(pi / 4 / fillet_segments)) inside it (1.9 uu
for r = 400 and 8 segments).

Everything marked ``@njit`` takes and returns plain floats, so it can be called from other numba kernels.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .constants import (ARENA_CORNER_SUM, ARENA_EXTENT_X, ARENA_EXTENT_Y, ARENA_FILLET_RADIUS, ARENA_HEIGHT,
                        GOAL_DEPTH, GOAL_HALF_WIDTH, GOAL_HEIGHT)

# The goal box starts this far in front of the end of the flat floor (|y| = 5120 - r), inside the field, so
# that the floor runs flat from the field into the goal (no ramp in the mouth).
GOAL_BOX_OVERLAP = 64.0
# Longest edge of the flat mesh parts (uu). Huge triangles make Bullet's box-vs-triangle contacts jittery.
MESH_MAX_EDGE = 1000.0
FAIRING_OVERLAP = 10.0  # uu the fairing reaches into the goal box and in front of the ramp (no seams)
FAIRING_STATIONS = 32  # mesh columns across each fairing's slope

R = ARENA_FILLET_RADIUS
X_IN = ARENA_EXTENT_X - R  # the inner prism that the rounded field grows from
Y_IN = ARENA_EXTENT_Y - R
SQRT_HALF = math.sqrt(0.5)
C_IN = ARENA_CORNER_SUM - R * math.sqrt(2.0)  # |x| + |y| <= C_IN: the inner corner planes
V1_Y = C_IN - X_IN  # inner octagon vertex (X_IN, V1_Y) between side wall and corner plane
V2_X = C_IN - Y_IN  # inner octagon vertex (V2_X, Y_IN) between corner plane and back wall
Z_LO = R
Z_HI = ARENA_HEIGHT - R
GOAL_W = GOAL_HALF_WIDTH
GOAL_H = GOAL_HEIGHT
GOAL_BACK_Y = ARENA_EXTENT_Y + GOAL_DEPTH
GOAL_START_Y = Y_IN - GOAL_BOX_OVERLAP
FAIRING_END_X = GOAL_W + R  # where the fairing's quarter pipe reaches the top of the ramp

assert 0.0 < V2_X and GOAL_W < V2_X and V1_Y > 0.0 and R < GOAL_H < Z_HI

_NEWTON_ITERS = 40
_NO_INTERVAL = (1e30, 1e30, 0.0, 0.0, 1.0)
_NEWTON_TOL = 1e-7  # uu of distance
_FAR = 1e30


# ================================================================= distance fields
@njit(cache=True, nogil=True, inline="always")
def _seg(px, py, ax, ay, bx, by, best, cx, cy):
    """Closest point of segment ab to p if it beats the squared distance ``best`` (else the old one)."""
    ex, ey = bx - ax, by - ay
    t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
    t = min(max(t, 0.0), 1.0)
    qx, qy = ax + t * ex, ay + t * ey
    d2 = (px - qx) * (px - qx) + (py - qy) * (py - qy)
    if d2 < best:
        return d2, qx, qy
    return best, cx, cy


@njit(cache=True, nogil=True)
def _field(x, y, z):
    """Exact signed distance to the rounded field (positive inside) and its unit gradient (into the field)."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    ax, ay = abs(x), abs(y)
    # signed 2D distance from (|x|, |y|) to the inner octagon, and its gradient (gx, gy), folded coordinates
    e1 = ax - X_IN
    e2 = ay - Y_IN
    e3 = (ax + ay - C_IN) * SQRT_HALF
    if e1 >= e2 and e1 >= e3:
        s2, gx, gy = e1, 1.0, 0.0
    elif e2 >= e3:
        s2, gx, gy = e2, 0.0, 1.0
    else:
        s2, gx, gy = e3, SQRT_HALF, SQRT_HALF
    if s2 > 0.0:  # outside the octagon: Euclidean distance to its boundary chain in this quadrant
        best, cx, cy = _seg(ax, ay, X_IN, 0.0, X_IN, V1_Y, _FAR, 0.0, 0.0)
        best, cx, cy = _seg(ax, ay, X_IN, V1_Y, V2_X, Y_IN, best, cx, cy)
        best, cx, cy = _seg(ax, ay, V2_X, Y_IN, 0.0, Y_IN, best, cx, cy)
        s2 = math.sqrt(best)
        if s2 > 0.0:
            gx, gy = (ax - cx) / s2, (ay - cy) / s2
    if Z_LO - z >= z - Z_HI:
        sz, gz = Z_LO - z, -1.0
    else:
        sz, gz = z - Z_HI, 1.0
    if s2 > 0.0 and sz > 0.0:
        o = math.sqrt(s2 * s2 + sz * sz)
        inv = 1.0 / o
        return R - o, -sx * gx * s2 * inv, -sy * gy * s2 * inv, -gz * sz * inv
    if s2 >= sz:
        return R - s2, -sx * gx, -sy * gy, 0.0
    return R - sz, 0.0, 0.0, -gz


@njit(cache=True, nogil=True)
def _goal(x, y, z):
    """Exact signed distance to the goal box on the side of y (positive inside) and its unit gradient."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    ay = abs(y)
    dx, gx = abs(x) - GOAL_W, sx
    if GOAL_START_Y - ay >= ay - GOAL_BACK_Y:
        dy, gy = GOAL_START_Y - ay, -sy
    else:
        dy, gy = ay - GOAL_BACK_Y, sy
    if -z >= z - GOAL_H:
        dz, gz = -z, -1.0
    else:
        dz, gz = z - GOAL_H, 1.0
    if dx <= 0.0 and dy <= 0.0 and dz <= 0.0:
        if dx >= dy and dx >= dz:
            return -dx, -gx, 0.0, 0.0
        if dy >= dz:
            return -dy, 0.0, -gy, 0.0
        return -dz, 0.0, 0.0, -gz
    ox, oy, oz = max(dx, 0.0), max(dy, 0.0), max(dz, 0.0)
    o = math.sqrt(ox * ox + oy * oy + oz * oz)
    inv = 1.0 / o
    return -o, -gx * ox * inv, -gy * oy * inv, -gz * oz * inv


@njit(cache=True, nogil=True)
def _fairing(x, y, z):
    """Signed distance to the fairing beside the nearest post (positive inside: exact there; outside a lower
    bound) and its gradient into the fairing. Its section across the back wall is a strip 10 uu wide inside the
    goal box (the overlap) and a quarter disc of radius r centred r above the post's line: above the floor, under
    the ramp's top, between the ramp's start and the back wall."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    ax, ay = abs(x), abs(y)
    # inside distances of the constraints (the smallest is the nearest boundary) and inward gradients
    best, gx, gy, gz = z, 0.0, 0.0, 1.0  # the floor
    d = R - z  # the ramp's top
    if d < best:
        best, gx, gy, gz = d, 0.0, 0.0, -1.0
    d = ax - (GOAL_W - FAIRING_OVERLAP)  # the strip's inner side, inside the goal box
    if d < best:
        best, gx, gy, gz = d, 1.0, 0.0, 0.0
    d = ay - (Y_IN - FAIRING_OVERLAP)  # the ramp's start
    if d < best:
        best, gx, gy, gz = d, 0.0, 1.0, 0.0
    d = ARENA_EXTENT_Y - ay  # the back wall
    if d < best:
        best, gx, gy, gz = d, 0.0, -1.0, 0.0
    if ax > GOAL_W:  # the quarter pipe (where ax <= W the strip's side is never the nearest boundary)
        ux, uz = ax - GOAL_W, z - R
        length = math.sqrt(ux * ux + uz * uz)
        d = R - length
        if d < best and length > 0.0:
            best, gx, gy, gz = d, -ux / length, 0.0, -uz / length
    return best, sx * gx, sy * gy, gz


@njit(cache=True, nogil=True)
def arena_sdf(x, y, z):
    """(d, nx, ny, nz): signed distance in uu (positive in the playable interior, negative in solid) and the
    unit normal (gradient) pointing into the interior."""
    d, nx, ny, nz = _field(x, y, z)
    g, gx, gy, gz = _goal(x, y, z)
    if g > d:
        d, nx, ny, nz = g, gx, gy, gz
    f, fx, fy, fz = _fairing(x, y, z)
    if f > d:
        return f, fx, fy, fz
    return d, nx, ny, nz


@njit(cache=True, nogil=True)
def _buried(qx, qy, qz, own):
    """Whether a surface point of piece ``own`` (0 field, 1 goal box, 2 fairing) lies inside another piece."""
    if own != 0 and _field(qx, qy, qz)[0] > 1e-3:
        return True
    if own != 1 and _goal(qx, qy, qz)[0] > 1e-3:
        return True
    return own != 2 and _fairing(qx, qy, qz)[0] > 1e-3


@njit(cache=True, nogil=True)
def _add_contact(out, n, x, y, z, qx, qy, qz, nx, ny, nz, reach, own):
    """Row n of ``out`` = the surface point q (normal n) if it is within reach, real and new. Returns the count."""
    d = math.sqrt((x - qx) ** 2 + (y - qy) ** 2 + (z - qz) ** 2)
    if d > reach or _buried(qx, qy, qz, own):
        return n
    for r in range(n):
        if abs(out[r, 0] - d) < 1e-6 and out[r, 1] * nx + out[r, 2] * ny + out[r, 3] * nz > 1.0 - 1e-9:
            return n  # the same surface point seen from two pieces (the floor under a goal mouth)
    if n < out.shape[0]:
        out[n, 0], out[n, 1], out[n, 2], out[n, 3] = d, nx, ny, nz
        n += 1
    return n


@njit(cache=True, nogil=True)
def _add_face(out, n, x, y, z, nx, ny, nz, c, reach, own):
    """The foot of (x, y, z) on the plane n . p = c of piece ``own``'s boundary (n pointing into the piece), if
    the foot lies on the piece (inside its other faces)."""
    t = nx * x + ny * y + nz * z - c
    qx, qy, qz = x - nx * t, y - ny * t, z - nz * t
    if own == 1:
        inside = _goal(qx, qy, qz)[0] > -1e-6
    else:
        inside = _fairing(qx, qy, qz)[0] > -1e-6
    if not inside:
        return n
    return _add_contact(out, n, x, y, z, qx, qy, qz, nx, ny, nz, reach, own)


@njit(cache=True, nogil=True)
def _add_edge(out, n, x, y, z, qx, qy, qz, reach):
    """An edge point q of the surface (where two pieces meet), the normal pointing from q to (x, y, z): only if the
    point lies in the arena (an edge the sphere can reach without crossing a surface first)."""
    d = math.sqrt((x - qx) ** 2 + (y - qy) ** 2 + (z - qz) ** 2)
    if d <= 1e-9 or d > reach or arena_sdf(x, y, z)[0] < 0.0:
        return n
    return _add_contact(out, n, x, y, z, qx, qy, qz, (x - qx) / d, (y - qy) / d, (z - qz) / d, reach, -1)


@njit(cache=True, nogil=True)
def surface_contacts(x, y, z, reach, out):
    """Where a sphere at (x, y, z) reaching ``reach`` uu meets the arena: rows (distance, nx, ny, nz) of ``out``
    (normals into the arena), one per surface it reaches, only real ones. Returns the number of rows.

    ``arena_sdf`` takes the largest piece distance, which near a seam is below the true distance (the field's
    ramp runs on under a goal mouth, a goal box's side under a fairing): a ball there would touch a surface that is
    not there. Here every candidate (the field's nearest point and its flat floor and ceiling, each face of the
    goal box and the fairing on the sphere's side, the rim of the goal opening) counts only if no other piece covers
    it."""
    n = 0
    d, nx, ny, nz = _field(x, y, z)
    n = _add_contact(out, n, x, y, z, x - nx * d, y - ny * d, z - nz * d, nx, ny, nz, reach, 0)
    near_goal = abs(y) > GOAL_START_Y - reach and abs(x) < FAIRING_END_X + reach and z < GOAL_H + reach
    if not near_goal:
        return n
    if _field(x, y, 0.0)[0] > -1e-6 and abs(_field(x, y, 0.0)[0]) < 1e-6:  # the field's flat floor below
        n = _add_contact(out, n, x, y, z, x, y, 0.0, 0.0, 0.0, 1.0, reach, 0)
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    # the goal box on this side: floor, roof, sides, back (its front lies inside the field)
    n = _add_face(out, n, x, y, z, 0.0, 0.0, 1.0, 0.0, reach, 1)
    n = _add_face(out, n, x, y, z, 0.0, 0.0, -1.0, -GOAL_H, reach, 1)
    n = _add_face(out, n, x, y, z, -sx, 0.0, 0.0, -GOAL_W, reach, 1)
    n = _add_face(out, n, x, y, z, 0.0, -sy, 0.0, -GOAL_BACK_Y, reach, 1)
    # the rim of the goal opening, where the back wall meets the goal box: the crossbar and the posts
    n = _add_edge(out, n, x, y, z, min(max(x, -GOAL_W), GOAL_W), sy * ARENA_EXTENT_Y, GOAL_H, reach)
    n = _add_edge(out, n, x, y, z, sx * GOAL_W, sy * ARENA_EXTENT_Y, min(max(z, 0.0), GOAL_H), reach)
    # the fairing on this side: floor, quarter pipe, back wall (its other faces lie inside other pieces)
    n = _add_face(out, n, x, y, z, 0.0, 0.0, 1.0, 0.0, reach, 2)
    ux, uz = abs(x) - GOAL_W, z - R
    length = math.sqrt(ux * ux + uz * uz)
    if ux > 0.0 and uz < 0.0 and length > 0.0:  # the nearest point of the pipe's arc (its inside is the fairing)
        qx, qz = sx * (GOAL_W + ux / length * R), R + uz / length * R
        if _fairing(qx, y, qz)[0] > -1e-6:
            n = _add_contact(out, n, x, y, z, qx, y, qz, -sx * ux / length, 0.0, -uz / length, reach, 2)
    n = _add_face(out, n, x, y, z, 0.0, -sy, 0.0, -ARENA_EXTENT_Y, reach, 2)
    return n


@njit(cache=True, nogil=True)
def arena_distance(x, y, z):
    """The signed distance of ``arena_sdf`` alone."""
    return arena_sdf(x, y, z)[0]


@njit(cache=True, nogil=True)
def is_inside_arena(x, y, z, margin):
    """True if (x, y, z) is inside the playable space with at least ``margin`` uu of clearance."""
    return arena_sdf(x, y, z)[0] >= margin


# ================================================================= ray casts
@njit(cache=True, nogil=True, inline="always")
def _field_along(ox, oy, oz, dx, dy, dz, t):
    f, nx, ny, nz = _field(ox + dx * t, oy + dy * t, oz + dz * t)
    return f, nx * dx + ny * dy + nz * dz


@njit(cache=True, nogil=True)
def _field_interval(ox, oy, oz, dx, dy, dz, max_len):
    """[a, b] of the ray inside the (convex) field, clipped to start at 0; a = _FAR if it never enters
    before max_len; b = _FAR if it is still inside at max_len. f(t) is concave, so Newton's method from a
    point left of the entry (right of the exit) approaches it monotonically without overshooting."""
    f, g = _field_along(ox, oy, oz, dx, dy, dz, 0.0)
    a = 0.0
    if f < 0.0:
        t = 0.0
        for _ in range(_NEWTON_ITERS):
            if g <= 0.0:
                return _FAR, _FAR  # past the maximum of a concave function: never enters
            t -= f / g
            if t > max_len:
                return _FAR, _FAR
            f, g = _field_along(ox, oy, oz, dx, dy, dz, t)
            if f >= -_NEWTON_TOL:
                break
        if f < -1e-3:
            return _FAR, _FAR  # grazing tangent ray that never really enters
        a = t
    t = max_len
    f, g = _field_along(ox, oy, oz, dx, dy, dz, t)
    if f >= 0.0:
        return a, _FAR
    for _ in range(_NEWTON_ITERS):
        if g >= 0.0:
            break
        t -= f / g
        f, g = _field_along(ox, oy, oz, dx, dy, dz, t)
        if f >= -_NEWTON_TOL:
            break
    return a, max(t, a)


@njit(cache=True, nogil=True, inline="always")
def _slab(o, d, lo, hi):
    """Entry/exit parameters of a ray coordinate in [lo, hi] (entry > exit if it misses)."""
    if abs(d) < 1e-300:
        if lo <= o <= hi:
            return -_FAR, _FAR
        return _FAR, -_FAR
    inv = 1.0 / d
    t1, t2 = (lo - o) * inv, (hi - o) * inv
    if t1 > t2:
        return t2, t1
    return t1, t2


@njit(cache=True, nogil=True)
def _box_interval(ox, oy, oz, dx, dy, dz, ylo, yhi):
    """[a, b] of the ray inside a goal box and the inward normal of the face it leaves through."""
    ax, bx = _slab(ox, dx, -GOAL_W, GOAL_W)
    ay, by = _slab(oy, dy, ylo, yhi)
    az, bz = _slab(oz, dz, 0.0, GOAL_H)
    a = max(ax, ay, az, 0.0)
    if bx <= by and bx <= bz:
        b, nx, ny, nz = bx, (-1.0 if dx > 0.0 else 1.0), 0.0, 0.0
    elif by <= bz:
        b, nx, ny, nz = by, 0.0, (-1.0 if dy > 0.0 else 1.0), 0.0
    else:
        b, nx, ny, nz = bz, 0.0, 0.0, (-1.0 if dz > 0.0 else 1.0)
    if a > b:
        return _FAR, _FAR, 0.0, 0.0, 1.0
    return a, b, nx, ny, nz


@njit(cache=True, nogil=True)
def _fairing_interval(ox, oy, oz, dx, dy, dz, sx, sy):
    """[a, b] of the ray inside the fairing on the (sx, sy) side and the inward normal of the face it leaves by:
    the slabs of its flat faces clip the interval of the (convex) union of the half-space |x| <= W and the pipe's
    disc."""
    a, b = 0.0, _FAR
    bx, by, bz = 0.0, 0.0, 1.0
    for f in range(5):
        if f == 0:
            nx, ny, nz, c = 0.0, 0.0, -1.0, 0.0  # above the floor
        elif f == 1:
            nx, ny, nz, c = 0.0, 0.0, 1.0, R  # under the ramp's top
        elif f == 2:
            nx, ny, nz, c = -sx, 0.0, 0.0, -(GOAL_W - FAIRING_OVERLAP)  # beyond the strip's inner side
        elif f == 3:
            nx, ny, nz, c = 0.0, -sy, 0.0, -(Y_IN - FAIRING_OVERLAP)  # behind the ramp's start
        else:
            nx, ny, nz, c = 0.0, sy, 0.0, ARENA_EXTENT_Y  # in front of the back wall
        o_n = nx * ox + ny * oy + nz * oz
        d_n = nx * dx + ny * dy + nz * dz
        if abs(d_n) < 1e-300:
            if o_n > c:
                return _FAR, _FAR, 0.0, 0.0, 1.0
            continue
        t = (c - o_n) / d_n
        if d_n < 0.0:
            a = max(a, t)
        elif t < b:
            b, bx, by, bz = t, nx, ny, nz
        if a > b:
            return _FAR, _FAR, 0.0, 0.0, 1.0
    # the half-space sx x <= W ...
    ha, hb = -_FAR, _FAR
    hnx = 0.0
    if abs(dx) < 1e-300:
        if sx * ox > GOAL_W:
            ha, hb = _FAR, -_FAR
    else:
        t = (sx * GOAL_W - ox) / dx
        if sx * dx > 0.0:
            hb, hnx = t, sx
        else:
            ha = t
    # ... united with the disc of radius R about (x, z) = (sx W, R)
    da, db = _FAR, -_FAR
    px, pz = ox - sx * GOAL_W, oz - R
    qa = dx * dx + dz * dz
    if qa > 1e-300:
        qb = px * dx + pz * dz
        disc = qb * qb - qa * (px * px + pz * pz - R * R)
        if disc >= 0.0:
            root = math.sqrt(disc)
            da, db = (-qb - root) / qa, (-qb + root) / qa
    elif px * px + pz * pz <= R * R:
        da, db = -_FAR, _FAR
    # Within the slabs the union is convex (a box with one rounded edge): clip both pieces first, then join them.
    ha, hb_clip = max(ha, a), min(hb, b)
    da, db_clip = max(da, a), min(db, b)
    h_ok, d_ok = ha <= hb_clip, da <= db_clip
    if not h_ok and not d_ok:
        return _FAR, _FAR, 0.0, 0.0, 1.0
    if h_ok and d_ok:
        start, end = min(ha, da), max(hb_clip, db_clip)
    elif h_ok:
        start, end = ha, hb_clip
    else:
        start, end = da, db_clip
    if end < b:  # the ray leaves by the half-space's side or the pipe, not by a slab
        if d_ok and db_clip == end and db < b:
            ex, ez = ox + dx * end - sx * GOAL_W, oz + dz * end - R
            length = math.sqrt(ex * ex + ez * ez)
            bx, by, bz = ex / length, 0.0, ez / length
        else:
            bx, by, bz = hnx, 0.0, 0.0
    return start, end, -bx, -by, -bz


@njit(cache=True, nogil=True, inline="always")
def _near_a_fairing(ox, oy, oz, dx, dy, dz, max_len):
    """Whether the ray's bounding box reaches any fairing's (most rays, far from the goals, skip them)."""
    ex, ey, ez = ox + dx * max_len, oy + dy * max_len, oz + dz * max_len
    if min(oz, ez) > R or max(abs(oy), abs(ey)) < Y_IN - FAIRING_OVERLAP:
        return False
    if min(abs(ox), abs(ex)) > FAIRING_END_X and ox * ex > 0.0:
        return False
    return True


@njit(cache=True, nogil=True)
def arena_raycast(ox, oy, oz, dx, dy, dz, max_len):
    """First surface hit of the unit ray (dx, dy, dz) from (ox, oy, oz) within max_len uu:
    (hit, t, nx, ny, nz), the normal pointing into the interior. An origin in solid hits at t = 0 with the
    distance field's normal; a miss returns (False, max_len, 0, 0, 0)."""
    d0, nx, ny, nz = arena_sdf(ox, oy, oz)
    if d0 < 0.0:
        return True, 0.0, nx, ny, nz
    if d0 > max_len:
        return False, max_len, 0.0, 0.0, 0.0
    fa, fb = _field_interval(ox, oy, oz, dx, dy, dz, max_len)
    # the convex pieces: the field, two goal boxes, four fairings; each an interval with its exit normal
    pa, pb, pnx, pny, pnz = _box_interval(ox, oy, oz, dx, dy, dz, GOAL_START_Y, GOAL_BACK_Y)
    ma, mb, mnx, mny, mnz = _box_interval(ox, oy, oz, dx, dy, dz, -GOAL_BACK_Y, -GOAL_START_Y)
    near = _near_a_fairing(ox, oy, oz, dx, dy, dz, max_len)
    f0 = _fairing_interval(ox, oy, oz, dx, dy, dz, 1.0, 1.0) if near else _NO_INTERVAL
    f1 = _fairing_interval(ox, oy, oz, dx, dy, dz, 1.0, -1.0) if near else _NO_INTERVAL
    f2 = _fairing_interval(ox, oy, oz, dx, dy, dz, -1.0, 1.0) if near else _NO_INTERVAL
    f3 = _fairing_interval(ox, oy, oz, dx, dy, dz, -1.0, -1.0) if near else _NO_INTERVAL
    # walk the chain of overlapping intervals that starts at the origin
    eps = 1e-6
    t_end = 0.0
    hit = (0.0, 0.0, 0.0)
    which = -1
    for _ in range(8):
        moved = False
        if fa <= t_end + eps and fb > t_end:
            t_end, which, moved = fb, 0, True
        if pa <= t_end + eps and pb > t_end:
            t_end, which, moved, hit = pb, 1, True, (pnx, pny, pnz)
        if ma <= t_end + eps and mb > t_end:
            t_end, which, moved, hit = mb, 1, True, (mnx, mny, mnz)
        for f in (f0, f1, f2, f3):
            if f[0] <= t_end + eps and f[1] > t_end:
                t_end, which, moved, hit = f[1], 1, True, (f[2], f[3], f[4])
        if not moved:
            break
    if which < 0:  # on the surface, leaving it at once
        return True, 0.0, nx, ny, nz
    if t_end > max_len:
        return False, max_len, 0.0, 0.0, 0.0
    if which == 1:
        return True, t_end, hit[0], hit[1], hit[2]
    _, nx, ny, nz = _field(ox + dx * t_end, oy + dy * t_end, oz + dz * t_end)
    return True, t_end, nx, ny, nz


@njit(cache=True, nogil=True)
def _sdf_many(points):
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        out[i] = arena_sdf(points[i, 0], points[i, 1], points[i, 2])[0]
    return out


def arena_sdf_many(points: np.ndarray) -> np.ndarray:
    """``arena_sdf`` distances of an (n, 3) array of points."""
    return _sdf_many(np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3))


# ================================================================= the surface mesh
def _splits(a: float, b: float, max_len: float) -> list[float]:
    """Parameters in [0, 1) splitting a..b into equal pieces no longer than max_len (the end is left out)."""
    n = max(1, math.ceil(abs(b - a) / max_len - 1e-9))
    return [k / n for k in range(n)]


def _stations(fillet_segments: int) -> list[tuple[float, float, float, float, bool]]:
    """(x, y, nx, ny, in_mouth) around the inner octagon, counter-clockwise: points of the octagon with the
    outward direction of the profile drawn from them. Each octagon vertex carries a fan of directions (the
    rounded vertical edge); the back walls get stations at the goal posts. ``in_mouth``: the station and the
    next one bound a piece of the goal opening."""
    ring = [(X_IN, -V1_Y), (X_IN, V1_Y), (V2_X, Y_IN), (-V2_X, Y_IN),
            (-X_IN, V1_Y), (-X_IN, -V1_Y), (-V2_X, -Y_IN), (V2_X, -Y_IN)]
    fan = max(2, (fillet_segments + 1) // 2)  # pieces per 45 degree vertical edge
    out: list[tuple[float, float, float, float, bool]] = []
    n = len(ring)
    for k in range(n):
        p0, p1, p2 = np.array(ring[k - 1]), np.array(ring[k]), np.array(ring[(k + 1) % n])
        e_in, e_out = p1 - p0, p2 - p1
        a0 = math.atan2(-e_in[0], e_in[1])  # outward normal (ey, -ex) of a counter-clockwise edge
        a1 = math.atan2(-e_out[0], e_out[1])
        if a1 < a0:
            a1 += 2.0 * math.pi
        for a in np.linspace(a0, a1, fan + 1)[:-1]:
            out.append((p1[0], p1[1], math.cos(a), math.sin(a), False))
        nx, ny = math.cos(a1), math.sin(a1)
        # along edge k -> k + 1 (the vertex itself with the edge normal, then the interior points)
        cuts = [0.0, 1.0]
        if abs(e_out[1]) < 1e-9:  # a back wall: the posts split it, and the fairings need fine stations
            fairing = np.linspace(GOAL_W, FAIRING_END_X, FAIRING_STATIONS + 1)
            cuts += [(x - p1[0]) / e_out[0] for x in np.concatenate((fairing, -fairing))]
            cuts = sorted(cuts)
        for c0, c1 in zip(cuts[:-1], cuts[1:]):
            q0 = p1 + c0 * e_out
            mouth = abs(e_out[1]) < 1e-9 and abs(q0[0] + 0.5 * (c1 - c0) * e_out[0]) < GOAL_W
            for s in _splits(0.0, (c1 - c0) * float(np.hypot(*e_out)), MESH_MAX_EDGE):
                q = q0 + s * (c1 - c0) * e_out
                out.append((float(q[0]), float(q[1]), nx, ny, mouth))
    return out


def _profile(fillet_segments: int) -> list[tuple[float, float]]:
    """(outward offset h, z) from the floor's edge up the ramp, the wall and the top ramp to the ceiling's."""
    bottom = [(R * math.cos(a), R + R * math.sin(a)) for a in np.linspace(-math.pi / 2, 0.0, fillet_segments + 1)]
    top = [(R * math.cos(a), Z_HI + R * math.sin(a)) for a in np.linspace(0.0, math.pi / 2, fillet_segments + 1)]
    wall = [(R, GOAL_H)] + [(R, GOAL_H + s * (Z_HI - GOAL_H)) for s in _splits(GOAL_H, Z_HI, MESH_MAX_EDGE)[1:]]
    bottom[-1] = (R, R)
    top[0] = (R, Z_HI)
    top[-1] = (0.0, ARENA_HEIGHT)
    bottom[0] = (0.0, 0.0)
    return bottom + wall + top


class _MeshBuilder:
    def __init__(self) -> None:
        self.index: dict[tuple[float, float, float], int] = {}
        self.verts: list[tuple[float, float, float]] = []
        self.tris: list[tuple[int, int, int]] = []

    def v(self, x: float, y: float, z: float) -> int:
        key = (round(float(x), 6) + 0.0, round(float(y), 6) + 0.0, round(float(z), 6) + 0.0)
        i = self.index.get(key)
        if i is None:
            i = self.index[key] = len(self.verts)
            self.verts.append(key)
        return i

    def quad(self, a: int, b: int, c: int, d: int) -> None:
        self.tris.append((a, b, c))
        self.tris.append((a, c, d))


def arena_mesh(fillet_segments: int = 8, with_floor_and_ceiling: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The whole interior boundary as (vertices (N, 3) float64 uu, triangles (M, 3) int32), wound so that the
    right-hand normals point into the interior: floor, walls, rounded corners, ramps, ceiling, back walls with
    the goal openings, and the goal boxes (floor, side walls, roof, back of the net).

    The physics world leaves out the flat floor and ceiling (``with_floor_and_ceiling=False``) and collides
    with planes there instead: a ball rolling over the internal edges between coplanar triangles gets kicked
    up at every edge (Bullet's contact normals flip at triangle edges), which planes have none of."""
    if fillet_segments < 1:
        raise ValueError("fillet_segments must be >= 1")
    m = _MeshBuilder()
    stations = _stations(fillet_segments)
    prof = _profile(fillet_segments)
    cols = [[m.v(x + h * nx, y + h * ny, z) for h, z in _faired_profile(prof, x, ny)] for x, y, nx, ny, _ in stations]
    n = len(stations)
    for i in range(n):
        j = (i + 1) % n
        for k in range(len(prof) - 1):
            if stations[i][4] and prof[k + 1][1] <= GOAL_H + 1e-6:
                continue  # the goal opening
            m.quad(cols[i][k], cols[j][k], cols[j][k + 1], cols[i][k + 1])
    # floor and ceiling: the inner octagon as concentric rings scaled towards the centre
    ring = []
    for x, y, _, ny, _ in stations:
        if _in_fairing(x, ny) and abs(x) > GOAL_W + 1e-6:
            continue  # the fairings' fine columns: the floor and ceiling rings stay coarse (no sliver triangles)
        if not ring or (x, y) != ring[-1]:
            ring.append((x, y))
    if ring[0] == ring[-1]:
        ring.pop()
    ring_arr = np.array(ring)
    n_rings = max(1, math.ceil(float(np.hypot(ring_arr[:, 0], ring_arr[:, 1]).max()) / MESH_MAX_EDGE))
    for z in (0.0, ARENA_HEIGHT) if with_floor_and_ceiling else ():
        centre = m.v(0.0, 0.0, z)
        rings = [[m.v(x * s, y * s, z) for x, y in ring] for s in np.arange(1, n_rings + 1) / n_rings]
        nr = len(ring)
        for i in range(nr):
            m.tris.append((centre, rings[0][i], rings[0][(i + 1) % nr]))
            for r0, r1 in zip(rings[:-1], rings[1:]):
                m.quad(r0[i], r1[i], r1[(i + 1) % nr], r0[(i + 1) % nr])
    # the goals
    w, gh, back = GOAL_W, GOAL_H, GOAL_BACK_Y
    mouth_x = sorted({x for x, y, _, _, _ in stations if abs(y) == Y_IN and abs(x) <= w + 1e-6})
    ny_floor = max(1, math.ceil((back - Y_IN) / MESH_MAX_EDGE))
    for s in (1.0, -1.0):
        ys = [Y_IN + (back - Y_IN) * k / ny_floor for k in range(ny_floor + 1)]
        for a, b in zip(mouth_x[:-1], mouth_x[1:]):
            for y0, y1 in zip(ys[:-1], ys[1:]) if with_floor_and_ceiling else ():  # goal floor
                m.quad(m.v(a, s * y0, 0.0), m.v(b, s * y0, 0.0), m.v(b, s * y1, 0.0), m.v(a, s * y1, 0.0))
            # roof (from the crossbar) and back of the net
            m.quad(m.v(a, s * ARENA_EXTENT_Y, gh), m.v(b, s * ARENA_EXTENT_Y, gh), m.v(b, s * back, gh),
                   m.v(a, s * back, gh))
            m.quad(m.v(a, s * back, 0.0), m.v(b, s * back, 0.0), m.v(b, s * back, gh), m.v(a, s * back, gh))
        for x in (w, -w):  # side wall of the net
            m.quad(m.v(x, s * ARENA_EXTENT_Y, 0.0), m.v(x, s * back, 0.0), m.v(x, s * back, gh),
                   m.v(x, s * ARENA_EXTENT_Y, gh))
    verts = np.array(m.verts, dtype=np.float64)
    tris = _orient_inward(verts, np.array(m.tris, dtype=np.int64))
    used, tris = np.unique(tris, return_inverse=True)  # drop vertices no triangle uses (inside the mouths)
    return verts[used], tris.reshape(-1, 3).astype(np.int32)


def _in_fairing(x: float, ny: float) -> bool:
    return abs(ny) > 0.99 and GOAL_W - 1e-6 <= abs(x) <= FAIRING_END_X + 1e-6


def _faired_profile(prof: list[tuple[float, float]], x: float, ny: float) -> list[tuple[float, float]]:
    """A back-wall station's profile where a fairing cuts the ramp down beside a post: the ramp's arc up to the
    quarter pipe's height c there, a vertex exactly where they meet, then flat at c to the wall."""
    if not _in_fairing(x, ny):
        return prof
    u = min(max(abs(x) - GOAL_W, 0.0), R)
    c = R - math.sqrt(R * R - u * u)
    out, met = [], False
    for h, z in prof:
        if z <= c or z > R:
            out.append((h, z))
        elif not met:
            crease = math.sqrt(max(R * R - (R - c) ** 2, 0.0))  # where the arc reaches height c
            out.append((crease if crease > out[-1][0] + 0.5 else h, c))  # (no sliver right at the post)
            met = True
        else:
            out.append((h, c))
    return out


def _orient_inward(v: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Drop degenerate triangles and wind the rest so that their right-hand normals face the interior."""
    t = t[(t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])]
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    normal = np.cross(b - a, c - a)
    area = np.linalg.norm(normal, axis=1)
    keep = area > 1e-6
    t, normal, area = t[keep], normal[keep], area[keep]
    centroid = (a[keep] + b[keep] + c[keep]) / 3.0
    unit = normal / area[:, None]
    flip = arena_sdf_many(centroid + 0.5 * unit) < arena_sdf_many(centroid - 0.5 * unit)
    t = t.copy()
    t[flip] = t[flip][:, [0, 2, 1]]
    return t.astype(np.int32)
