"""The game's arena dimensions measured on RocketSim's soccar meshes, next to ours: fillet and rounding radii from
circle fits to cross-sections, and the goal's size. The numbers a refit of ``arena_geometry`` needs.

A cross-section is the set of points where the meshes' triangle edges cross a plane; a radius is the
least-squares circle through the section's points in a window that holds one arc only (the fit's worst residual is
reported with it, so a window that caught a flat piece shows). Shared by ``benchmarks/fidelity.py``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rocketdrl_ma.physics import arena_geometry as G
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.mesh_file import read_soccar_arena


@dataclass(frozen=True)
class Measurement:
    name: str
    game: float  # uu
    ours: float  # uu
    fit_residual: float  # uu: the circle fit's worst point (0 for a direct reading)
    where: str


def cross_section(vertices: np.ndarray, triangles: np.ndarray, axis: int, value: float) -> np.ndarray:
    """(n, 3) points where the triangles' edges cross the plane coordinate[axis] = value."""
    out = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        a, b = vertices[triangles[:, i]], vertices[triangles[:, j]]
        da, db = a[:, axis] - value, b[:, axis] - value
        crossing = da * db < 0.0
        t = da[crossing] / (da[crossing] - db[crossing])
        out.append(a[crossing] + t[:, None] * (b[crossing] - a[crossing]))
    return np.unique(np.concatenate(out).round(3), axis=0)


def fit_circle(points_2d: np.ndarray) -> tuple[float, float, float, float]:
    """(centre u, centre v, radius, worst |distance - radius|) of the least-squares circle through the points."""
    if len(points_2d) < 3:
        raise ValueError(f"points_2d: a circle needs >= 3 points, got {len(points_2d)}")
    u, v = points_2d[:, 0], points_2d[:, 1]
    coef = np.linalg.lstsq(np.column_stack([2.0 * u, 2.0 * v, np.ones(len(u))]), u * u + v * v, rcond=None)[0]
    radius = float(np.sqrt(coef[2] + coef[0] ** 2 + coef[1] ** 2))
    residual = float(np.abs(np.hypot(u - coef[0], v - coef[1]) - radius).max())
    return float(coef[0]), float(coef[1]), radius, residual


def _arc(section: np.ndarray, axes: tuple[int, int], lo: tuple[float, float], hi: tuple[float, float]) -> tuple:
    """The circle through the section's points whose (axes) coordinates lie inside the open box lo..hi."""
    p = section[:, list(axes)]
    inside = np.all((p > np.array(lo)) & (p < np.array(hi)), axis=1)
    return fit_circle(p[inside])


