"""The game-shaped soccar arena: Rocket League's collision surface as analytic pieces (uu, z up).

Its dimensions are ``GAME_ARENA`` (data, measured on RocketSim's soccar meshes: see ``GameArenaDimensions``); this
module only turns them into a surface. It is the ``"game"`` arena
shape; ``arena_geometry`` is the ``"classic"`` one (one 400 uu fillet everywhere).

**Pieces.** The playable space is the union of these pieces:

- the *field*: the octagon (side walls, back walls, 45 degree corner walls) whose vertical corners are rounded
  (``side_corner_rounding``, ``corner_back_rounding``), with a profile swept along that outline: a floor fillet
  whose radius depends on where along the outline it is (256 on the side and corner walls, tapering to 160 round
  the corner-to-back rounding and to 96 beside the posts) and a ceiling fillet (512);
- per goal a *mouth* piece: the opening in the back wall, 904 uu half-wide and 648 high at the wall, bevelled by
  8 uu at 45 degrees onto the net's 896 x 640, its edges to the floor and roof rounded by 96;
- per goal the *net*: the slab |x| <= 896 intersected with the net's y-z section (floor flat then rising 16 uu,
  a half cylinder of radius 240 at the back, the roof flat then sloping down onto it), the edges where the slab
  meets the section rounded by 96;
- per post its *foot*: the 96 uu floor fillet revolved round the post's vertical edge, where the back wall's
  fillet turns into the net's.

The fillets are the meshes' polygons (8 chords, vertices on the circle at ``fillet_vertex_angles_deg``), not
circles.

**Distance.** Each piece's inside distance is exact or nearly (the floor fillet's radius varies slowly along the
outline); the union is their maximum, a lower bound near the seams. ``game_surface_contacts`` gives the contacts
RocketSim's ball gets from the meshes and planes (each face's nearest point, and at an edge between two faces
the direction to the centre clamped between their normals, as Bullet's internal-edge utility does);
``game_arena_raycast`` sphere-traces the union (its distance is a lower bound, so no step overshoots);
``game_arena_mesh`` sweeps the same polygons and drops the triangles that lie inside another piece.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit


@dataclass(frozen=True)
class GameArenaDimensions:
    """Rocket League's soccar arena in uu, measured on RocketSim's collision meshes: circle fits to cross-sections
    (``tests/physics/arena_mesh_profile.py``) and the meshes' vertices (docs/experiments/arena-mesh.md, "the game
    shape", lists both)."""
    side_x: float = 4096.0             # side walls |x| =
    back_y: float = 5120.0             # back walls |y| =
    corner_sum: float = 8064.0         # corner walls |x| + |y| =
    height: float = 2048.0             # ceiling z =
    # the vertical roundings (circle fits at z = 1000): tangent to the corner walls, 2.0 and 3.3 uu short of the
    # side and back walls (the game's walls step out there)
    side_corner_rounding: float = 864.27
    side_corner_rounding_centre: tuple[float, float] = (3229.7, 3612.3)
    corner_back_rounding: float = 852.09
    corner_back_rounding_centre: tuple[float, float] = (2593.8, 4264.6)
    floor_fillet: float = 256.0        # side and corner walls to the floor
    back_floor_fillet: float = 160.0   # back walls to the floor, away from the posts
    post_floor_fillet: float = 96.0    # back walls to the floor beside the posts
    # The floor fillet's radius where it changes, read off the meshes' vertices (linear between them): round the
    # corner-to-back rounding by the angle (degrees) about its centre, and along the back wall by |x|.
    corner_back_floor_fillet: tuple[tuple[float, float], ...] = (
        (44.7, 256.0), (50.8, 251.6), (56.7, 240.6), (62.6, 225.3), (68.4, 208.0), (74.3, 190.8), (80.2, 175.4),
        (86.1, 160.0))
    back_floor_fillet_by_x: tuple[tuple[float, float], ...] = (
        (960.0, 96.0), (1024.0, 100.6), (1088.0, 112.5), (1152.0, 127.8), (1216.0, 143.2), (1280.0, 155.1),
        (1344.0, 160.0))
    ceiling_fillet: float = 512.0      # every wall to the ceiling
    # The fillets are polygons (their vertices on the circle): the vertices' angles from the wall's tangent point
    # to the floor's or ceiling's, the same on every wall and both fillets.
    fillet_vertex_angles_deg: tuple[float, ...] = (0.0, 11.6, 22.9, 34.0, 45.0, 56.0, 67.1, 78.4, 90.0)
    goal_half_width: float = 896.0     # the net's side walls |x| =
    goal_height: float = 640.0         # the roof behind the crossbar
    frame_bevel: float = 8.0           # posts and crossbar: 45 degree bevels from the back wall onto the net
    net_edge_rounding: float = 96.0    # the net's side walls to its floor, roof and back
    net_roof_slope_start_y: float = 5344.0  # |y| where the roof starts sloping down onto the back
    net_floor_rise_start_y: float = 5355.0  # |y| where the floor starts rising
    net_floor_rise: float = 16.0       # uu the floor has risen at net_back_centre_y
    net_back_centre_y: float = 5760.0  # the back half cylinder's axis (|y|, z)
    net_back_centre_z: float = 256.0
    net_back_radius: float = 240.0     # reaches |y| = 6000


GAME_ARENA = GameArenaDimensions()

