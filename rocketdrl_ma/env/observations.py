"""Observation builders: a ``GameState`` turned into one flat float32 vector per agent.

The interface follows RLGym v2's small composable builders and Gymnasium's spaces:

* ``space(blue_size, orange_size)`` declares the ``Box`` once; it is the same for every agent, float32,
  with finite bounds (slot by slot: flags in [0, 1], signed quantities in [-1, 1]).
* ``reset(state)`` is an optional per-episode hook (a no-op here for every builder).
* ``build(agent, state)`` returns a float32 vector inside that space. The **last step** of every builder
  is a clip to the space's bounds, so a state beyond the scales below (a car past the declared speed
  cap, a ball deep in a goal) saturates instead of leaving the space. Inputs are validated upstream
  (``CarState``/``BallState`` reject NaN), so the clip never hides a bad value, only a large one.

Team frame: orange sees the field turned half a circle about z (x -> -x, y -> -y), so one policy plays
both sides. Positions, velocities and direction vectors map ``v -> (-vx, -vy, vz)``; angular velocity
does the same (a proper rotation about z by pi maps ``(wx, wy, wz) -> (-wx, -wy, wz)``); boost pads are
permuted to the pad at the mirrored position. A blue car at a state and the matching orange car at the
mirrored state (teams swapped) get bit-identical observations.

Builders: ``SeedSensors`` (the RocketDRL seed's 12 general data sensors), ``RaySensor`` (a fan of
distance rays with a hit class), ``TeamRelativeObs`` (the full state in the team frame) and
``CombinedObs`` (concatenation). ``make_obs_builder("seed_sensors+ray")`` combines by name.
``SeedBarrierSensors`` / ``SeedAerialSensors`` (``seed_barrier``, ``seed_aerial``) are the seed sensors plus
the Barrier and Aerial minigames' own.
"""
from __future__ import annotations

import functools
import inspect
import math
from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np
from gymnasium import spaces
from numba import njit

from rocketdrl_ma.physics import CarControls, get_preset
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_geometry import arena_distance, arena_raycast
from rocketdrl_ma.physics.state import CarState
from rocketdrl_ma.rules.state import BLUE, TEAM_NAMES, GameState, agent_team

# ---------------------------------------------------------------- scales (uu, uu/s, rad/s)
POS_SCALE = np.array([C.ARENA_EXTENT_X, C.ARENA_EXTENT_Y + C.GOAL_DEPTH, C.ARENA_HEIGHT])  # to the goal's back
#: The longest straight line in the arena (corner to corner, goal back to goal back): |car -> ball| <= this.
ARENA_DIAGONAL = float(np.linalg.norm([2.0 * POS_SCALE[0], 2.0 * POS_SCALE[1], C.ARENA_HEIGHT]))
CAR_VEL_SCALE = C.CAR_MAX_SPEED
CAR_ANG_VEL_SCALE = C.CAR_MAX_ANG_SPEED
BALL_VEL_SCALE = C.BALL_MAX_SPEED
BALL_ANG_VEL_SCALE = C.BALL_MAX_ANG_SPEED
CLOCK_SCALE_S = 300.0  # a 5-minute match
SCORE_DIFF_SCALE = 3.0  # tanh(diff / 3)
#: The opponent's goal centre in the team frame (blue attacks +y; orange too, after mirroring).
ATTACK_GOAL_CENTER = np.array([0.0, C.ARENA_EXTENT_Y, C.GOAL_HEIGHT / 2.0])

MIRROR = np.array([-1.0, -1.0, 1.0])  # x -> -x, y -> -y: the half-turn about z that swaps the sides
PAD_COOLDOWN = np.where(C.BOOST_PAD_IS_BIG, C.BOOST_PAD_BIG_COOLDOWN, C.BOOST_PAD_SMALL_COOLDOWN)


