"""A fan of distance rays with a hit class (``ray``), cast by compiled kernels against the arena's distance field,
the ball, the cars and the minigame barriers."""
from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces
from numba import literally, njit

from rocketdrl_ma.physics import get_preset
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_shape import CLASSIC, GAME, arena_shape_index, shape_distance, shape_raycast
from rocketdrl_ma.rules.state import GameState, agent_team

from .base import ObsBuilder, box_space, check_sizes, clip_to_space

RAY_CLASSES = ("ball", "car", "barrier", "wall")
_MIN_MARCH_STEP = 1.0  # uu: the fallback march's smallest step (its worst-case overshoot into a surface)
_MAX_MARCH_STEPS = 8192


@njit(cache=True, nogil=True, inline="always")
def arena_ray_distances(shape, origin, dirs, max_len):
    """Distance along each unit ray in ``dirs`` (n, 3) from ``origin`` to the surface of the arena of ``shape``
    (``arena_shape``'s integer, a literal); inf if none within ``max_len``. Uses the shape's ray cast; when it
    reports a miss, the ray is marched on over the distance field, because a sphere tracer running out of steps (a
    ray grazing the floor from a car's centre, ~17 uu up) also reports a miss."""
    n = dirs.shape[0]
    out = np.full(n, np.inf)
    ox, oy, oz = origin[0], origin[1], origin[2]
    for i in range(n):
        dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        hit, t, _, _, _ = shape_raycast(shape, ox, oy, oz, dx, dy, dz, max_len)
        if hit:
            out[i] = t
            continue
        t = 0.0
        for _ in range(_MAX_MARCH_STEPS):
            d = shape_distance(shape, ox + dx * t, oy + dy * t, oz + dz * t)
            if d < 0.02:
                out[i] = t
                break
            t += max(d, _MIN_MARCH_STEP)
            if t > max_len:
                break
    return out


@njit(cache=True, nogil=True)
def _ray_sphere(ox, oy, oz, dx, dy, dz, center, radius):
    """Entry distance of a unit ray into a sphere (0 if the origin is inside; inf if missed)."""
    cx, cy, cz = ox - center[0], oy - center[1], oz - center[2]
    c = cx * cx + cy * cy + cz * cz - radius * radius
    if c <= 0.0:
        return 0.0
    b = dx * cx + dy * cy + dz * cz
    disc = b * b - c
    if disc < 0.0:
        return np.inf
    t = -b - math.sqrt(disc)
    return t if t >= 0.0 else np.inf


@njit(cache=True, nogil=True)
def _ray_box(ox, oy, oz, dx, dy, dz, center, axes, half):
    """Entry distance of a unit ray into an oriented box (slab test; 0 if the origin is inside, inf if missed).
    ``axes`` holds the box's unit axes as columns, ``half`` its half extents along them."""
    enter, leave = -np.inf, np.inf
    rx, ry, rz = ox - center[0], oy - center[1], oz - center[2]
    for k in range(3):
        o = axes[0, k] * rx + axes[1, k] * ry + axes[2, k] * rz
        d = axes[0, k] * dx + axes[1, k] * dy + axes[2, k] * dz
        if abs(d) < 1e-12:
            if abs(o) > half[k]:
                return np.inf
            continue
        t1, t2 = (-half[k] - o) / d, (half[k] - o) / d
        enter, leave = max(enter, min(t1, t2)), min(leave, max(t1, t2))
    if enter <= leave and leave >= 0.0:
        return max(enter, 0.0)
    return np.inf


@njit(cache=True, nogil=True)
def ray_hits(shape, origin, dirs, ball_pos, ball_radius, box_centers, box_axes, box_half, box_class, reach):
    """Per unit ray in ``dirs`` (n, 3) from ``origin``: the nearest hit distance within ``reach`` (inf if
    none) and its class (index into ``RAY_CLASSES``; -1 if none): the ball sphere, oriented boxes of class
    ``box_class[m]`` (cars, barriers), and the arena of ``shape`` (``arena_shape``'s integer, compiled per value:
    call ``ray_hits_classic`` or ``ray_hits_game``). On a tie the lower class wins."""
    literally(shape)
    n = dirs.shape[0]
    nearest = np.full(n, np.inf)
    cls = np.full(n, -1, np.int64)
    walls = arena_ray_distances(shape, origin, dirs, reach)
    ox, oy, oz = origin[0], origin[1], origin[2]
    for i in range(n):
        dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        best, best_cls = _ray_sphere(ox, oy, oz, dx, dy, dz, ball_pos, ball_radius), 0
        for m in range(box_centers.shape[0]):
            t = _ray_box(ox, oy, oz, dx, dy, dz, box_centers[m], box_axes[m], box_half[m])
            if t < best or (t == best and box_class[m] < best_cls):
                best, best_cls = t, box_class[m]
        if walls[i] < best:
            best, best_cls = walls[i], 3
        if best <= reach:
            nearest[i], cls[i] = best, best_cls
    return nearest, cls


@njit(cache=True, nogil=True)
def ray_hits_classic(origin, dirs, ball_pos, ball_radius, box_centers, box_axes, box_half, box_class, reach):
    """``ray_hits`` in the "classic" arena."""
    return ray_hits(CLASSIC, origin, dirs, ball_pos, ball_radius, box_centers, box_axes, box_half, box_class, reach)