_D = GAME_ARENA
SIDE_X, BACK_Y, CORNER_SUM, HEIGHT = _D.side_x, _D.back_y, _D.corner_sum, _D.height
R1, R2 = _D.side_corner_rounding, _D.corner_back_rounding
SQRT_HALF = math.sqrt(0.5)
C1X, C1Y = _D.side_corner_rounding_centre
C2X, C2Y = _D.corner_back_rounding_centre
RF_SIDE, RF_BACK, RF_POST = _D.floor_fillet, _D.back_floor_fillet, _D.post_floor_fillet
CORNER_TAPER_DEG = np.array([p[0] for p in _D.corner_back_floor_fillet])
CORNER_TAPER_R = np.array([p[1] for p in _D.corner_back_floor_fillet])
BACK_TAPER_X = np.array([p[0] for p in _D.back_floor_fillet_by_x])
BACK_TAPER_R = np.array([p[1] for p in _D.back_floor_fillet_by_x])
RC = _D.ceiling_fillet
_ANG = np.radians(np.array(_D.fillet_vertex_angles_deg))
CHORD_COS_MID = np.cos(0.5 * (_ANG[1:] + _ANG[:-1]))  # each chord's normal, from the fillet's centre outwards
CHORD_SIN_MID = np.sin(0.5 * (_ANG[1:] + _ANG[:-1]))
CHORD_COS_HALF = np.cos(0.5 * (_ANG[1:] - _ANG[:-1]))  # the chord's distance from the centre, per unit radius
VERTEX_A = 1.0 - np.cos(_ANG)  # the polygon's vertices per unit radius: from the wall, from the floor
VERTEX_B = 1.0 - np.sin(_ANG)
CHORD_MID = 0.5 * (_ANG[1:] + _ANG[:-1])  # the angle of each chord's normal in (from the wall, from the floor)
GW, GH, BEVEL = _D.goal_half_width, _D.goal_height, _D.frame_bevel
MOUTH_W = GW + BEVEL                       # the opening at the back wall
MOUTH_H = GH + BEVEL
NET_R = _D.net_edge_rounding
ROOF_Y = _D.net_roof_slope_start_y
RISE_Y = _D.net_floor_rise_start_y
BACK_CY, BACK_CZ, BACK_R = _D.net_back_centre_y, _D.net_back_centre_z, _D.net_back_radius
RISE_K = _D.net_floor_rise / (BACK_CY - RISE_Y)  # floor slope
RISE_N = 1.0 / math.sqrt(1.0 + RISE_K * RISE_K)
# the roof's slope: the line from (ROOF_Y, GH) tangent to the back circle (on its upper side)
_dy, _dz = BACK_CY - ROOF_Y, BACK_CZ - GH
_L = math.hypot(_dy, _dz)
_ang = math.atan2(_dz, _dy) + math.asin(BACK_R / _L)
ROOF_DIR_Y, ROOF_DIR_Z = math.cos(_ang), math.sin(_ang)  # along the roof from (ROOF_Y, GH) down to the tangent
ROOF_NY, ROOF_NZ = ROOF_DIR_Z, -ROOF_DIR_Y  # the slope's normal into the net (down and forward)
ROOF_C = ROOF_NY * ROOF_Y + ROOF_NZ * GH
PIECE_START_Y = BACK_Y - RF_BACK - 64.0    # the goal pieces start inside the field (the mouth's floor runs flat)
assert ROOF_NZ < 0.0 and C2X > MOUTH_W and C1Y > 0.0

_FAR = 1e30
RAY_TOL = 1e-4          # uu: a sphere-traced ray has hit when the distance is below this
RAY_MAX_STEPS = 400
MESH_MAX_EDGE = 500.0   # longest edge of the flat mesh parts (uu)


# ================================================================= the field
@njit(cache=True, nogil=True, inline="always")
def _floor_fillet(piece, ax, t):
    """The floor fillet's radius at the outline point of ``piece`` (0 side, 1 side rounding, 2 corner,
    3 corner rounding, 4 back) at parameter t (the rounding's angle share, or |x| on the back wall)."""
    if piece <= 2:
        return RF_SIDE
    if piece == 3:  # 256 to 160 round the corner-to-back rounding
        return np.interp(45.0 + 45.0 * t, CORNER_TAPER_DEG, CORNER_TAPER_R)
    return np.interp(ax, BACK_TAPER_X, BACK_TAPER_R)  # 160 tapering to 96 beside the posts


@njit(cache=True, nogil=True)
def _outline(ax, ay):
    """Signed distance from the folded point (|x|, |y|) to the rounded octagon (positive outside), the outward
    unit normal (folded) of its nearest point, and that point's piece and parameter (see ``_floor_fillet``)."""
    # the Voronoi wedges of the convex outline's pieces, from the centres of the roundings
    ux, uy = ax - C1X, ay - C1Y
    if uy >= 0.0 and ux >= uy:  # side-to-corner rounding
        L = math.sqrt(ux * ux + uy * uy)
        if L > 1e-9:
            out_d = L - R1
            if out_d >= 0.0 or -out_d < _inside_others(ax, ay):
                return out_d, ux / L, uy / L, 1, math.atan2(uy, ux) / (0.25 * math.pi)
    vx, vy = ax - C2X, ay - C2Y
    if vx >= 0.0 and vy >= vx:  # corner-to-back rounding
        L = math.sqrt(vx * vx + vy * vy)
        if L > 1e-9:
            out_d = L - R2
            if out_d >= 0.0 or -out_d < _inside_others(ax, ay):
                return out_d, vx / L, vy / L, 3, (math.atan2(vy, vx) - 0.25 * math.pi) / (0.25 * math.pi)
    # the flat walls: the nearest of the three lines whose segment the point projects onto
    e_side = ax - SIDE_X
    e_back = ay - BACK_Y
    e_corner = (ax + ay - CORNER_SUM) * SQRT_HALF
    best, nx, ny, piece = -_FAR, 0.0, 0.0, 0
    if ay <= C1Y and e_side > best:
        best, nx, ny, piece = e_side, 1.0, 0.0, 0
    if ax <= C2X and e_back > best:
        best, nx, ny, piece = e_back, 0.0, 1.0, 4
    if ay - ax >= C1Y - SIDE_X and ay - ax <= BACK_Y - C2X and e_corner > best:
        best, nx, ny, piece = e_corner, SQRT_HALF, SQRT_HALF, 2
    if best <= -_FAR:  # beyond every wedge (far outside, numerically): the largest line distance
        best, nx, ny, piece = max(e_side, e_back, e_corner), 1.0, 0.0, 0
    return best, nx, ny, piece, 0.0