def measure_game_arena(mesh_folder: str | Path) -> list[Measurement]:
    """The game's fillet and rounding radii and goal dimensions (first quadrant, x >= 0, y >= 0), and ours."""
    vertices, triangles, _ = read_soccar_arena(mesh_folder)
    v = vertices.astype(np.float64)
    x_wall, y_wall, height, r = C.ARENA_EXTENT_X, C.ARENA_EXTENT_Y, C.ARENA_HEIGHT, C.ARENA_FILLET_RADIUS
    out = []

    def radius(name: str, ours: float, where: str, axis: int, value: float, axes, lo, hi) -> None:
        *_, rad, res = _arc(cross_section(v, triangles, axis, value), axes, lo, hi)
        out.append(Measurement(name, rad, ours, res, where))

    radius("side wall to floor fillet", r, "x-z section at y = 2000", 1, 2000.5, (0, 2),
           (3000.0, 0.5), (x_wall - 1.0, 250.0))
    radius("side wall to ceiling fillet", r, "x-z section at y = 2000", 1, 2000.5, (0, 2),
           (3000.0, 1540.0), (x_wall - 1.0, height - 1.0))
    radius("back wall to floor fillet", r, "y-z section at x = 2000", 0, 2000.5, (1, 2),
           (4000.0, 0.5), (y_wall - 0.5, 159.0))
    radius("back wall to floor fillet beside the post", r, "y-z section at x = 950 (ours: the fairing's pipe)",
           0, 950.5, (1, 2), (4900.0, 0.5), (y_wall - 0.5, 95.0))
    radius("back wall to ceiling fillet", r, "y-z section at x = 2000", 0, 2000.5, (1, 2),
           (4000.0, 1540.0), (y_wall - 0.5, height - 1.0))
    # the corner wall's own fillets, on a section across its middle: coordinates (along, across, z) of the wall
    diagonal = np.column_stack([(v[:, 0] - v[:, 1]) * G.SQRT_HALF, (v[:, 0] + v[:, 1]) * G.SQRT_HALF, v[:, 2]])
    across = cross_section(diagonal, triangles, 0, -1024.0 * G.SQRT_HALF)
    corner_wall = C.ARENA_CORNER_SUM * G.SQRT_HALF
    *_, rad, res = _arc(across, (1, 2), (corner_wall - 400.0, 0.5), (corner_wall - 0.5, 250.0))
    out.append(Measurement("corner wall to floor fillet", rad, r, res, "section across the corner at x - y = -1024"))
    *_, rad, res = _arc(across, (1, 2), (corner_wall - 600.0, 1540.0), (corner_wall - 0.5, height - 1.0))
    out.append(Measurement("corner wall to ceiling fillet", rad, r, res, "section across the corner at x - y = -1024"))
    radius("side wall to corner wall rounding (vertical)", r, "x-y section at z = 1000", 2, 1000.5, (0, 1),
           (3845.0, 3340.0), (x_wall - 1.0, 4300.0))
    radius("corner wall to back wall rounding (vertical)", r, "x-y section at z = 1000", 2, 1000.5, (0, 1),
           (2690.0, 4800.0), (3195.0, y_wall - 0.1))

    # the goal: the net's side wall, roof and back, read off sections through its middle
    level = cross_section(v, triangles, 2, 300.5)
    net_side = level[(level[:, 1] > y_wall + 50.0) & (level[:, 1] < 5800.0) & (level[:, 0] > 0.0)]
    out.append(Measurement("goal half width (net side wall)", float(np.median(net_side[:, 0])), C.GOAL_HALF_WIDTH,
                           float(np.ptp(net_side[:, 0])), "x-y section at z = 300, 5170 < y < 5800"))
    back_wall = level[(np.abs(level[:, 1] - y_wall) < 0.05) & (level[:, 0] > 800.0) & (level[:, 0] < 1100.0)]
    out.append(Measurement("post edge bevel (back wall's end to the net's side)",
                           float(back_wall[:, 0].min() - np.median(net_side[:, 0])), 0.0, 0.0,
                           "x-y section at z = 300"))
    lip = cross_section(v, triangles, 0, 0.5)
    roof = lip[(lip[:, 1] > y_wall + 5.0) & (lip[:, 1] < y_wall + 300.0) & (lip[:, 2] > 300.0)]
    out.append(Measurement("goal height (roof behind the crossbar)", float(np.median(roof[:, 2])), C.GOAL_HEIGHT,
                           float(np.ptp(roof[:, 2])), "y-z section at x = 0, 5125 < y < 5420"))
    above = lip[(np.abs(lip[:, 1] - y_wall) < 0.05) & (lip[:, 2] > 600.0) & (lip[:, 2] < 800.0)]
    out.append(Measurement("crossbar edge bevel (back wall's end above the roof)",
                           float(above[:, 2].min() - np.median(roof[:, 2])), 0.0, 0.0, "y-z section at x = 0"))
    out.append(Measurement("back of the net", float(lip[:, 1].max()), G.GOAL_BACK_Y, 0.0, "y-z section at x = 0"))
    *_, rad, res = _arc(lip, (1, 2), (5790.0, 30.0), (G.GOAL_BACK_Y + 1.0, 480.0))
    out.append(Measurement("net back rounding (y-z)", rad, 0.0, res, "y-z section at x = 0, 30 < z < 480"))
    floor = lip[(lip[:, 1] > y_wall) & (lip[:, 2] < 20.0)]
    out.append(Measurement("net floor rise at the back", float(floor[:, 2].max()), 0.0, 0.0,
                           "y-z section at x = 0, the floor's highest point before the back's rounding"))
    return out


def format_measurements(rows: list[Measurement]) -> str:
    """Markdown: one row per dimension."""
    lines = ["| dimension | game (uu) | ours (uu) | game - ours | fit residual | where |",
             "|---|---:|---:|---:|---:|---|"]
    for m in rows:
        lines.append(f"| {m.name} | {m.game:.1f} | {m.ours:.1f} | {m.game - m.ours:+.1f} | {m.fit_residual:.2f} | "
                     f"{m.where} |")
    return "\n".join(lines)
