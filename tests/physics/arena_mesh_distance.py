"""Signed distance from our analytic arena (``arena_geometry.arena_sdf``, the ball kernel's distance query) to the
game's: RocketSim's soccar collision meshes plus its four planes (floor z = 0, ceiling z = 2048, side walls
x = +-4096), sampled uniformly by area.

The sign is ``arena_sdf``'s at a point of the game's surface: positive where that point lies in our playable space
(the game's surface stands in front of ours), negative where it lies in our solid (ours stands in front).

Only the part of the game's surface that bounds its playable space is sampled: mesh points beyond a plane (the
meshes run a few uu under the floor and past the side walls) are dropped, and so are points that a mesh hides
(the floor under a fillet, the end of a corner mesh behind the back wall's): a point counts if the segment from it
to the arena's centre (to the goal's centre, for a point in a goal) meets no mesh triangle from behind first.

Shared by tests/physics/test_mesh_file.py and ``benchmarks/fidelity.py``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from rocketdrl_ma.physics.arena_geometry import arena_sdf_many
from rocketdrl_ma.physics.constants import ARENA_EXTENT_X, ARENA_HEIGHT
from rocketdrl_ma.physics.game_arena import game_arena_sdf_many
from rocketdrl_ma.physics.mesh_file import read_soccar_arena

GOAL_BACK_Y = 6000.0  # the back of the game's net; every mesh vertex has |y| <= 6000
ARENA_CENTRE = (0.0, 0.0, 0.5 * ARENA_HEIGHT)
GOAL_CENTRE = (0.0, 5560.0, 320.0)  # mirrored for the blue goal; sees the whole inside of the net
GOAL_BOX = (896.0, 5120.0, 640.0)  # |x| <=, |y| >=, z <=: a point in the game's goal (arena_mesh_profile.py)
OUR_FILLET_TOP_Z = 400.0  # issue 49 splits the walls at the top of our (pre-refit) 400 uu floor-to-wall ramp
# (origin, unit normal into the arena, edge u, edge v) of RocketSim's four planes, cut to the arena's bounding box
PLANES = (
    ((-ARENA_EXTENT_X, -GOAL_BACK_Y, 0.0), (0.0, 0.0, 1.0), (2 * ARENA_EXTENT_X, 0.0, 0.0),
     (0.0, 2 * GOAL_BACK_Y, 0.0)),
    ((-ARENA_EXTENT_X, -GOAL_BACK_Y, ARENA_HEIGHT), (0.0, 0.0, -1.0), (2 * ARENA_EXTENT_X, 0.0, 0.0),
     (0.0, 2 * GOAL_BACK_Y, 0.0)),
    ((-ARENA_EXTENT_X, -GOAL_BACK_Y, 0.0), (1.0, 0.0, 0.0), (0.0, 2 * GOAL_BACK_Y, 0.0), (0.0, 0.0, ARENA_HEIGHT)),
    ((ARENA_EXTENT_X, -GOAL_BACK_Y, 0.0), (-1.0, 0.0, 0.0), (0.0, 2 * GOAL_BACK_Y, 0.0), (0.0, 0.0, ARENA_HEIGHT)),
)
FAMILIES = ("floor", "floor-wall fillet", "walls below 400 uu", "walls above 400 uu", "corners",
            "wall-ceiling fillet", "ceiling", "goal mouth, posts, crossbar", "goal interior")
FLAT_NZ = 0.98  # |normal z| above this: floor, ceiling or goal roof
VERTICAL_NZ = 0.05  # |normal z| below this: a wall
GOAL_REGION_X = 1300.0  # the goal frame and the ramps beside the posts
GOAL_REGION_Z = 900.0
GOAL_FRAME_Y = 4700.0  # |y| from which the back wall curves round the posts and the crossbar
GOAL_INTERIOR_Y = 5200.0  # |y| past the frame's rounding: the net's floor, sides, roof and back
CORNER_X, CORNER_Y = 2550.0, 3550.0  # the corner walls with the game's ~860 uu roundings into the side and back walls


@dataclass(frozen=True)
class SurfaceSample:
    points: np.ndarray  # (n, 3) uu
    normals: np.ndarray  # (n, 3) unit, into the arena
    from_mesh: np.ndarray  # (n,) bool: a mesh point (False: a plane point)
    family: np.ndarray  # (n,) index into FAMILIES


@dataclass(frozen=True)
class FamilyRow:
    family: str
    points: int
    signed_min: float
    signed_max: float
    abs_percentiles: tuple[float, float, float, float]  # 50, 90, 99, 99.9
    abs_max: float
    worst_point: tuple[float, float, float]
    worst_signed: float


PERCENTILES = (50.0, 90.0, 99.0, 99.9)


def classify(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The index in FAMILIES of each surface point (by position and normal), first rule that matches."""
    x, y, z = np.abs(points[:, 0]), np.abs(points[:, 1]), points[:, 2]
    nz = np.abs(normals[:, 2])
    flat, vertical = nz > FLAT_NZ, nz < VERTICAL_NZ
    family = np.full(len(points), -1, dtype=np.int64)

    def put(mask: np.ndarray, name: str) -> None:
        family[(family < 0) & mask] = FAMILIES.index(name)

    floor = flat & (z < 0.5 * ARENA_HEIGHT) & (normals[:, 2] > 0.0)
    goal = (x < GOAL_REGION_X) & (z < GOAL_REGION_Z)
    put(goal & (y > GOAL_INTERIOR_Y), "goal interior")
    put(floor, "floor")
    put(goal & (y > GOAL_FRAME_Y), "goal mouth, posts, crossbar")
    put(flat, "ceiling")
    put(~vertical & (z < 0.5 * ARENA_HEIGHT), "floor-wall fillet")
    put(~vertical, "wall-ceiling fillet")
    put((x > CORNER_X) & (y > CORNER_Y), "corners")
    put(z < OUR_FILLET_TOP_Z, "walls below 400 uu")
    put(np.ones(len(points), dtype=bool), "walls above 400 uu")
    return family