@njit(cache=True, nogil=True, inline="always")
def _inside_others(ax, ay):
    """Inside distance to the flat walls (a point in a rounding's wedge may still be nearer a wall inside)."""
    d = _FAR
    if ay <= C1Y:
        d = min(d, SIDE_X - ax)
    if ax <= C2X:
        d = min(d, BACK_Y - ay)
    if ay - ax >= C1Y - SIDE_X and ay - ax <= BACK_Y - C2X:
        d = min(d, (CORNER_SUM - ax - ay) * SQRT_HALF)
    return d


@njit(cache=True, nogil=True, inline="always")
def _polygon_fillet(a, b, r):
    """Inside distance in a fillet's corner (a from the wall, b from the floor or ceiling, both < r) to the wall,
    the floor and the fillet's chords (a convex polygon: the nearest of their lines inside it), and its gradient
    (along a, along b)."""
    if a <= b:
        d, ga, gb = a, 1.0, 0.0
    else:
        d, ga, gb = b, 0.0, 1.0
    u, v = r - a, r - b  # from the fillet's centre towards the wall and towards the floor
    for k in range(CHORD_COS_MID.shape[0]):
        f = r * CHORD_COS_HALF[k] - (u * CHORD_COS_MID[k] + v * CHORD_SIN_MID[k])
        if f < d:
            d, ga, gb = f, CHORD_COS_MID[k], CHORD_SIN_MID[k]
    return d, ga, gb


@njit(cache=True, nogil=True)
def _field(x, y, z):
    """Signed distance to the field (positive inside) and its unit gradient (into the field)."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    ax, ay = abs(x), abs(y)
    s, ox, oy, piece, t = _outline(ax, ay)
    rf = _floor_fillet(piece, ax, t)
    a = -s  # inside distance from the wall
    if a < rf and z < rf:  # the floor fillet
        d, ga, gb = _polygon_fillet(a, z, rf)
        return d, -sx * ox * ga, -sy * oy * ga, gb
    c = HEIGHT - z
    if a < RC and c < RC:  # the ceiling fillet
        d, ga, gb = _polygon_fillet(a, c, RC)
        return d, -sx * ox * ga, -sy * oy * ga, -gb
    if a <= z and a <= c:
        return a, -sx * ox, -sy * oy, 0.0
    if z <= c:
        return z, 0.0, 0.0, 1.0
    return c, 0.0, 0.0, -1.0


# ================================================================= the goals
@njit(cache=True, nogil=True, inline="always")
def _round_join(a, ga, b, gb, r):
    """Inside distance of the intersection of two sets (inside distances a, b and their gradients) with the edge
    between them rounded by r."""
    if a < r and b < r:
        u, v = r - a, r - b
        L = math.sqrt(u * u + v * v)
        if L > 1e-12:
            return r - L, (u * ga[0] + v * gb[0]) / L, (u * ga[1] + v * gb[1]) / L, (u * ga[2] + v * gb[2]) / L
    if a <= b:
        return a, ga[0], ga[1], ga[2]
    return b, gb[0], gb[1], gb[2]


@njit(cache=True, nogil=True)
def _net_section(ay, z):
    """Inside distance of the net's y-z section (folded |y|) and its gradient (gy, gz): the floor (flat, then
    rising), the roof (flat, then sloping) and, behind the back's axis, the half cylinder."""
    d, gy, gz = z, 0.0, 1.0  # floor
    f = (z - RISE_K * (ay - RISE_Y)) * RISE_N  # rising floor
    if f < d:
        d, gy, gz = f, -RISE_K * RISE_N, RISE_N
    f = GH - z  # roof
    if f < d:
        d, gy, gz = f, 0.0, -1.0
    f = ROOF_NY * ay + ROOF_NZ * z - ROOF_C  # sloping roof
    if f < d:
        d, gy, gz = f, ROOF_NY, ROOF_NZ
    u, v = ay - BACK_CY, z - BACK_CZ
    if u > 0.0 and u * ROOF_NZ - v * ROOF_NY <= 0.0:  # the half cylinder, up to where the roof's slope meets it
        L = math.sqrt(u * u + v * v)
        f = BACK_R - L
        if f < d and L > 1e-12:
            d, gy, gz = f, -u / L, -v / L
    return d, gy, gz


@njit(cache=True, nogil=True)
def _net(x, y, z):
    """Signed distance to the net on y's side (positive inside) and its gradient."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    b, gy, gz = _net_section(abs(y), z)
    d, nx, ny, nz = _round_join(GW - abs(x), (-sx, 0.0, 0.0), b, (0.0, sy * gy, gz), NET_R)
    f = abs(y) - PIECE_START_Y  # the front, inside the field (not rounded)
    if f < d:
        return f, 0.0, sy, 0.0
    return d, nx, ny, nz


@njit(cache=True, nogil=True)
def _mouth(x, y, z):
    """Signed distance to the goal mouth on y's side (the opening in the back wall with its bevels, from inside
    the field to where the bevels meet the net) and its gradient."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    ax, ay = abs(x), abs(y)
    # across: |x| <= MOUTH_W and the bevel |x| + |y| <= MOUTH_W + back_y
    a, gax, gay = MOUTH_W - ax, -sx, 0.0
    f = (MOUTH_W + BACK_Y - ax - ay) * SQRT_HALF
    if f < a:
        a, gax, gay = f, -sx * SQRT_HALF, -sy * SQRT_HALF
    # up: floor, roof z <= MOUTH_H and its bevel z + |y| <= MOUTH_H + back_y, front and back (the net takes over)
    b, gby, gbz = z, 0.0, 1.0
    f = MOUTH_H - z
    if f < b:
        b, gby, gbz = f, 0.0, -1.0
    f = (MOUTH_H + BACK_Y - z - ay) * SQRT_HALF
    if f < b:
        b, gby, gbz = f, -sy * SQRT_HALF, -SQRT_HALF
    d, nx, ny, nz = _round_join(a, (gax, gay, 0.0), b, (0.0, gby, gbz), NET_R)
    f = ay - PIECE_START_Y  # the front and the back (where the net takes over) are not rounded
    if f < d:
        d, nx, ny, nz = f, 0.0, sy, 0.0
    f = BACK_Y + BEVEL + 1.0 - ay
    if f < d:
        d, nx, ny, nz = f, 0.0, -sy, 0.0
    return d, nx, ny, nz


