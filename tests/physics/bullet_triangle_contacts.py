"""How RocketSim's Bullet finds a ball's contacts with the game's collision meshes, rebuilt in numpy on the mesh
triangles (a test model: it reads the meshes ``rlgym-rocket-league`` installs, nothing of them is in the package).

Bullet tests the ball against every triangle of a mesh near it (``SphereTriangleDetector``: the triangle's nearest
point, a contact when the gap is at most the contact-breaking distance), RocketSim's contact callback turns each
contact's normal with ``btAdjustInternalEdgeContacts`` (a contact within 5 uu of an edge shared with a coplanar or
concave neighbour takes its own triangle's normal), and each contact goes into the one persistent manifold of that
mesh and the ball: a contact whose point on the ball lies within the breaking distance of one there replaces it,
and a full manifold (4 points) keeps its deepest point and swaps out the one that leaves the largest area
(``btPersistentManifold::sortCachedPoints``). Each of RocketSim's four planes is a manifold of its own. The ball's
contact is then the mean of every manifold point's normal (RocketSim's "special" contact).

So a face counts once per triangle of it that reaches the ball (a quad's diagonal within reach adds its second
triangle), which depends on how the game's meshes split their quads, and a mesh with more than four contacts
keeps four of them in an order set by its bounding-volume tree (taken here as the file's triangle order).
``per_face=True`` gives what an analytic surface gives instead: one contact per distinct face normal.
"""
from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from rocketdrl_ma.physics import ball_kernel as bk
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.mesh_file import read_soccar_arena

BREAKING_GAP = 1.905       # uu: RocketSim's ball touches the arena from this gap (ball_kernel.BALL_WORLD_CONTACT_GAP)
EDGE_DISTANCE = 5.0        # uu: btTriangleInfoMap's m_edgeDistanceThreshold (0.1 in RocketSim's 50 uu units)
MANIFOLD_SIZE = 4          # Bullet's MANIFOLD_CACHE_SIZE
PLANES = ((2, 0.0, 1.0), (2, 2048.0, -1.0), (0, -4096.0, 1.0), (0, 4096.0, -1.0))  # (axis, position, normal sign)
_PLANE_MANIFOLD = 1000     # manifold ids of the planes start here (the meshes' are their file index)


class TriangleContacts:
    """The soccar meshes of ``folder`` (``RocketSim.init``'s folder) and their shared edges."""

    def __init__(self, folder: str) -> None:
        vertices, triangles, self.mesh = read_soccar_arena(folder)
        v = vertices.astype(np.float64)
        self.a, self.b, self.c = v[triangles[:, 0]], v[triangles[:, 1]], v[triangles[:, 2]]
        normal = np.cross(self.b - self.a, self.c - self.a)
        self.normal = normal / np.linalg.norm(normal, axis=1)[:, None]
        self.lo = np.minimum(np.minimum(self.a, self.b), self.c)
        self.hi = np.maximum(np.maximum(self.a, self.b), self.c)
        by_edge = defaultdict(list)
        for k in range(len(triangles)):
            for e, (p, q) in enumerate(self._edges(k)):
                by_edge[(int(self.mesh[k]),) + tuple(sorted((tuple(np.round(p, 3)), tuple(np.round(q, 3)))))].append(k)
        self.neighbour = np.full((len(triangles), 3), -1)
        for k in range(len(triangles)):
            for e, (p, q) in enumerate(self._edges(k)):
                key = (int(self.mesh[k]),) + tuple(sorted((tuple(np.round(p, 3)), tuple(np.round(q, 3)))))
                others = [j for j in by_edge[key] if j != k]
                if others:
                    self.neighbour[k, e] = others[0]

    def _edges(self, k: int):
        vs = (self.a[k], self.b[k], self.c[k])
        return [(vs[e], vs[(e + 1) % 3]) for e in range(3)]

    def contacts(self, centre: np.ndarray) -> list[tuple[int, np.ndarray, np.ndarray, float]]:
        """Every contact of a ball at ``centre``: (manifold id, point on the ball relative to its centre, adjusted
        normal, gap), the meshes' in file order, then the planes."""
        reach = C.BALL_RADIUS + BREAKING_GAP
        near = np.where(np.all(self.lo <= centre + reach, axis=1) & np.all(self.hi >= centre - reach, axis=1))[0]
        out = []
        for k in near:
            if abs((centre - self.a[k]) @ self.normal[k]) >= reach:
                continue
            q = _closest_point_on_triangle(centre, self.a[k], self.b[k], self.c[k])
            d = float(np.linalg.norm(centre - q))
            if d >= reach or d <= 1e-9:
                continue
            n = (centre - q) / d
            out.append((int(self.mesh[k]), -n * C.BALL_RADIUS, self._adjusted(k, q, n), d - C.BALL_RADIUS))
        for m, (axis, position, sign) in enumerate(PLANES):
            gap = sign * (centre[axis] - position) - C.BALL_RADIUS
            if gap <= BREAKING_GAP:
                n = np.zeros(3)
                n[axis] = sign
                out.append((_PLANE_MANIFOLD + m, -n * C.BALL_RADIUS, n, gap))
        return out

    def _adjusted(self, k: int, point: np.ndarray, n: np.ndarray) -> np.ndarray:
        """``btAdjustInternalEdgeContacts`` on a contact of triangle ``k``: near an edge shared with a coplanar or
        concave neighbour the triangle's own normal; near a convex one the normal clamped to the two faces."""
        own = self.normal[k]
        best, best_d = -1, math.inf
        for e, (p, q) in enumerate(self._edges(k)):
            if self.neighbour[k, e] < 0:
                continue  # a mesh border: no edge information
            d = float(np.linalg.norm(point - _closest_point_on_segment(point, p, q)))
            if d < best_d:
                best, best_d = e, d
        if best < 0 or best_d >= EDGE_DISTANCE:
            return n
        p, q = self._edges(k)[best]
        other = self.neighbour[k, best]
        apex = max((self.a[other], self.b[other], self.c[other]), key=lambda v: abs((v - p) @ own))
        bend = float((apex - p) @ own)
        convex = bend < -1e-3 and np.linalg.norm(np.cross(own, self.normal[other])) > 1e-4
        if not convex:
            return own.copy() if own @ n >= 0.0 else n
        return _clamped(n, own, self.normal[other], q - p)