def _sample_triangles(a: np.ndarray, b: np.ndarray, c: np.ndarray, n: int, rng: np.random.Generator) -> tuple:
    """n points uniform by area on the triangles (a, b, c), and the index of each one's triangle."""
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    tri = rng.choice(len(a), size=n, p=area / area.sum())
    r1, r2 = rng.random(n), rng.random(n)
    s = np.sqrt(r1)
    points = (1.0 - s)[:, None] * a[tri] + (s * (1.0 - r2))[:, None] * b[tri] + (s * r2)[:, None] * c[tri]
    return points, tri


@njit(cache=True)
def _leaves_through_a_back(points, targets, a, e1, e2, normal, lo, hi):
    """Per point: whether the first mesh triangle on the segment point -> its target is met from behind (normal
    along the segment): the point lies outside the game's playable space."""
    out = np.zeros(points.shape[0], dtype=np.bool_)
    for i in range(points.shape[0]):
        o = points[i]
        target = targets[i]
        d = target - o
        seg_lo = np.minimum(o, target)
        seg_hi = np.maximum(o, target)
        best_t = 1.0
        back = False
        for k in range(a.shape[0]):
            if (hi[k, 0] < seg_lo[0] or lo[k, 0] > seg_hi[0] or hi[k, 1] < seg_lo[1] or lo[k, 1] > seg_hi[1]
                    or hi[k, 2] < seg_lo[2] or lo[k, 2] > seg_hi[2]):
                continue
            # Moller-Trumbore, t in segment units (0 at the point, 1 at the target)
            px = d[1] * e2[k, 2] - d[2] * e2[k, 1]
            py = d[2] * e2[k, 0] - d[0] * e2[k, 2]
            pz = d[0] * e2[k, 1] - d[1] * e2[k, 0]
            det = e1[k, 0] * px + e1[k, 1] * py + e1[k, 2] * pz
            if abs(det) < 1e-12:
                continue
            inv = 1.0 / det
            sx, sy, sz = o[0] - a[k, 0], o[1] - a[k, 1], o[2] - a[k, 2]
            u = (sx * px + sy * py + sz * pz) * inv
            if u < 0.0 or u > 1.0:
                continue
            qx = sy * e1[k, 2] - sz * e1[k, 1]
            qy = sz * e1[k, 0] - sx * e1[k, 2]
            qz = sx * e1[k, 1] - sy * e1[k, 0]
            v = (d[0] * qx + d[1] * qy + d[2] * qz) * inv
            if v < 0.0 or u + v > 1.0:
                continue
            t = (e2[k, 0] * qx + e2[k, 1] * qy + e2[k, 2] * qz) * inv
            if 1e-6 < t < best_t:
                best_t = t
                back = normal[k, 0] * d[0] + normal[k, 1] * d[1] + normal[k, 2] * d[2] > 0.0
        out[i] = back
    return out


def _view_targets(points: np.ndarray) -> np.ndarray:
    """Where each point is seen from: the goal's centre for a point in a goal, else the arena's centre."""
    in_goal = ((np.abs(points[:, 0]) <= GOAL_BOX[0]) & (np.abs(points[:, 1]) >= GOAL_BOX[1])
               & (points[:, 2] <= GOAL_BOX[2]))
    targets = np.tile(np.array(ARENA_CENTRE), (len(points), 1))
    targets[in_goal] = GOAL_CENTRE
    targets[in_goal, 1] *= np.sign(points[in_goal, 1])
    return targets