@njit(cache=True, nogil=True)
def _post_foot(x, y, z):
    """Signed distance to the space round the foot of the post on (x, y)'s side (positive inside) and its
    gradient: the post's floor fillet revolved round its vertical edge at (MOUTH_W, back_y + BEVEL), where the
    post is a quarter cylinder of radius BEVEL, up to the fillet's top; between the back wall (facing -y) and the
    net's side (facing -x)."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    u, v = MOUTH_W - abs(x), BACK_Y + BEVEL - abs(y)  # from the post's edge towards the goal and the field
    if u <= 0.0 or v <= 0.0:  # outside the wedge: the nearer of its sides
        if u <= v:
            return u, -sx, 0.0, 0.0
        return v, 0.0, -sy, 0.0
    rho = math.sqrt(u * u + v * v)
    ru, rv = -sx * u / rho, -sy * v / rho  # the gradient of rho
    a = rho - BEVEL
    if a < RF_POST and z < RF_POST:
        d, ga, gb = _polygon_fillet(a, z, RF_POST)
        d, gx, gy, gz = d, ga * ru, ga * rv, gb
    elif a <= z:
        d, gx, gy, gz = a, ru, rv, 0.0
    else:
        d, gx, gy, gz = z, 0.0, 0.0, 1.0
    if RF_POST - z < d:  # the fillet's top (inside the field and the mouth)
        d, gx, gy, gz = RF_POST - z, 0.0, 0.0, -1.0
    if u < d:
        d, gx, gy, gz = u, -sx, 0.0, 0.0
    if v < d:
        d, gx, gy, gz = v, 0.0, -sy, 0.0
    return d, gx, gy, gz


@njit(cache=True, nogil=True)
def game_arena_sdf(x, y, z):
    """(d, nx, ny, nz): signed distance in uu (positive in the playable space) and the unit normal into it."""
    d, nx, ny, nz = _field(x, y, z)
    if abs(y) > PIECE_START_Y:
        g, gx, gy, gz = _net(x, y, z)
        if g > d:
            d, nx, ny, nz = g, gx, gy, gz
        g, gx, gy, gz = _mouth(x, y, z)
        if g > d:
            d, nx, ny, nz = g, gx, gy, gz
        g, gx, gy, gz = _post_foot(x, y, z)
        if g > d:
            d, nx, ny, nz = g, gx, gy, gz
    return d, nx, ny, nz


@njit(cache=True, nogil=True)
def _sdf_many(points):
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        out[i] = game_arena_sdf(points[i, 0], points[i, 1], points[i, 2])[0]
    return out


def game_arena_sdf_many(points: np.ndarray) -> np.ndarray:
    """``game_arena_sdf`` distances of an (n, 3) array of points."""
    return _sdf_many(np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3))


# ================================================================= contacts
@njit(cache=True, nogil=True)
def _piece(k, x, y, z):
    if k == 0:
        return _field(x, y, z)
    if k == 1:
        return _net(x, y, z)
    if k == 2:
        return _mouth(x, y, z)
    return _post_foot(x, y, z)


@njit(cache=True, nogil=True)
def _on_surface(qx, qy, qz, own):
    """Whether a surface point of piece ``own`` (0 field, 1 net, 2 mouth, 3 post foot; -1 an edge) lies inside no
    other piece."""
    for k in range(4):
        if k != own and (k == 0 or abs(qy) > PIECE_START_Y) and _piece(k, qx, qy, qz)[0] > 1e-3:
            return False
    return True


@njit(cache=True, nogil=True)
def _add(out, n, d, nx, ny, nz):
    """Row n of ``out`` = (d, normal) unless the same contact is there already. Returns the count."""
    for r in range(n):
        if abs(out[r, 0] - d) < 1e-3 and out[r, 1] * nx + out[r, 2] * ny + out[r, 3] * nz > 1.0 - 1e-6:
            return n
    if n < out.shape[0]:
        out[n, 0], out[n, 1], out[n, 2], out[n, 3] = d, nx, ny, nz
        n += 1
    return n


@njit(cache=True, nogil=True)
def _add_point(out, n, x, y, z, qx, qy, qz, reach):
    """The surface point q (an edge's or a bevel's nearest point) as a contact, the normal from q to the centre."""
    dx, dy, dz = x - qx, y - qy, z - qz
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if d <= 1e-9 or d > reach or not _on_surface(qx, qy, qz, -1):
        return n
    return _add(out, n, d, dx / d, dy / d, dz / d)


@njit(cache=True, nogil=True)
def _in_a_goal_piece(qx, qy, qz):
    """Whether a point of the field's surface lies inside a goal piece (the opening cut into the back wall)."""
    if abs(qy) <= PIECE_START_Y:
        return False
    return _net(qx, qy, qz)[0] > 1e-3 or _mouth(qx, qy, qz)[0] > 1e-3 or _post_foot(qx, qy, qz)[0] > 1e-3


