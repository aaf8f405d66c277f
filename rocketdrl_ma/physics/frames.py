"""Rotations and the team frame, for every layer: rotation matrix <-> quaternion, and orange's mirror.

A rotation matrix's columns are the body's forward, right and up axes in the world; quaternions are (x, y, z, w),
PyBullet's order. Orange's team frame is the field turned half a circle about z (x -> -x, y -> -y), so both teams
attack +y in their own frame.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

TEAM_MIRROR = np.array([-1.0, -1.0, 1.0])  # per-axis sign of the half-turn about z that swaps the sides
_TEAM_MIRROR_MATRIX = np.diag(TEAM_MIRROR)
ORANGE = 1  # the team whose frame is mirrored (blue, 0, plays in the world frame)


def rot_mat_to_quat_raw(m: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a proper rotation matrix by Shepperd's method (stable for every angle), not renormalised:
    its length is 1 to float rounding."""
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        return (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s
    if m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        return 0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s
    if m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        return (m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s
    s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
    return (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s


def rot_mat_to_quat(m: np.ndarray) -> tuple[float, float, float, float]:
    """(x, y, z, w) unit quaternion of a rotation matrix (what PyBullet is given)."""
    q = rot_mat_to_quat_raw(np.asarray(m, dtype=np.float64))
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


@njit(cache=True, nogil=True)
def quat_to_rot_mat(q, out):
    """An (x, y, z, w) quaternion to a 3x3 rotation matrix, written into ``out``."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    out[0, 0] = 1 - 2 * (y * y + z * z)
    out[0, 1] = 2 * (x * y - z * w)
    out[0, 2] = 2 * (x * z + y * w)
    out[1, 0] = 2 * (x * y + z * w)
    out[1, 1] = 1 - 2 * (x * x + z * z)
    out[1, 2] = 2 * (y * z - x * w)
    out[2, 0] = 2 * (x * z - y * w)
    out[2, 1] = 2 * (y * z + x * w)
    out[2, 2] = 1 - 2 * (x * x + y * y)


def team_spot(team: int, x: float, y: float, yaw: float) -> tuple[float, float, float]:
    """A spawn spot given for blue (x, y in uu, yaw in rad) as ``team``'s: orange's is turned half a circle."""
    return (x, y, yaw) if team != ORANGE else (-x, -y, yaw + math.pi)


def team_axis_sign(team: int) -> np.ndarray:
    """The per-axis sign that takes a world vector (position, velocity, angular velocity) into ``team``'s frame."""
    return np.ones(3) if team != ORANGE else TEAM_MIRROR


def to_team_frame(team: int, vec: np.ndarray) -> np.ndarray:
    """World vectors (``(..., 3)``) in ``team``'s frame; blue's are returned as they are."""
    return vec if team != ORANGE else vec * TEAM_MIRROR


def rot_to_team_frame(team: int, rot: np.ndarray) -> np.ndarray:
    """A rotation matrix (columns forward, right, up) in ``team``'s frame; blue's is returned as it is."""
    return rot if team != ORANGE else _TEAM_MIRROR_MATRIX @ rot