def _clamped(n: np.ndarray, own: np.ndarray, other: np.ndarray, edge: np.ndarray) -> np.ndarray:
    """The normal turned about the edge into the wedge between the two faces' normals."""
    axis = edge / np.linalg.norm(edge)

    def angle(v):
        v = v - axis * (v @ axis)
        return math.atan2(np.cross(own, v) @ axis, own @ v)

    a_n, a_other = angle(n), angle(other)
    lo, hi = min(0.0, a_other), max(0.0, a_other)
    if lo <= a_n <= hi:
        return n
    return own.copy() if abs(a_n) < abs(a_n - a_other) else other.copy()


def _closest_point_on_segment(x, p, q):
    pq = q - p
    return p + np.clip((x - p) @ pq / (pq @ pq), 0.0, 1.0) * pq


def _closest_point_on_triangle(x, a, b, c):
    """RocketSim's ``closestPointTriangle`` (SphereTriangleDetector.cpp)."""
    ab, ac, ax = b - a, c - a, x - a
    d1, d2 = ab @ ax, ac @ ax
    if d1 <= 0 and d2 <= 0:
        return a
    bx = x - b
    d3, d4 = ab @ bx, ac @ bx
    if d3 >= 0 and d4 <= d3:
        return b
    cx = x - c
    d5, d6 = ab @ cx, ac @ cx
    if d6 >= 0 and d5 <= d6:
        return c
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return a + d1 / (d1 - d3) * ab
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return a + d2 / (d2 - d6) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
    denominator = 1.0 / (va + vb + vc)
    return a + vb * denominator * ab + vc * denominator * ac


def manifold_normals(contacts: list, per_face: bool = False) -> tuple[list[np.ndarray], bool]:
    """The normals the ball's merged contact averages, and whether a manifold had to drop a point (its choice
    then depends on the order of the triangles). ``per_face``: one contact per distinct normal, no manifolds."""
    if per_face:
        normals: list[np.ndarray] = []
        for _, _, n, _ in contacts:
            if all(n @ m < 1.0 - 1e-9 for m in normals):
                normals.append(n)
        return normals, False
    manifolds: dict[int, list] = defaultdict(list)
    dropped = False
    for m, on_ball, n, gap in contacts:
        points = manifolds[m]
        nearest, nearest_d2 = -1, BREAKING_GAP ** 2
        for i, (other_on_ball, _, _) in enumerate(points):
            d2 = float(np.sum((other_on_ball - on_ball) ** 2))
            if d2 < nearest_d2:
                nearest, nearest_d2 = i, d2
        if nearest >= 0:
            points[nearest] = (on_ball, n, gap)
        elif len(points) < MANIFOLD_SIZE:
            points.append((on_ball, n, gap))
        else:
            dropped = True
            points[_sorted_cache_slot(points, on_ball, gap)] = (on_ball, n, gap)
    return [n for points in manifolds.values() for _, n, _ in points], dropped


def _sorted_cache_slot(points: list, on_ball: np.ndarray, gap: float) -> int:
    """``btPersistentManifold::sortCachedPoints``: keep the deepest point, swap out the one leaving the largest
    area."""
    deepest, deepest_gap = -1, gap
    for i, (_, _, g) in enumerate(points):
        if g < deepest_gap:
            deepest, deepest_gap = i, g
    p = [q[0] for q in points]
    pairs = ((1, 3, 2), (0, 3, 2), (0, 3, 1), (0, 2, 1))
    areas = [0.0 if i == deepest else float(np.sum(np.cross(on_ball - p[a], p[b] - p[c]) ** 2))
             for i, (a, b, c) in enumerate(pairs)]
    return int(np.argmax(areas))


def velocity_after_contact(normals: list[np.ndarray], vel: np.ndarray, ang_vel: np.ndarray) -> np.ndarray:
    """The ball's velocity after one tick's merged contact of ``normals`` (the ball kernel's solve, zero gravity;
    ``vel`` after this tick's drag)."""
    rows = np.zeros((1 + len(normals), bk._ROW))
    for r, n in enumerate(normals):
        bk._world_point(rows[1 + r], n, 0.0)
    n = sum(normals) / len(normals)  # RocketSim averages the normals without normalising them
    row = rows[0]
    row[bk._N:bk._N + 3] = n
    row[bk._RB:bk._RB + 3] = -n * C.BALL_RADIUS
    row[bk._MU] = C.BALL_FRICTION
    vb, wb = np.array(vel, dtype=np.float64), np.array(ang_vel, dtype=np.float64)
    approach = n @ vb + n @ np.cross(wb, row[bk._RB:bk._RB + 3])
    row[bk._TARGET] = max(C.BALL_RESTITUTION * -approach, 0.0) if abs(approach) >= bk.RESTITUTION_MIN_SPEED else 0.0
    row[bk._CAR] = bk.WORLD
    none = np.zeros((1, 3))
    bk._solve(rows, len(rows), vb, wb, none.copy(), none.copy(), np.zeros((1, 3, 3)), none.copy(), np.zeros(3),
              1.0 / 120.0)
    return vb