@njit(cache=True, nogil=True)
def _add_field_point(out, n, x, y, z, qx, qy, qz, reach):
    """A point q of the field's surface as a contact (normal from q to the centre) if within reach and real."""
    dx, dy, dz = x - qx, y - qy, z - qz
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if d <= 1e-9 or d > reach or _in_a_goal_piece(qx, qy, qz):
        return n
    return _add(out, n, d, dx / d, dy / d, dz / d)


@njit(cache=True, nogil=True)
def _fillet_contacts(out, n, a, b, r, wall_is_a_plane, wx, wy, zs, reach, x, y, z):
    """The faces and edges of one fillet's polygon within reach of a centre at (a from the wall, b from the floor
    or ceiling), as Bullet's sphere-triangle test with RocketSim's internal-edge adjustment gives them: a chord's
    nearest point with its normal, and at an edge between two faces (chords, or the first chord and a mesh wall)
    the direction to the centre clamped between the two faces' normals. The mesh runs the outer chords on past
    the floor or ceiling plane and past a side wall's plane, so those ends have no edge. (wx, wy, zs): the 3D
    directions of a and b's growth; (x, y, z) the centre, so that a point of the fillet cut away by a goal's
    opening (the back walls' floor fillets run on across the goal mouths) makes no contact."""
    n_chords = CHORD_MID.shape[0]
    for c in range(n_chords):
        a0, b0 = r * VERTEX_A[c], r * VERTEX_B[c]
        ea, eb = r * VERTEX_A[c + 1] - a0, r * VERTEX_B[c + 1] - b0
        u = ((a - a0) * ea + (b - b0) * eb) / (ea * ea + eb * eb)
        lo = -_FAR if (c == 0 and wall_is_a_plane) else 0.0
        hi = _FAR if c == n_chords - 1 else 1.0
        if lo <= u <= hi:  # the face
            da, db = a - (a0 + u * ea), b - (b0 + u * eb)
            d = math.sqrt(da * da + db * db)
            if d <= reach and not _in_a_goal_piece(x - da * wx, y - da * wy, z - db * zs):
                ca, cb = math.cos(CHORD_MID[c]), math.sin(CHORD_MID[c])
                n = _add(out, n, d, ca * wx, ca * wy, cb * zs)
    for j in range(0 if not wall_is_a_plane else 1, n_chords):  # the edges between faces
        da, db = a - r * VERTEX_A[j], b - r * VERTEX_B[j]
        d = math.sqrt(da * da + db * db)
        if d > reach or d <= 1e-9 or _in_a_goal_piece(x - da * wx, y - da * wy, z - db * zs):
            continue
        phi = math.atan2(db, da)
        phi = min(max(phi, CHORD_MID[j - 1] if j > 0 else 0.0), CHORD_MID[j])
        ca, cb = math.cos(phi), math.sin(phi)
        n = _add(out, n, d, ca * wx, ca * wy, cb * zs)
    return n


@njit(cache=True, nogil=True)
def _field_contacts(x, y, z, reach, out, n):
    """The field's faces within reach, as a triangle mesh plus RocketSim's planes gives them (each face its own
    nearest point, hidden or not): the floor, ceiling and side-wall planes, each chord of the fillets' polygons,
    the wall between the fillets and, elsewhere, the field's nearest point (the vertical roundings)."""
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    ax, ay = abs(x), abs(y)
    if z <= reach:
        n = _add_field_point(out, n, x, y, z, x, y, 0.0, reach)
    if HEIGHT - z <= reach:
        n = _add_field_point(out, n, x, y, z, x, y, HEIGHT, reach)
    if SIDE_X - ax <= reach:
        n = _add_field_point(out, n, x, y, z, sx * SIDE_X, y, z, reach)
    s, ox, oy, piece, t = _outline(ax, ay)
    a = -s
    if a > reach + RC:
        return n
    rf = _floor_fillet(piece, ax, t)
    in_fillet = False
    for k in range(2):  # the floor's fillet, then the ceiling's
        r = rf if k == 0 else RC
        b = z if k == 0 else HEIGHT - z
        if a >= r + reach or b >= r + reach:
            continue
        in_fillet = in_fillet or (a < r and b < r)
        zs = 1.0 if k == 0 else -1.0
        n = _fillet_contacts(out, n, a, b, r, piece == 0, -sx * ox, -sy * oy, zs, reach, x, y, z)
    if piece != 0 and 0.0 <= a <= reach and rf <= z <= HEIGHT - RC:  # a mesh wall between the fillets
        n = _add_field_point(out, n, x, y, z, sx * (ax - s * ox), sy * (ay - s * oy), z, reach)
    if not in_fillet:
        d, nx, ny, nz = _field(x, y, z)
        if d <= reach and not _in_a_goal_piece(x - nx * d, y - ny * d, z - nz * d):
            n = _add(out, n, d, nx, ny, nz)
    return n