class _Mesh:
    """The game's meshes as triangle arrays, with what the visibility test needs."""

    def __init__(self, mesh_folder: str | Path):
        vertices, triangles, _ = read_soccar_arena(mesh_folder)
        v = vertices.astype(np.float64)
        self.a, self.b, self.c = v[triangles[:, 0]], v[triangles[:, 1]], v[triangles[:, 2]]
        cross = np.cross(self.b - self.a, self.c - self.a)
        self.area = 0.5 * float(np.linalg.norm(cross, axis=1).sum())
        self.normal = cross / np.linalg.norm(cross, axis=1)[:, None]  # RocketSim's meshes wind towards the arena
        self.lo = np.minimum(np.minimum(self.a, self.b), self.c)
        self.hi = np.maximum(np.maximum(self.a, self.b), self.c)

    def visible(self, points: np.ndarray) -> np.ndarray:
        """Which points bound the game's playable space: inside RocketSim's planes and hidden by no mesh."""
        inside = (points[:, 2] >= 0.0) & (points[:, 2] <= ARENA_HEIGHT) & (np.abs(points[:, 0]) <= ARENA_EXTENT_X)
        hidden = _leaves_through_a_back(points, _view_targets(points), self.a, self.b - self.a, self.c - self.a,
                                        self.normal, self.lo, self.hi)
        return inside & ~hidden


def sample_game_surface(mesh_folder: str | Path, n_mesh_points: int, seed: int) -> SurfaceSample:
    """``n_mesh_points`` points on the meshes and as many per uu^2 on the planes (before the hidden ones are
    dropped), uniform by area, seeded; only points on the boundary of the game's playable space (see the module
    docstring)."""
    if n_mesh_points < 1:
        raise ValueError(f"n_mesh_points must be >= 1, got {n_mesh_points}")
    rng = np.random.default_rng(seed)
    mesh = _Mesh(mesh_folder)
    mesh_points, mesh_normals = [], []
    kept = 0
    while kept < n_mesh_points:  # hidden points are dropped: draw until enough are left
        p, tri = _sample_triangles(mesh.a, mesh.b, mesh.c, n_mesh_points, rng)
        keep = mesh.visible(p)
        mesh_points.append(p[keep])
        mesh_normals.append(mesh.normal[tri[keep]])
        kept += int(keep.sum())
    mesh_points = np.concatenate(mesh_points)[:n_mesh_points]
    mesh_normals = np.concatenate(mesh_normals)[:n_mesh_points]

    density = n_mesh_points / mesh.area
    plane_points, plane_normals = [], []
    for origin, normal, edge_u, edge_v in PLANES:
        area = float(np.linalg.norm(np.cross(edge_u, edge_v)))
        n = int(round(density * area))
        uv = rng.random((n, 2))
        plane_points.append(np.asarray(origin) + uv[:, :1] * np.asarray(edge_u) + uv[:, 1:] * np.asarray(edge_v))
        plane_normals.append(np.tile(normal, (n, 1)))
    plane_points, plane_normals = np.concatenate(plane_points), np.concatenate(plane_normals)
    keep = mesh.visible(plane_points)
    plane_points, plane_normals = plane_points[keep], plane_normals[keep]

    points = np.concatenate([mesh_points, plane_points])
    normals = np.concatenate([mesh_normals, plane_normals])
    from_mesh = np.concatenate([np.ones(len(mesh_points), bool), np.zeros(len(plane_points), bool)])
    return SurfaceSample(points, normals, from_mesh, classify(points, normals))


def distance_table(sample: SurfaceSample, arena_shape: str = "classic") -> list[FamilyRow]:
    """One row per surface family that has points, in FAMILIES order, then "all", for the arena shape's distance
    (``arena_sdf`` for "classic", ``game_arena_sdf`` for "game")."""
    sdf_many = {"classic": arena_sdf_many, "game": game_arena_sdf_many}.get(arena_shape)
    if sdf_many is None:
        raise ValueError(f"arena_shape: must be 'classic' or 'game', got {arena_shape!r}")
    signed = sdf_many(sample.points)
    rows = []
    for k, name in list(enumerate(FAMILIES)) + [(-1, "all")]:
        mask = sample.family == k if k >= 0 else np.ones(len(signed), dtype=bool)
        if not mask.any():
            continue
        d = signed[mask]
        worst = int(np.argmax(np.abs(d)))
        rows.append(FamilyRow(name, int(mask.sum()), float(d.min()), float(d.max()),
                              tuple(float(q) for q in np.percentile(np.abs(d), PERCENTILES)),
                              float(np.abs(d[worst])), tuple(float(q) for q in sample.points[mask][worst]),
                              float(d[worst])))
    return rows


def format_table(rows: list[FamilyRow]) -> str:
    """Markdown: per family the point count, signed range and |distance| percentiles, max and where."""
    lines = ["| surface family | points | signed min / max (uu) | abs p50 | p90 | p99 | p99.9 | abs max | "
             "worst point (x, y, z) |", "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        p50, p90, p99, p999 = r.abs_percentiles
        where = ", ".join(f"{q:.0f}" for q in r.worst_point)
        lines.append(f"| {r.family} | {r.points} | {r.signed_min:+.1f} / {r.signed_max:+.1f} | {p50:.2f} | "
                     f"{p90:.2f} | {p99:.2f} | {p999:.2f} | {r.abs_max:.2f} | ({where}) |")
    return "\n".join(lines)