def _pad_mirror_permutation() -> np.ndarray:
    """``perm[i]`` is the pad at the mirrored position of pad ``i`` (x -> -x, y -> -y)."""
    xy = C.BOOST_PAD_POSITIONS[:, :2]
    dist = np.linalg.norm(xy[:, None, :] + xy[None, :, :], axis=2)  # |p_j - (-p_i)|
    perm = np.argmin(dist, axis=1)
    assert np.all(dist[np.arange(len(xy)), perm] < 1e-6) and len(set(perm.tolist())) == len(xy)
    return perm


PAD_MIRROR = _pad_mirror_permutation()
N_PADS = len(C.BOOST_PAD_POSITIONS)


def team_sign(agent: str) -> np.ndarray:
    """The per-axis sign that takes a world vector into ``agent``'s team frame."""
    return np.ones(3) if agent_team(agent) == BLUE else MIRROR


def has_flip_available(car: CarState) -> bool:
    """Can the car still dodge: on the ground, or airborne within the double-jump window with its flip unused."""
    if car.on_ground:
        return True
    return (not car.has_double_jumped and not car.has_flipped
            and car.air_time_since_jump < C.DOUBLEJUMP_MAX_DELAY)


def _box(low: Sequence[float], high: Sequence[float]) -> spaces.Box:
    low_a, high_a = np.asarray(low, dtype=np.float32), np.asarray(high, dtype=np.float32)
    return spaces.Box(low_a, high_a, low_a.shape, np.float32)


def _finish(values: np.ndarray, space: spaces.Box) -> np.ndarray:
    """The last step of every ``build``: clip to the space's bounds and cast to float32."""
    return np.clip(np.asarray(values, dtype=np.float64), space.low, space.high).astype(np.float32)


def _check_sizes(blue_size: int, orange_size: int) -> None:
    for name, size in (("blue_size", blue_size), ("orange_size", orange_size)):
        if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or not 0 <= size <= 4:
            raise ValueError(f"{name}: must be an int in 0..4, got {size!r}")
    if blue_size + orange_size == 0:
        raise ValueError("blue_size/orange_size: a game needs at least one car")


class ObsBuilder(ABC):
    """Turns a ``GameState`` into one agent's observation (RLGym v2 style: small and composable)."""

    @abstractmethod
    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        """The observation space for this team size: float32, finite bounds, the same for every agent."""

    def reset(self, state: GameState) -> None:
        """Per-episode hook, called with the first state of each episode before any ``build``."""

    @abstractmethod
    def build(self, agent: str, state: GameState) -> np.ndarray:
        """``agent``'s observation: float32, inside ``space`` (clipped to its bounds as the last step)."""