@njit(cache=True, nogil=True)
def game_surface_contacts(x, y, z, reach, out):
    """Where a sphere at (x, y, z) reaching ``reach`` uu meets the game arena: rows (distance, nx, ny, nz) of
    ``out`` (normals into the arena), one per surface it reaches. Returns the number of rows.

    The field's faces count as RocketSim's meshes and planes give them (``_field_contacts``); near a goal each goal
    piece's nearest point counts if no other piece covers it, and the bevels of the posts and the crossbar are
    added as strips (their nearest point, which is an edge when the centre is off the strip)."""
    n = _field_contacts(x, y, z, reach, out, 0)
    near_goal = abs(y) > PIECE_START_Y - reach and abs(x) < MOUTH_W + RF_BACK + reach and z < MOUTH_H + reach
    for k in range(1, 4 if near_goal else 1):
        d, nx, ny, nz = _piece(k, x, y, z)
        if d <= reach and _on_surface(x - nx * d, y - ny * d, z - nz * d, k):
            n = _add(out, n, d, nx, ny, nz)
    if not near_goal or game_arena_sdf(x, y, z)[0] < 0.0:
        return n
    sx = 1.0 if x >= 0.0 else -1.0
    sy = 1.0 if y >= 0.0 else -1.0
    ax, ay = abs(x), abs(y)
    # The post: in (|x|, |y|) the back wall (normal at 270 degrees), its edge at (MOUTH_W, back_y), the bevel
    # (225), its edge at (GW, back_y + BEVEL) and the net's side (180); along z between the roundings.
    if NET_R <= z <= GH - NET_R:
        t = ((MOUTH_W - ax) + (ay - BACK_Y)) * 0.5 / BEVEL
        if 0.0 < t < 1.0:  # the bevel's face
            n = _add_point(out, n, x, y, z, sx * (MOUTH_W - t * BEVEL), sy * (BACK_Y + t * BEVEL), z, reach)
        for ex, ey, lo, hi in ((MOUTH_W, BACK_Y, 1.25, 1.5), (GW, BACK_Y + BEVEL, 1.0, 1.25)):
            n = _frame_edge(out, n, ax - ex, ay - ey, lo, hi, sx, 0.0, 0.0, 0.0, sy, 0.0, reach)
    # The crossbar: in (|y|, z) the back wall (180 degrees), its edge at (back_y, MOUTH_H), the bevel (225), its
    # edge at (back_y + BEVEL, GH) and the net's roof (270); along x between the roundings.
    if abs(x) <= GW - NET_R:
        t = ((MOUTH_H - z) + (ay - BACK_Y)) * 0.5 / BEVEL
        if 0.0 < t < 1.0:
            n = _add_point(out, n, x, y, z, x, sy * (BACK_Y + t * BEVEL), MOUTH_H - t * BEVEL, reach)
        for ey, ez, lo, hi in ((BACK_Y, MOUTH_H, 1.0, 1.25), (BACK_Y + BEVEL, GH, 1.25, 1.5)):
            n = _frame_edge(out, n, ay - ey, z - ez, lo, hi, 0.0, sy, 0.0, 0.0, 0.0, 1.0, reach)
    return n


@njit(cache=True, nogil=True)
def _frame_edge(out, n, du, dv, lo, hi, ux, uy, uz, vx, vy, vz, reach):
    """An edge of the goal frame seen from a centre at (du, dv) from it in the frame's section, as Bullet with
    RocketSim's internal-edge adjustment gives it: the direction to the centre, clamped between the normals of the
    two faces that meet there (angles lo..hi in half turns). The section's axes u and v are (ux, uy, uz) and
    (vx, vy, vz) in 3D."""
    d = math.sqrt(du * du + dv * dv)
    if d > reach or d <= 1e-9:
        return n
    phi = math.atan2(dv, du) / math.pi
    if phi < 0.0:
        phi += 2.0
    phi = min(max(phi, lo), hi) * math.pi
    cu, cv = math.cos(phi), math.sin(phi)
    return _add(out, n, d, cu * ux + cv * vx, cu * uy + cv * vy, cu * uz + cv * vz)


# ================================================================= ray casts
@njit(cache=True, nogil=True)
def game_arena_raycast(ox, oy, oz, dx, dy, dz, max_len):
    """First surface hit of the unit ray (dx, dy, dz) from (ox, oy, oz) within max_len uu: (hit, t, nx, ny, nz),
    the normal pointing into the interior. Sphere tracing: the union's distance never exceeds the distance to the
    surface, so each step stays in the playable space. An origin in solid hits at t = 0 with the distance field's
    normal; a miss returns (False, max_len, 0, 0, 0)."""
    d, nx, ny, nz = game_arena_sdf(ox, oy, oz)
    if d < 0.0:
        return True, 0.0, nx, ny, nz
    t = 0.0
    for _ in range(RAY_MAX_STEPS):
        if d <= RAY_TOL:
            return True, t, nx, ny, nz
        t += d
        if t > max_len:
            return False, max_len, 0.0, 0.0, 0.0
        d, nx, ny, nz = game_arena_sdf(ox + dx * t, oy + dy * t, oz + dz * t)
    return True, t, nx, ny, nz


# ================================================================= the surface mesh
ROUNDING_SEGMENTS = 16  # mesh pieces per 45 degrees of a vertical rounding
WALL_END_GAP = 0.01     # uu: a flat wall's last mesh station before its rounding's tangent line


def _quadrant_outline() -> list[tuple[float, float, float, float, int, float]]:
    """(x, y, outward nx, ny, piece, parameter) stations along the outline in the first quadrant, from the side
    wall at y = 0 to the back wall at x = 0 (pieces and parameters as ``_floor_fillet`` reads them)."""
    out = []
    # Each flat wall runs to just short of the rounding's tangent line (the rounding starts 2.0 / 3.3 uu off the
    # wall there): a quad from the wall's last station to the rounding's first would be twisted off the surface
    # and left out, and the cars' boxes would go through the wall.
    side_ys = np.linspace(0.0, C1Y, max(2, math.ceil(C1Y / MESH_MAX_EDGE)) + 1)
    side_ys[-1] = C1Y - WALL_END_GAP
    for y in side_ys:
        out.append((SIDE_X, float(y), 1.0, 0.0, 0, 0.0))
    for a in np.linspace(0.0, 0.25 * math.pi, ROUNDING_SEGMENTS + 1):
        out.append((C1X + R1 * math.cos(a), C1Y + R1 * math.sin(a), math.cos(a), math.sin(a), 1, a / (0.25 * math.pi)))
    for a in np.linspace(0.25 * math.pi, 0.5 * math.pi, ROUNDING_SEGMENTS + 1):
        out.append((C2X + R2 * math.cos(a), C2Y + R2 * math.sin(a), math.cos(a), math.sin(a), 3,
                    (a - 0.25 * math.pi) / (0.25 * math.pi)))
    xs = sorted({0.0, MOUTH_W, *BACK_TAPER_X.tolist(), *np.linspace(0.0, MOUTH_W, 5).tolist(),
                 *np.linspace(BACK_TAPER_X[-1], C2X - WALL_END_GAP, 5).tolist()}, reverse=True)
    for x in xs:
        out.append((float(x), BACK_Y, 0.0, 1.0, 4, 0.0))
    return out