@njit(cache=True, nogil=True)
def ray_hits_game(origin, dirs, ball_pos, ball_radius, box_centers, box_axes, box_half, box_class, reach):
    """``ray_hits`` in the "game" arena."""
    return ray_hits(GAME, origin, dirs, ball_pos, ball_radius, box_centers, box_axes, box_half, box_class, reach)


#: the compiled ray kernel of each arena shape, by ``arena_shape_index``
RAY_HITS_BY_SHAPE = (ray_hits_classic, ray_hits_game)


class RaySensor(ObsBuilder):
    """A fan of ``n_rays`` distance rays across the car's front, 5 numbers per ray.

    Rays start at the car's centre and lie in the car's forward/right plane, at angles
    ``linspace(-fan_deg / 2, +fan_deg / 2, n_rays)`` from forward (negative: to the car's left; a single
    ray points straight ahead), so ``fan_deg`` is the fan's full width. Ray ``k`` fills slots
    ``5k .. 5k+4``:

    ====== =================================================================== ========
    offset value                                                               range
    ====== =================================================================== ========
    0      distance to the nearest hit / ``reach_uu`` (1.0 when nothing within) [0, 1]
    1      hit the ball (sphere of radius 91.25 at the ball's centre)           {0, 1}
    2      hit another car (its hitbox: an oriented box; demoed cars are gone)  {0, 1}
    3      hit a barrier (``state.obstacles``, axis-aligned boxes)              {0, 1}
    4      hit the arena (walls, floor, ceiling, goals; ``state.arena_shape``) {0, 1}
    ====== =================================================================== ========

    The nearest hit wins; the one-hot is all zero when nothing is within reach. Hitboxes come from
    ``state.car_configs`` (the octane preset for a car without one). The own car is never hit. Everything
    is in the car's own frame, so the sensor is identical for both teams without mirroring.
    """

    def __init__(self, n_rays: int = 8, fan_deg: float = 70.0, reach_uu: float = 4000.0):
        if isinstance(n_rays, bool) or not isinstance(n_rays, (int, np.integer)) or not 1 <= n_rays <= 256:
            raise ValueError(f"n_rays: must be an int in 1..256, got {n_rays!r}")
        if isinstance(fan_deg, bool) or not isinstance(fan_deg, (int, float)) or not 0.0 <= fan_deg <= 360.0:
            raise ValueError(f"fan_deg: must be a number in [0, 360], got {fan_deg!r}")
        if (isinstance(reach_uu, bool) or not isinstance(reach_uu, (int, float)) or not math.isfinite(reach_uu)
                or reach_uu <= 0.0):
            raise ValueError(f"reach_uu: must be a finite number > 0, got {reach_uu!r}")
        self.n_rays, self.fan_deg, self.reach_uu = int(n_rays), float(fan_deg), float(reach_uu)
        half = math.radians(self.fan_deg) / 2.0
        self.angles = np.linspace(-half, half, self.n_rays) if self.n_rays > 1 else np.zeros(1)
        self.size = 5 * self.n_rays
        self._space = box_space([0.0] * self.size, [1.0] * self.size)
        self._octane = get_preset("octane")

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        check_sizes(blue_size, orange_size)
        return self._space

    def ray_directions(self, rot_mat: np.ndarray) -> np.ndarray:
        """(n_rays, 3) unit world directions: cos(a) forward + sin(a) right."""
        return np.cos(self.angles)[:, None] * rot_mat[:, 0] + np.sin(self.angles)[:, None] * rot_mat[:, 1]

    def hits(self, agent: str, state: GameState) -> tuple[np.ndarray, np.ndarray]:
        """Per ray: the nearest hit distance (inf if none within reach) and its class index into
        ``RAY_CLASSES`` (-1 if none)."""
        car = state.cars[agent]
        centers, axes, half, box_class = [], [], [], []
        for name, other in state.cars.items():
            if name != agent and not other.is_demoed:
                cfg = state.car_configs.get(name) or self._octane
                centers.append(other.pos + other.rot_mat @ np.asarray(cfg.hitbox_offset, dtype=np.float64))
                axes.append(other.rot_mat)
                half.append(np.asarray(cfg.hitbox_size, dtype=np.float64) / 2.0)
                box_class.append(1)
        for ob in state.obstacles:
            centers.append(np.asarray(ob.center, dtype=np.float64))
            axes.append(np.eye(3))
            half.append(np.asarray(ob.half_extents, dtype=np.float64))
            box_class.append(2)
        if centers:
            centers, axes, half = np.array(centers), np.array(axes), np.array(half)
        else:
            centers, axes, half = np.empty((0, 3)), np.empty((0, 3, 3)), np.empty((0, 3))
        # fresh writable copies: a read-only state array (a decoded server state) would compile another signature
        ray_hits_of_shape = RAY_HITS_BY_SHAPE[arena_shape_index(state.arena_shape)]
        return ray_hits_of_shape(np.array(car.pos, dtype=np.float64), self.ray_directions(car.rot_mat),
                                 np.array(state.ball.pos, dtype=np.float64), C.BALL_RADIUS, centers, axes, half,
                                 np.array(box_class, dtype=np.int64), self.reach_uu)

    def build(self, agent: str, state: GameState) -> np.ndarray:
        agent_team(agent)  # validates the name
        out = np.zeros((self.n_rays, 5))
        out[:, 0] = 1.0
        if agent in state.cars:
            nearest, cls = self.hits(agent, state)
            seen = cls >= 0
            out[seen, 0] = nearest[seen] / self.reach_uu
            out[np.nonzero(seen)[0], 1 + cls[seen]] = 1.0
        return clip_to_space(out.ravel(), self._space)