# ================================================================= the seed's general data sensors
class SeedSensors(ObsBuilder):
    """The RocketDRL seed paper's 12 general data sensors (18 numbers; 15 without the goal sensor).

    ====== ================ ======================================================================== =========
    index  sensor           value                                                                    range
    ====== ================ ======================================================================== =========
    0      ready to drive   on the ground and not in a jump                                           {0, 1}
    1      body on ground   ``on_ground`` (at least 3 wheels touching)                                {0, 1}
    2      wheels on ground number of wheels in contact / 4                                           [0, 1]
    3      jumping          ``is_jumping`` (the jump button's held phase)                             {0, 1}
    4      boost amount     boost / 100                                                               [0, 1]
    5      boosting         last control's boost pressed and boost > 0                                {0, 1}
    6      velocity sign    sign of the forward speed (velocity . forward)                            {-1,0,1}
    7      speed            |velocity| / 2300                                                         [0, 1]
    8      steer angle      last control's steer                                                      [-1, 1]
    9-11   rotation         Euler pitch, yaw, roll / pi, in the team frame (see below)                [-1, 1]
    12-14  car -> ball      ball - car in the car's frame (forward, right, up) / ARENA_DIAGONAL       [-1, 1]
    15-17  ball -> goal     opponent goal centre - ball, team frame / ARENA_DIAGONAL (if goal_sensor) [-1, 1]
    ====== ================ ======================================================================== =========

    Euler angles from the team-frame rotation matrix (columns forward ``f``, right ``r``, up ``u``):
    pitch = atan2(f.z, |f.xy|) (nose up > 0), yaw = atan2(f.y, f.x), roll = atan2(r.z, u.z).
    ``ARENA_DIAGONAL`` (~14673 uu) is the longest line through the arena including the goals, so the two
    vectors never saturate. The opponent goal centre is (0, 5120, 321.4) in the team frame for both teams.
    An agent missing from ``state.cars`` observes zeros.
    """

    SLOTS = ("ready_to_drive", "on_ground", "wheels_on_ground", "jumping", "boost_amount", "boosting",
             "velocity_sign", "speed", "steer", "pitch", "yaw", "roll", "ball_local_x", "ball_local_y",
             "ball_local_z", "ball_to_goal_x", "ball_to_goal_y", "ball_to_goal_z")
    _LOW = (0, 0, 0, 0, 0, 0, -1, 0, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1)

    def __init__(self, goal_sensor: bool = True):
        if not isinstance(goal_sensor, bool):
            raise ValueError(f"goal_sensor: expected a bool, got {goal_sensor!r}")
        self.goal_sensor = goal_sensor
        self.size = 18 if goal_sensor else 15
        self._space = _box(self._LOW[:self.size], [1.0] * self.size)

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        _check_sizes(blue_size, orange_size)
        return self._space

    def build(self, agent: str, state: GameState) -> np.ndarray:
        sign = team_sign(agent)
        car = state.cars.get(agent)
        out = np.zeros(self.size)
        if car is None:
            return _finish(out, self._space)
        controls = state.last_controls.get(agent) or CarControls()
        rot = car.rot_mat * sign[:, None]  # the team frame: each column mirrored
        forward, right, up = rot[:, 0], rot[:, 1], rot[:, 2]
        forward_speed = float(np.dot(car.vel, car.rot_mat[:, 0]))
        out[0] = float(car.on_ground and not car.is_jumping)
        out[1] = float(car.on_ground)
        out[2] = sum(car.wheels_in_contact) / 4.0
        out[3] = float(car.is_jumping)
        out[4] = car.boost / C.BOOST_MAX
        out[5] = float(controls.boost and car.boost > 0.0)
        out[6] = float(np.sign(forward_speed))
        out[7] = float(np.linalg.norm(car.vel)) / C.CAR_MAX_SPEED
        out[8] = controls.steer
        out[9] = math.atan2(forward[2], math.hypot(forward[0], forward[1])) / math.pi
        out[10] = math.atan2(forward[1], forward[0]) / math.pi
        out[11] = math.atan2(right[2], up[2]) / math.pi
        out[12:15] = car.rot_mat.T @ (state.ball.pos - car.pos) / ARENA_DIAGONAL
        if self.goal_sensor:
            out[15:18] = (ATTACK_GOAL_CENTER - state.ball.pos * sign) / ARENA_DIAGONAL
        return _finish(out, self._space)


# ================================================================= distance rays
RAY_CLASSES = ("ball", "car", "barrier", "wall")
_MIN_MARCH_STEP = 1.0  # uu: the fallback march's smallest step (its worst-case overshoot into a surface)
_MAX_MARCH_STEPS = 8192


