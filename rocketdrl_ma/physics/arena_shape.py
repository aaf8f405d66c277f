"""The arena shapes a world can be built with, and their queries chosen at compile time.

``"classic"`` is ``arena_geometry`` (one 400 uu fillet everywhere; the shape the shipped checkpoints and kickoff
tables were measured on, and the default); ``"game"`` is ``game_arena`` (Rocket League's collision surface). A
kernel takes the shape as a literal integer (``numba.literally``), so each shape gets its own compiled kernel and
the classic one contains no branch on the shape.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .arena_geometry import arena_distance, arena_mesh, arena_raycast, is_inside_arena, surface_contacts
from .game_arena import game_arena_mesh, game_arena_raycast, game_arena_sdf, game_surface_contacts

ARENA_SHAPES = ("classic", "game")
CLASSIC = 0
GAME = 1
DEFAULT_ARENA_SHAPE = "classic"


def arena_shape_index(arena_shape: str) -> int:
    """The kernels' integer for an arena shape name; a ValueError names the allowed ones."""
    if arena_shape not in ARENA_SHAPES:
        raise ValueError(f"arena_shape: must be one of {', '.join(repr(s) for s in ARENA_SHAPES)}, "
                         f"got {arena_shape!r}")
    return ARENA_SHAPES.index(arena_shape)


@njit(cache=True, nogil=True, inline="always")
def shape_surface_contacts(shape, x, y, z, reach, out):
    """``surface_contacts`` of the shape (a literal: the other branch is compiled away)."""
    if shape == CLASSIC:
        return surface_contacts(x, y, z, reach, out)
    return game_surface_contacts(x, y, z, reach, out)


@njit(cache=True, nogil=True, inline="always")
def shape_raycast(shape, ox, oy, oz, dx, dy, dz, max_len):
    """``arena_raycast`` of the shape (a literal: the other branch is compiled away)."""
    if shape == CLASSIC:
        return arena_raycast(ox, oy, oz, dx, dy, dz, max_len)
    return game_arena_raycast(ox, oy, oz, dx, dy, dz, max_len)


@njit(cache=True, nogil=True, inline="always")
def shape_distance(shape, x, y, z):
    """The shape's signed distance from (x, y, z) to its surface (a literal: the other branch is compiled away)."""
    if shape == CLASSIC:
        return arena_distance(x, y, z)
    return game_arena_sdf(x, y, z)[0]


def shape_mesh(arena_shape: str, with_floor_and_ceiling: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The shape's surface mesh: (vertices (N, 3) uu, triangles (M, 3) int32), wound towards the interior."""
    if arena_shape_index(arena_shape) == CLASSIC:
        return arena_mesh(with_floor_and_ceiling=with_floor_and_ceiling)
    return game_arena_mesh(with_floor_and_ceiling=with_floor_and_ceiling)


def shape_contains(arena_shape: str, x: float, y: float, z: float, margin: float) -> bool:
    """Whether (x, y, z) lies in the shape's playable space at least ``margin`` uu from its surface."""
    if arena_shape_index(arena_shape) == CLASSIC:
        return bool(is_inside_arena(x, y, z, margin))
    return bool(game_arena_sdf(x, y, z)[0] >= margin)