def _field_profile(rf: float) -> list[tuple[float, float]]:
    """(inside distance from the wall a, z) from the floor's edge up the fillet's polygon, the wall and the ceiling
    fillet's polygon."""
    floor = [(rf - rf * math.cos(th), rf - rf * math.sin(th)) for th in _ANG[::-1]]
    wall = [(0.0, z) for z in (MOUTH_H, *np.linspace(rf, HEIGHT - RC, 4)[1:-1]) if rf < z < HEIGHT - RC]
    wall.sort(key=lambda p: p[1])
    ceiling = [(RC - RC * math.cos(th), HEIGHT - RC + RC * math.sin(th)) for th in _ANG]
    return floor + wall + ceiling


class _Mesh:
    def __init__(self) -> None:
        self.verts: list[tuple[float, float, float]] = []
        self.tris: list[tuple[int, int, int]] = []

    def v(self, p) -> int:
        self.verts.append((float(p[0]), float(p[1]), float(p[2])))
        return len(self.verts) - 1

    def grid(self, rows: list[list[tuple[float, float, float]]], closed: bool = False) -> None:
        """Quads between consecutive rows of the same length (closed: the last row joins the first), each split
        along the diagonal from the row nearer a mirror plane (x = 0 or y = 0), so that the mesh is as
        mirror-symmetric as the arena (one diagonal everywhere pushed a car sideways where it met a fillet)."""
        ids = [[self.v(p) for p in row] for row in rows]
        pairs = list(zip(ids[:-1], ids[1:])) + ([(ids[-1], ids[0])] if closed else [])
        for r0, r1 in pairs:
            for k in range(len(r0) - 1):
                if self._off_mirror(r0[k]) <= self._off_mirror(r1[k]):
                    self.tris.append((r0[k], r1[k], r1[k + 1]))
                    self.tris.append((r0[k], r1[k + 1], r0[k + 1]))
                else:
                    self.tris.append((r0[k], r1[k], r0[k + 1]))
                    self.tris.append((r1[k], r1[k + 1], r0[k + 1]))

    def _off_mirror(self, i: int) -> float:
        x, y, _ = self.verts[i]
        return min(abs(x), abs(y)) + 1e-6 * (abs(x) + abs(y))

    def fan(self, ring: list[tuple[float, float, float]]) -> None:
        c = self.v(np.mean(np.array(ring), axis=0))
        ids = [self.v(p) for p in ring]
        for a, b in zip(ids, ids[1:] + ids[:1]):
            self.tris.append((c, a, b))


def _field_rows() -> list[list[tuple[float, float, float]]]:
    quadrant = _quadrant_outline()
    ring = []
    for sx, sy, rev in ((1.0, 1.0, False), (-1.0, 1.0, True), (-1.0, -1.0, False), (1.0, -1.0, True)):
        q = quadrant[::-1] if rev else quadrant
        ring += [(sx * x, sy * y, sx * nx, sy * ny, piece, t) for x, y, nx, ny, piece, t in q]
    rows = []
    for x, y, nx, ny, piece, t in ring:
        rf = _floor_fillet(piece, abs(x), t)
        rows.append([(x - a * nx, y - a * ny, z) for a, z in _field_profile(rf)])
    return rows


def _rounded_section(w: float, lo: float, hi: float, segments: int) -> list[tuple[float, float]]:
    """(x, z) round the rectangle |x| <= w, lo <= z <= hi with corners rounded by NET_R, from the floor's middle."""
    r = NET_R
    pts = [(0.0, lo)]
    for cx, cz, a0 in ((w - r, lo + r, -0.5 * math.pi), (w - r, hi - r, 0.0), (-(w - r), hi - r, 0.5 * math.pi),
                       (-(w - r), lo + r, math.pi)):
        pts += [(cx + r * math.cos(a), cz + r * math.sin(a)) for a in np.linspace(a0, a0 + 0.5 * math.pi, segments + 1)]
    return pts + [(0.0, lo)]


def _mouth_rows(sy: float, segments: int) -> list[list[tuple[float, float, float]]]:
    ys = [BACK_Y, BACK_Y + BEVEL]  # the bevels (in front of the back wall the field and the posts' feet take over)
    rows = []
    for y in ys:
        w = min(MOUTH_W, MOUTH_W + BACK_Y - y)
        h = min(MOUTH_H, MOUTH_H + BACK_Y - y)
        rows.append([(x, sy * y, z) for x, z in _rounded_section(w, 0.0, h, segments)])
    return rows


def _net_stations(segments: int) -> list[tuple[float, float, float, float]]:
    """(|y|, z, inward ny, nz) round the net's y-z section from the mouth's floor to the mouth's roof."""
    rise = (-RISE_K * RISE_N, RISE_N)
    out = [(BACK_Y + BEVEL, 0.0, 0.0, 1.0), (RISE_Y, 0.0, 0.0, 1.0), (RISE_Y, 0.0, *rise), (BACK_CY, RISE_K * (
        BACK_CY - RISE_Y), *rise)]
    top = math.atan2(-ROOF_NZ, -ROOF_NY)
    for a in np.linspace(-0.5 * math.pi, top, 6 * segments + 1):
        out.append((BACK_CY + BACK_R * math.cos(a), BACK_CZ + BACK_R * math.sin(a), -math.cos(a), -math.sin(a)))
    tangent = out[-1]
    out.append((tangent[0], tangent[1], ROOF_NY, ROOF_NZ))
    out += [(ROOF_Y, GH, ROOF_NY, ROOF_NZ), (ROOF_Y, GH, 0.0, -1.0), (BACK_Y + BEVEL, GH, 0.0, -1.0)]
    return out