@njit(cache=True)
def arena_ray_distances(origin, dirs, max_len):
    """Distance along each unit ray in ``dirs`` (n, 3) from ``origin`` to the arena surface; inf if none
    within ``max_len``. Uses ``arena_raycast``; when it reports a miss, the ray is marched on over the
    distance field, because a sphere tracer running out of steps (a ray grazing the floor from a car's
    centre, ~17 uu up) also reports a miss."""
    n = dirs.shape[0]
    out = np.full(n, np.inf)
    ox, oy, oz = origin[0], origin[1], origin[2]
    for i in range(n):
        dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        hit, t, _, _, _ = arena_raycast(ox, oy, oz, dx, dy, dz, max_len)
        if hit:
            out[i] = t
            continue
        t = 0.0
        for _ in range(_MAX_MARCH_STEPS):
            d = arena_distance(ox + dx * t, oy + dy * t, oz + dz * t)
            if d < 0.02:
                out[i] = t
                break
            t += max(d, _MIN_MARCH_STEP)
            if t > max_len:
                break
    return out


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def ray_hits(origin, dirs, ball_pos, ball_radius, box_centers, box_axes, box_half, box_class, reach):
    """Per unit ray in ``dirs`` (n, 3) from ``origin``: the nearest hit distance within ``reach`` (inf if
    none) and its class (index into ``RAY_CLASSES``; -1 if none): the ball sphere, oriented boxes of class
    ``box_class[m]`` (cars, barriers), and the arena. On a tie the lower class wins."""
    n = dirs.shape[0]
    nearest = np.full(n, np.inf)
    cls = np.full(n, -1, np.int64)
    walls = arena_ray_distances(origin, dirs, reach)
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
    4      hit the arena (walls, floor, ceiling, goals: ``arena_raycast``)      {0, 1}
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
        self._space = _box([0.0] * self.size, [1.0] * self.size)
        self._octane = get_preset("octane")

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        _check_sizes(blue_size, orange_size)
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
        return ray_hits(np.ascontiguousarray(car.pos, dtype=np.float64), self.ray_directions(car.rot_mat),
                        np.ascontiguousarray(state.ball.pos, dtype=np.float64), C.BALL_RADIUS, centers, axes, half,
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
        return _finish(out.ravel(), self._space)


# ================================================================= the full state, team-relative
CAR_FEATURES = ("pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z", "ang_vel_x", "ang_vel_y", "ang_vel_z",
                "forward_x", "forward_y", "forward_z", "up_x", "up_y", "up_z", "boost", "on_ground",
                "has_flip", "is_demoed", "present")
_CAR_LOW = [-1.0] * 15 + [0.0] * 5
BALL_FEATURES = ("pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z", "ang_vel_x", "ang_vel_y", "ang_vel_z")
GAME_FEATURES = ("score_diff", "clock", "is_overtime", "kickoff_pending")
_GAME_LOW = [-1.0, 0.0, 0.0, 0.0]


_FEATURE_MIRROR = np.concatenate([np.tile(MIRROR, 5), np.ones(5)])  # team frame of CAR_FEATURES for orange
# The divisors of the first 15 car features and of the ball block (1.0 for direction vectors: an exact no-op).
_CAR_SCALE = np.concatenate([POS_SCALE, [CAR_VEL_SCALE] * 3, [CAR_ANG_VEL_SCALE] * 3, np.ones(6)])
_BALL_SCALE = np.concatenate([POS_SCALE, [BALL_VEL_SCALE] * 3, [BALL_ANG_VEL_SCALE] * 3])
_BALL_MIRROR = np.tile(MIRROR, 3)


def car_features(car: CarState | None) -> np.ndarray:
    """``CAR_FEATURES`` of one car in the blue (world) frame, zeros for an absent car; multiply by
    ``_FEATURE_MIRROR`` for orange's frame."""
    features = np.zeros(len(CAR_FEATURES))
    if car is None:
        return features
    np.divide(np.concatenate((car.pos, car.vel, car.ang_vel, car.rot_mat[:, 0], car.rot_mat[:, 2])), _CAR_SCALE,
              out=features[:15])
    features[15:20] = (car.boost / C.BOOST_MAX, float(car.on_ground), float(has_flip_available(car)),
                       float(car.is_demoed), 1.0)
    return features


@functools.lru_cache(maxsize=None)
def _padded_slots(blue_size: int, orange_size: int) -> tuple[int, int]:
    """(teammate slots, opponent slots) that fit every agent of a ``blue_size`` v ``orange_size`` game."""
    teams = [(own, other) for own, other in ((blue_size, orange_size), (orange_size, blue_size)) if own > 0]
    return max(own - 1 for own, _ in teams), max(other for _, other in teams)


class TeamRelativeObs(ObsBuilder):
    """The whole game from one agent's side, in its team frame (orange mirrored; see the module doc).

    Layout for ``T = teammate slots`` and ``O = opponent slots`` (below), all scaled to [-1, 1]:

    ================= ======== ==============================================================================
    block             size     contents
    ================= ======== ==============================================================================
    self              20       ``CAR_FEATURES``: pos / (4096, 6000, 2048), vel / 2300, ang_vel / 5.5,
                               forward (3), up (3), boost / 100, on_ground, has_flip (on the ground, or
                               airborne within 1.25 s of a jump with no double jump or flip used yet),
                               is_demoed, present (1 for a car in ``state.cars``)
    ball              9        pos / (4096, 6000, 2048), vel / 6000, ang_vel / 6
    teammates         20 * T   ``CAR_FEATURES`` of each teammate, by index, self excluded
    opponents         20 * O   ``CAR_FEATURES`` of each opponent, by index
    boost pads        34       seconds until back / the pad's cooldown (0 = available), team-frame pad order
    game              4        tanh((own - opponent score) / 3), clock_s / 300 (clipped to [0, 1]),
                               is_overtime, kickoff_pending
    ================= ======== ==============================================================================

    ``T = max(team size - 1)`` and ``O = max(other team's size)`` over the teams that have cars, so every
    agent gets the same shape; unused slots and cars absent from ``state.cars`` are zeros (``present`` 0).
    A demoed car still appears with ``is_demoed`` 1. Sizes: 1v1 87, 2v2 127, 3v3 167, 4v4 207.

    Unequal teams are padded: in a 1v2 (``T`` 1, ``O`` 2) blue's lone car has an empty team-mate slot and orange's
    cars an empty second opponent slot, so both sides' observations have one shape (127). ``max_team_size``
    (1..4) fixes the layout whatever the game: ``T = max_team_size - 1`` and ``O = max_team_size`` slots, the
    absent cars zero, so one policy (a checkpoint trained with it) plays 1v1, 1v2, 2v2 and 2v1 with the same
    input; a game with a bigger team is a ValueError naming ``max_team_size``.

    ``space(blue_size, orange_size)`` fixes the team sizes for later ``build`` calls; before it is called,
    ``build`` infers them from the agent names in the state. The per-car features of the last state are
    cached for the other agents of the same decision (keyed on the object, which is a read-only snapshot).
    """

    def __init__(self, max_team_size: int | None = None):
        if max_team_size is not None and (isinstance(max_team_size, bool) or not isinstance(max_team_size, int)
                                          or not 1 <= max_team_size <= 4):
            raise ValueError(f"max_team_size: must be an int in 1..4 or null, got {max_team_size!r}")
        self.max_team_size = max_team_size
        self._sizes: tuple[int, int] | None = None
        self._spaces: dict[tuple[int, int], spaces.Box] = {}
        self._cached_state: GameState | None = None  # the last state seen, held so its id cannot be reused
        self._cached_cars: dict[str, np.ndarray] = {}
        self._cached_sizes: tuple[int, int] | None = None
        self._cached_frames: dict[int, tuple] = {}
        self._bounds: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}  # a space's bounds as float64
        self._layouts: dict[tuple[str, int, int], tuple] = {}  # see _layout

    def slots(self, blue_size: int, orange_size: int) -> tuple[int, int]:
        """(teammate slots, opponent slots) for this team size."""
        if self.max_team_size is not None:
            for name, size in (("blue_size", blue_size), ("orange_size", orange_size)):
                if size > self.max_team_size:
                    raise ValueError(f"max_team_size: the observation has room for teams of up to "
                                     f"{self.max_team_size} cars, but {name} is {size}")
            return self.max_team_size - 1, self.max_team_size
        return _padded_slots(blue_size, orange_size)

    def size(self, blue_size: int, orange_size: int) -> int:
        mates, opps = self.slots(blue_size, orange_size)
        return len(CAR_FEATURES) * (1 + mates + opps) + len(BALL_FEATURES) + N_PADS + len(GAME_FEATURES)

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        _check_sizes(blue_size, orange_size)
        self._sizes = (int(blue_size), int(orange_size))
        return self._make_space(blue_size, orange_size)

    def _make_space(self, blue_size: int, orange_size: int) -> spaces.Box:
        key = (int(blue_size), int(orange_size))
        if key not in self._spaces:
            mates, opps = self.slots(blue_size, orange_size)
            low = _CAR_LOW + [-1.0] * len(BALL_FEATURES) + _CAR_LOW * (mates + opps) + [0.0] * N_PADS + _GAME_LOW
            self._spaces[key] = _box(low, [1.0] * len(low))
            self._bounds[key] = (self._spaces[key].low.astype(np.float64), self._spaces[key].high.astype(np.float64))
        return self._spaces[key]

    def _team_sizes(self, state: GameState) -> tuple[int, int]:
        if self._sizes is not None:
            return self._sizes
        sizes = [0, 0]
        for name in list(state.cars) + list(state.last_controls) + list(state.car_configs):
            team = agent_team(name)
            sizes[team] = max(sizes[team], int(name.rsplit("_", 1)[1]) + 1)
        return sizes[0], sizes[1]

    def _layout(self, agent: str, blue_size: int, orange_size: int) -> tuple[tuple[tuple[int, str], ...], int, int]:
        """Where ``agent``'s observation puts each car's block (offset, car), the ball block and the pad timers
        (the game features follow them); worked out and validated once per agent and team sizes."""
        key = (agent, blue_size, orange_size)
        if key not in self._layouts:
            team = agent_team(agent)
            own_size, other_size = (blue_size, orange_size) if team == BLUE else (orange_size, blue_size)
            index = int(agent.rsplit("_", 1)[1])
            if not 0 <= index < own_size:
                raise ValueError(f"agent: {agent!r} is not in a {blue_size}v{orange_size} game")
            self._make_space(blue_size, orange_size)
            mates_n, opps_n = self.slots(blue_size, orange_size)
            own, other = TEAM_NAMES[team], TEAM_NAMES[1 - team]
            n_car = len(CAR_FEATURES)
            slots = [(0, agent)]
            at = n_car + len(BALL_FEATURES)
            for i in [i for i in range(own_size) if i != index]:
                slots.append((at, f"{own}_{i}"))
                at += n_car
            at += n_car * (mates_n - (own_size - 1))
            for i in range(other_size):
                slots.append((at, f"{other}_{i}"))
                at += n_car
            at += n_car * (opps_n - other_size)
            self._layouts[key] = (tuple(slots), n_car, at)
        return self._layouts[key]

    def build(self, agent: str, state: GameState) -> np.ndarray:
        team = agent_team(agent)
        blue_size, orange_size = self._team_sizes(state)
        car_slots, ball_at, pads_at = self._layout(agent, blue_size, orange_size)
        # Every agent of one decision shares the per-car features and the team frames' blocks.
        if self._cached_state is not state or self._cached_sizes != (blue_size, orange_size):
            for name in state.cars:
                t, i = agent_team(name), int(name.rsplit("_", 1)[1])
                if i >= (blue_size, orange_size)[t]:
                    raise ValueError(f"state.cars: {name!r} is not in a {blue_size}v{orange_size} game")
            self._cached_cars = {name: car_features(car) for name, car in state.cars.items()}
            self._cached_frames = {}
            self._cached_state, self._cached_sizes = state, (blue_size, orange_size)
        if team not in self._cached_frames:
            self._cached_frames[team] = self._team_frame(team, state)
        cars, ball_block, timers = self._cached_frames[team]
        low, high = self._bounds[(blue_size, orange_size)]
        # Filled block by block in the layout above; absent cars and unused slots stay zero.
        out = np.zeros(len(low))
        n_car = len(CAR_FEATURES)
        for at, name in car_slots:
            features = cars.get(name)
            if features is not None:
                out[at:at + n_car] = features
        out[ball_at:ball_at + len(BALL_FEATURES)] = ball_block
        out[pads_at:pads_at + N_PADS] = timers
        own_score, other_score = state.score[team], state.score[1 - team]
        out[pads_at + N_PADS:] = (math.tanh((own_score - other_score) / SCORE_DIFF_SCALE),
                                  state.clock_s / CLOCK_SCALE_S, float(state.is_overtime), float(state.kickoff_pending))
        # _finish's clip and cast, with the bounds already in float64 (the same values)
        return np.clip(out, low, high, out=out).astype(np.float32)

    def _team_frame(self, team: int, state: GameState) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
        """What every agent of ``team`` sees alike: car features, the ball block and pad timers in the team's
        frame."""
        ball = state.ball
        ball_block = np.concatenate((ball.pos, ball.vel, ball.ang_vel))
        timers = np.asarray(state.pad_timers, dtype=np.float64) / PAD_COOLDOWN
        if team == BLUE:  # the world frame: the features as they are (build copies them into its output)
            return self._cached_cars, ball_block / _BALL_SCALE, timers
        cars = {name: features * _FEATURE_MIRROR for name, features in self._cached_cars.items()}
        return cars, ball_block * _BALL_MIRROR / _BALL_SCALE, timers[PAD_MIRROR]


