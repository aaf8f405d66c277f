"""The arena as the page draws it, exported from the physics' own geometry (never re-derived in JavaScript):
the surface mesh of ``physics/arena_geometry.py``, the boost pads, the goals and the ball's size."""
from __future__ import annotations

import functools
import json

import numpy as np

from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_geometry import arena_mesh

#: fillet segments of the page's mesh: the physics' own default (chords within 1.9 uu of the surface)
PAGE_FILLET_SEGMENTS = 8


@functools.lru_cache(maxsize=1)
def arena_json() -> bytes:
    """``/arena.json``: vertices (flat, uu, z up), triangles (flat indices, wound to face the interior),
    pads (x, y, z, big), goal and field sizes, ball radius."""
    vertices, triangles = arena_mesh(PAGE_FILLET_SEGMENTS)
    pads = [[float(x), float(y), float(z), bool(big)]
            for (x, y, z), big in zip(C.BOOST_PAD_POSITIONS, C.BOOST_PAD_IS_BIG)]
    description = {
        "vertices": np.round(vertices, 2).ravel().tolist(),
        "triangles": triangles.ravel().tolist(),
        "pads": pads,
        "pad_radius": {"small": C.BOOST_PAD_SMALL_RADIUS, "big": C.BOOST_PAD_BIG_RADIUS},
        "goal": {"half_width": C.GOAL_HALF_WIDTH, "height": C.GOAL_HEIGHT, "depth": C.GOAL_DEPTH},
        "field": {"extent_x": C.ARENA_EXTENT_X, "extent_y": C.ARENA_EXTENT_Y, "height": C.ARENA_HEIGHT},
        "ball_radius": C.BALL_RADIUS,
    }
    return json.dumps(description, separators=(",", ":")).encode()