def _net_rows(sy: float, segments: int) -> tuple[list[list[tuple[float, float, float]]], list]:
    """The net's floor, back and roof with their rounded edges (rows across x) and its two side walls (rings)."""
    r = NET_R
    rows = []
    for y, z, ny, nz in _net_stations(segments):
        row = []
        for sx, a0, a1 in ((-1.0, 0.5 * math.pi, 0.0), (1.0, 0.0, 0.5 * math.pi)):
            for phi in np.linspace(a0, a1, segments + 1):
                off = r * (1.0 - math.cos(phi))
                row.append((sx * (GW - r + r * math.sin(phi)), sy * (y + ny * off), z + nz * off))
        rows.append(row)
    sides = []
    for sx in (1.0, -1.0):
        sides.append([(sx * GW, sy * (y + ny * r), z + nz * r) for y, z, ny, nz in _net_stations(segments)])
    return rows, sides


def _post_foot_rows(sx: float, sy: float) -> list[list[tuple[float, float, float]]]:
    """The post's foot: rows of the revolved fillet polygon from the back wall's side round to the net's."""
    rows = []
    for th in np.linspace(0.0, 0.5 * math.pi, ROUNDING_SEGMENTS + 1):
        row = []
        for al in _ANG:
            rho = BEVEL + RF_POST * (1.0 - math.cos(al))
            u, v = rho * math.sin(th), rho * math.cos(th)
            row.append((sx * (MOUTH_W - u), sy * (BACK_Y + BEVEL - v), RF_POST * (1.0 - math.sin(al))))
        rows.append(row)
    return rows


def game_arena_mesh(segments: int = 8, with_floor_and_ceiling: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The interior boundary as (vertices (N, 3) float64 uu, triangles (M, 3) int32), wound so the right-hand
    normals face the interior; every vertex lies on ``game_arena_sdf``'s zero level. Without the floor and ceiling
    (the physics world's planes), the parts of them at z = 0 and z = height are left out."""
    if segments < 1:
        raise ValueError(f"segments: must be >= 1, got {segments!r}")
    m = _Mesh()
    m.grid(_field_rows(), closed=True)
    for sy in (1.0, -1.0):
        m.grid(_mouth_rows(sy, segments))
        rows, sides = _net_rows(sy, segments)
        m.grid(rows)
        for ring in sides:
            m.fan(ring)
        for sx in (1.0, -1.0):
            m.grid(_post_foot_rows(sx, sy))
    if with_floor_and_ceiling:
        _add_floor_and_ceiling(m)
    v, t = np.array(m.verts), np.array(m.tris, dtype=np.int64)
    t = _keep_surface(v, t, with_floor_and_ceiling)
    used, t = np.unique(t, return_inverse=True)
    return v[used], t.reshape(-1, 3).astype(np.int32)


def _add_floor_and_ceiling(m: _Mesh) -> None:
    """The flat floor and ceiling inside the fillets as concentric rings of the outline where they meet the
    fillets, and the flat part of the nets' floors."""
    for z, ceiling in ((0.0, False), (HEIGHT, True)):
        pts = np.array(_outline_ring_points(ceiling))
        n_rings = max(1, math.ceil(float(np.hypot(pts[:, 0], pts[:, 1]).max()) / MESH_MAX_EDGE))
        centre = m.v((0.0, 0.0, z))
        rings = [[m.v((x * s, y * s, z)) for x, y in pts] for s in np.arange(1, n_rings + 1) / n_rings]
        nr = len(pts)
        for i in range(nr):
            m.tris.append((centre, rings[0][i], rings[0][(i + 1) % nr]))
            for r0, r1 in zip(rings[:-1], rings[1:]):
                m.tris.append((r0[i], r1[i], r1[(i + 1) % nr]))
                m.tris.append((r0[i], r1[(i + 1) % nr], r0[(i + 1) % nr]))
    for sy in (1.0, -1.0):  # the goal floors, flat part
        ring = [(x, sy * y, 0.0) for x, y in ((-(GW - NET_R), PIECE_START_Y), (GW - NET_R, PIECE_START_Y),
                                             (GW - NET_R, RISE_Y), (-(GW - NET_R), RISE_Y))]
        m.fan(ring)


def _outline_ring_points(ceiling: bool) -> list[tuple[float, float]]:
    """Where the floor (or the ceiling) meets its fillets, round the whole outline."""
    rows = _field_rows()
    k = -1 if ceiling else 0
    return [(row[k][0], row[k][1]) for row in rows]


def _keep_surface(v: np.ndarray, t: np.ndarray, with_floor_and_ceiling: bool) -> np.ndarray:
    """Drop degenerate triangles, those inside another piece, and (without floor and ceiling) the flat ones at
    z = 0 and z = height; wind the rest to face the interior."""
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    normal = np.cross(b - a, c - a)
    area = np.linalg.norm(normal, axis=1)
    keep = area > 1e-6
    centroid = (a + b + c) / 3.0
    keep &= np.abs(game_arena_sdf_many(centroid)) < 0.5  # a triangle inside another piece is off the surface
    if not with_floor_and_ceiling:
        flat = np.all(np.abs(np.stack([a[:, 2], b[:, 2], c[:, 2]], 1)) < 1e-6, axis=1)
        flat |= np.all(np.abs(np.stack([a[:, 2], b[:, 2], c[:, 2]], 1) - HEIGHT) < 1e-6, axis=1)
        keep &= ~flat
    t, normal, area, centroid = t[keep], normal[keep], area[keep], centroid[keep]
    unit = normal / area[:, None]
    flip = game_arena_sdf_many(centroid + 0.5 * unit) < game_arena_sdf_many(centroid - 0.5 * unit)
    t = t.copy()
    t[flip] = t[flip][:, [0, 2, 1]]
    return t