# ================================================================= the seed's minigame sensors
class SeedBarrierSensors(ObsBuilder):
    """``SeedSensors`` plus the seed's Barrier sensor (21 numbers; 18 without the goal sensor).

    ====== ================== ==================================================================== =======
    index  sensor             value                                                                range
    ====== ================== ==================================================================== =======
    0-17   general            ``SeedSensors``                                                      above
    18-20  barrier -> ball    ball - centre of the first ``state.obstacles`` box, team frame,      [-1, 1]
                              / ARENA_DIAGONAL; zeros when there is no barrier
    ====== ================== ==================================================================== =======

    The z part tells a lifted barrier (centre high above the ball) from one standing on the floor.
    """

    def __init__(self, goal_sensor: bool = True):
        self.general = SeedSensors(goal_sensor)
        self.size = self.general.size + 3
        g = self.general.space(1, 0)
        self._space = _box(np.concatenate([g.low, [-1.0] * 3]), np.concatenate([g.high, [1.0] * 3]))

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        _check_sizes(blue_size, orange_size)
        return self._space

    def build(self, agent: str, state: GameState) -> np.ndarray:
        extra = np.zeros(3)
        if state.obstacles and agent in state.cars:
            extra = (state.ball.pos - np.asarray(state.obstacles[0].center)) * team_sign(agent) / ARENA_DIAGONAL
        return _finish(np.concatenate([self.general.build(agent, state), extra]), self._space)


