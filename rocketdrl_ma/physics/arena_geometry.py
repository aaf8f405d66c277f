"""The soccar arena's shape: a signed distance field, ray casts against it, and its surface mesh (uu).

The field is an octagonal prism (side walls |x| = 4096, back walls |y| = 5120, 45 degree corners
|x| + |y| = 8064, floor z = 0, ceiling z = 2048) whose edges are rounded with radius 256, which is
Rocket League's floor-to-wall and wall-to-ceiling ramp. Modelled exactly as a rounded polytope (an
inner prism grown by a ball of radius 256), so the distance field is exact Euclidean distance. The two
goals are boxes (1785.51 wide, 642.775 high, to |y| = 6000) united with it: the floor runs flat through
each goal mouth and the ramp along the back wall stops at the posts.

Wheel rays use ``arena_raycast`` (sphere tracing on ``arena_sdf``, compiled with numba); PyBullet
collides bodies with ``arena_mesh()``, whose vertices lie on the same surface.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .constants import (ARENA_CORNER_SUM, ARENA_EXTENT_X, ARENA_EXTENT_Y, ARENA_FILLET_RADIUS, ARENA_HEIGHT,
                        GOAL_DEPTH, GOAL_HALF_WIDTH, GOAL_HEIGHT)

R = ARENA_FILLET_RADIUS
X_IN = ARENA_EXTENT_X - R  # the inner prism the rounded arena grows from
Y_IN = ARENA_EXTENT_Y - R
C_IN = ARENA_CORNER_SUM - R * math.sqrt(2.0)  # |x| + |y| <= C_IN for the inner corner planes
GOAL_BACK_Y = ARENA_EXTENT_Y + GOAL_DEPTH
GOAL_START_Y = Y_IN - 50.0  # the goal box starts inside the field, so the floor is flat through the mouth
SQRT_HALF = math.sqrt(0.5)
RAY_HIT_EPS = 0.02
RAY_MAX_STEPS = 96


@njit(cache=True)
def _seg_dist(px, py, ax, ay, bx, by):
    dx, dy = bx - ax, by - ay
    t = ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)
    t = min(max(t, 0.0), 1.0)
    ex, ey = px - (ax + t * dx), py - (ay + t * dy)
    return math.sqrt(ex * ex + ey * ey)


@njit(cache=True)
def _octagon_sd(qx, qy):
    """Signed 2D distance from (|x|, |y|) to the inner octagon (negative inside)."""
    inside = max(qx - X_IN, qy - Y_IN, (qx + qy - C_IN) * SQRT_HALF)
    if inside <= 0.0:
        return inside
    ay = C_IN - X_IN  # vertex between the side wall and the corner plane
    bx = C_IN - Y_IN  # vertex between the corner plane and the back wall
    d = _seg_dist(qx, qy, X_IN, 0.0, X_IN, ay)
    d = min(d, _seg_dist(qx, qy, X_IN, ay, bx, Y_IN))
    return min(d, _seg_dist(qx, qy, bx, Y_IN, 0.0, Y_IN))


@njit(cache=True)
def _field_sdf(x, y, z):
    sd2 = _octagon_sd(abs(x), abs(y))
    sdz = max(R - z, z - (ARENA_HEIGHT - R))
    if sd2 > 0.0 and sdz > 0.0:
        outside = math.sqrt(sd2 * sd2 + sdz * sdz)
    else:
        outside = max(sd2, sdz)
    return R - outside


@njit(cache=True)
def _goal_sdf(x, y, z):
    """Inside-positive distance for the goal box at |y| (both goals by symmetry)."""
    dx = abs(x) - GOAL_HALF_WIDTH
    ay = abs(y)
    dy = max(GOAL_START_Y - ay, ay - GOAL_BACK_Y)
    dz = max(-z, z - GOAL_HEIGHT)
    if dx <= 0.0 and dy <= 0.0 and dz <= 0.0:
        return -max(dx, dy, dz)
    ox, oy, oz = max(dx, 0.0), max(dy, 0.0), max(dz, 0.0)
    return -math.sqrt(ox * ox + oy * oy + oz * oz)


@njit(cache=True)
def arena_distance(x, y, z):
    """Signed distance (uu) to the arena surface: positive inside the playable space."""
    return max(_field_sdf(x, y, z), _goal_sdf(x, y, z))


@njit(cache=True)
def arena_sdf(x, y, z):
    """Signed distance (positive inside) and the unit normal pointing into the interior."""
    d = arena_distance(x, y, z)
    h = 0.25
    nx = arena_distance(x + h, y, z) - arena_distance(x - h, y, z)
    ny = arena_distance(x, y + h, z) - arena_distance(x, y - h, z)
    nz = arena_distance(x, y, z + h) - arena_distance(x, y, z - h)
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    if norm < 1e-12:
        return d, 0.0, 0.0, 1.0
    return d, nx / norm, ny / norm, nz / norm


@njit(cache=True)
def arena_raycast(ox, oy, oz, dx, dy, dz, max_len):
    """First hit of the unit ray from (ox, oy, oz): (hit, distance, normal). Origins in solid hit at 0."""
    t = 0.0
    for _ in range(RAY_MAX_STEPS):
        px, py, pz = ox + dx * t, oy + dy * t, oz + dz * t
        d = arena_distance(px, py, pz)
        if d < RAY_HIT_EPS:
            _, nx, ny, nz = arena_sdf(px, py, pz)
            return True, t, nx, ny, nz
        t += d
        if t > max_len:
            return False, max_len, 0.0, 0.0, 0.0
    return False, max_len, 0.0, 0.0, 0.0


@njit(cache=True)
def is_inside_arena(x, y, z, margin):
    return arena_distance(x, y, z) >= margin


# ---------------------------------------------------------------- the surface mesh
def _perimeter() -> list[tuple[float, float, float, float]]:
    """(x, y, nx, ny) samples around the inner octagon, counter-clockwise: each vertex carries a fan of
    outward normals (the rounded vertical edge) and the back walls get extra samples at the goal posts."""
    ay, bx = C_IN - X_IN, C_IN - Y_IN
    ring = [(X_IN, ay), (bx, Y_IN), (-bx, Y_IN), (-X_IN, ay), (-X_IN, -ay), (-bx, -Y_IN), (bx, -Y_IN), (X_IN, -ay)]
    samples = []
    n = len(ring)
    for k in range(n):
        p0, p1, p2 = np.array(ring[k - 1]), np.array(ring[k]), np.array(ring[(k + 1) % n])
        e_in, e_out = p1 - p0, p2 - p1
        a0 = math.atan2(-e_in[0], e_in[1])  # outward normal (ey, -ex) of a counter-clockwise edge
        a1 = math.atan2(-e_out[0], e_out[1])
        if a1 < a0:
            a1 += 2 * math.pi
        for a in np.linspace(a0, a1, 5):
            samples.append((p1[0], p1[1], math.cos(a), math.sin(a)))
        if abs(e_out[1]) < 1e-9:  # a back wall: add the goal posts in walking order
            for x in sorted((GOAL_HALF_WIDTH, -GOAL_HALF_WIDTH), key=lambda x: x * e_out[0]):
                samples.append((x, p1[1], 0.0, float(np.sign(p1[1]))))
    return samples


def _profile(segments: int) -> list[tuple[float, float]]:
    """(horizontal offset, z) from the floor edge up the ramp, the wall and the top ramp to the ceiling edge."""
    bottom = [(R * math.cos(a), R + R * math.sin(a)) for a in np.linspace(-math.pi / 2, 0.0, segments + 1)]
    top = [(R * math.cos(a), ARENA_HEIGHT - R + R * math.sin(a)) for a in np.linspace(0.0, math.pi / 2, segments + 1)]
    return bottom + [(R, GOAL_HEIGHT)] + top


def arena_mesh(fillet_segments: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """The arena's inner surface as (vertices (N, 3) uu, triangles (M, 3) int32), normals facing inside."""
    verts: list[tuple[float, float, float]] = []
    tris: list[tuple[int, int, int]] = []

    def add(p) -> int:
        verts.append((float(p[0]), float(p[1]), float(p[2])))
        return len(verts) - 1

    def quad(a, b, c, d) -> None:
        tris.append((a, b, c))
        tris.append((a, c, d))

    perim = _perimeter()
    prof = _profile(fillet_segments)
    grid = [[add((x + h * nx, y + h * ny, z)) for h, z in prof] for x, y, nx, ny in perim]
    n = len(perim)
    for i in range(n):
        j = (i + 1) % n
        xi, yi, _, nyi = perim[i]
        xj, yj, _, nyj = perim[j]
        in_mouth = (abs(nyi) == 1.0 and abs(nyj) == 1.0 and abs(yi) == Y_IN and abs(yj) == Y_IN
                    and max(abs(xi), abs(xj)) <= GOAL_HALF_WIDTH + 1e-6)
        for k in range(len(prof) - 1):
            if in_mouth and prof[k + 1][1] <= GOAL_HEIGHT + 1e-6:
                continue  # the goal opening
            quad(grid[i][k], grid[j][k], grid[j][k + 1], grid[i][k + 1])
    # floor and ceiling: the inner octagon (fan from the centre)
    ring = [(x, y) for x, y, nx, ny in perim]
    for z in (0.0, ARENA_HEIGHT):
        centre = add((0.0, 0.0, z))
        ids = [add((x, y, z)) for x, y in ring]
        for i in range(len(ids)):
            tris.append((centre, ids[i], ids[(i + 1) % len(ids)]))
    # the goals: floor strip through the mouth, side walls (with the ramp's cut end), roof, back of the net
    w, gh = GOAL_HALF_WIDTH, GOAL_HEIGHT
    bottom_arc = prof[:fillet_segments + 1]
    for s in (1.0, -1.0):
        y0, y1, yb = s * Y_IN, s * ARENA_EXTENT_Y, s * GOAL_BACK_Y
        quad(add((-w, y0, 0)), add((w, y0, 0)), add((w, yb, 0)), add((-w, yb, 0)))
        quad(add((-w, y1, gh)), add((w, y1, gh)), add((w, yb, gh)), add((-w, yb, gh)))
        quad(add((-w, yb, 0)), add((w, yb, 0)), add((w, yb, gh)), add((-w, yb, gh)))
        for x in (w, -w):
            quad(add((x, y1, 0)), add((x, yb, 0)), add((x, yb, gh)), add((x, y1, gh)))
            corner = add((x, y1, 0.0))  # the solid behind the ramp, cut at the post
            arc = [add((x, y0 + s * h, z)) for h, z in bottom_arc]
            for a, b in zip(arc[:-1], arc[1:]):
                tris.append((corner, a, b))
    v = np.array(verts, dtype=np.float64)
    t = np.array(tris, dtype=np.int32)
    return v, _orient_inward(v, t)


def _orient_inward(v: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Flip triangles whose right-hand normal points into the solid, and drop degenerate ones."""
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    normal = np.cross(b - a, c - a)
    area = np.linalg.norm(normal, axis=1)
    keep = area > 1e-6
    t, normal, area = t[keep], normal[keep], area[keep]
    centroid = (a[keep] + b[keep] + c[keep]) / 3.0
    unit = normal / area[:, None]
    flip = np.array([arena_distance(*(p + 0.5 * n)) < arena_distance(*(p - 0.5 * n)) for p, n in zip(centroid, unit)])
    t = t.copy()
    t[flip] = t[flip][:, [0, 2, 1]]
    return t