class SeedAerialSensors(ObsBuilder):
    """``SeedSensors`` plus the seed's Aerial sensors (22 numbers; 19 without the goal sensor).

    ====== ================== ==================================================================== =======
    index  sensor             value                                                                range
    ====== ================== ==================================================================== =======
    0-17   general            ``SeedSensors``                                                      above
    18     ball frozen        the ball still hangs where it was placed (``mode_state["ball_frozen"]``) {0, 1}
    19     release countdown  seconds until the ball is released / the release delay                [0, 1]
    20     aerial touch done  this agent made this round's valid aerial touch                       {0, 1}
    21     touch state        1: touched the ball and waiting for reset (not on the ground since),  {0, 1}
                              0: ready
    ====== ================== ==================================================================== =======

    The flags come from ``GameState.mode_state`` (the Aerial minigame fills it); elsewhere they are zeros.
    """

    def __init__(self, goal_sensor: bool = True):
        self.general = SeedSensors(goal_sensor)
        self.size = self.general.size + 4
        g = self.general.space(1, 0)
        self._space = _box(np.concatenate([g.low, [0.0] * 4]), np.concatenate([g.high, [1.0] * 4]))

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        _check_sizes(blue_size, orange_size)
        return self._space

    def build(self, agent: str, state: GameState) -> np.ndarray:
        mode = state.mode_state
        release_after = float(mode.get("release_after_s", 0.0))
        extra = [float(mode.get("ball_frozen", False)),
                 float(mode.get("release_in_s", 0.0)) / release_after if release_after > 0.0 else 0.0,
                 float(mode.get("aerial_touch_done", {}).get(agent, False)),
                 float(mode.get("touch_waiting_reset", {}).get(agent, False))]
        return _finish(np.concatenate([self.general.build(agent, state), extra]), self._space)


# ================================================================= composition and the registry
class CombinedObs(ObsBuilder):
    """The concatenation of several builders' observations, in order (e.g. seed sensors + rays)."""

    def __init__(self, builders: Sequence[ObsBuilder]):
        builders = list(builders)
        if not builders or not all(isinstance(b, ObsBuilder) for b in builders):
            raise ValueError(f"builders: expected a non-empty list of ObsBuilder, got {builders!r}")
        self.builders = builders

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        parts = [b.space(blue_size, orange_size) for b in self.builders]
        return _box(np.concatenate([p.low for p in parts]), np.concatenate([p.high for p in parts]))

    def reset(self, state: GameState) -> None:
        for b in self.builders:
            b.reset(state)

    def build(self, agent: str, state: GameState) -> np.ndarray:
        return np.concatenate([b.build(agent, state) for b in self.builders]).astype(np.float32)


OBS_BUILDERS: dict[str, type[ObsBuilder]] = {
    "seed_sensors": SeedSensors, "ray": RaySensor, "team_relative": TeamRelativeObs,
    "seed_barrier": SeedBarrierSensors, "seed_aerial": SeedAerialSensors}


def _construct(name: str, kwargs: dict) -> ObsBuilder:
    if name not in OBS_BUILDERS:
        raise ValueError(f"observation: unknown observation builder {name!r}; allowed: {sorted(OBS_BUILDERS)} "
                         f"or several joined with '+'")
    cls = OBS_BUILDERS[name]
    allowed = [p for p in inspect.signature(cls.__init__).parameters if p != "self"]
    unknown = sorted(set(kwargs) - set(allowed))
    if unknown:
        raise ValueError(f"observation.{name}: unknown option(s) {unknown}; allowed: {allowed}")
    return cls(**kwargs)


def make_obs_builder(name: str, **kwargs) -> ObsBuilder:
    """A builder by registry name, with its options: ``make_obs_builder("ray", n_rays=12)``.

    Several names joined with ``+`` build a ``CombinedObs`` in that order; each part's options then go in a
    mapping under its name: ``make_obs_builder("seed_sensors+ray", ray={"n_rays": 12})``.
    """
    if not isinstance(name, str):
        raise ValueError(f"observation: expected a builder name, got {name!r}")
    parts = [p.strip() for p in name.split("+")]
    if len(parts) == 1:
        return _construct(parts[0], kwargs)
    for p in parts:
        if p not in OBS_BUILDERS:
            _construct(p, {})  # raises, naming the allowed ones
    unknown = sorted(set(kwargs) - set(parts))
    if unknown:
        raise ValueError(f"observation: unknown option(s) {unknown} for {name!r}; allowed: {parts} "
                         f"(each a mapping of that builder's options)")
    for key, value in kwargs.items():
        if not isinstance(value, dict):
            raise ValueError(f"observation.{key}: expected a mapping of options, got {value!r}")
    return CombinedObs([_construct(p, dict(kwargs.get(p, {}))) for p in parts])
