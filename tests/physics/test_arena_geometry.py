"""The arena's shape: its distance field is exact near the surface, ray casts find the first surface, and the
PyBullet mesh built from the same surface keeps a ball inside the field and the goals."""
import math
import time

import numpy as np
import pybullet as pb
import pytest
from numba import njit

from rocketdrl_ma.physics import arena_geometry as G
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_geometry import (FAIRING_END_X, arena_mesh, arena_raycast, arena_sdf, arena_sdf_many,
                                                 is_inside_arena)

# On 2 xdist workers (`make test`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_arena_geometry")

R = C.ARENA_FILLET_RADIUS
S = math.sqrt(0.5)
BALL_R = C.BALL_RADIUS
DT = 1.0 / C.TICK_RATE_HZ


@pytest.fixture(scope="module")
def mesh():
    return arena_mesh()


def _random_interior(rng, n, margin=1.0):
    """Uniform points of the playable space (field and goals) with at least ``margin`` of clearance."""
    pts = rng.uniform([-C.ARENA_EXTENT_X, -G.GOAL_BACK_Y, 0.0], [C.ARENA_EXTENT_X, G.GOAL_BACK_Y, C.ARENA_HEIGHT],
                      size=(8 * n, 3))
    return pts[arena_sdf_many(pts) >= margin][:n]


# ================================================================= distance field
@pytest.mark.parametrize("point,dist,normal", [
    ((0.0, 0.0, 10.0), 10.0, (0, 0, 1)),  # floor
    ((0.0, -3000.0, 1.0), 1.0, (0, 0, 1)),
    ((0.0, 0.0, 2000.0), 48.0, (0, 0, -1)),  # ceiling
    ((4000.0, 0.0, 1000.0), 96.0, (-1, 0, 0)),  # side walls
    ((-4090.0, 1000.0, 1000.0), 6.0, (1, 0, 0)),
    ((2500.0, 5000.0, 1000.0), 120.0, (0, -1, 0)),  # back wall beside the goal
    ((0.0, -5000.0, 1500.0), 120.0, (0, 1, 0)),  # back wall above the crossbar
    ((3700.0, 4300.0, 1000.0), (C.ARENA_CORNER_SUM - 8000.0) * S, (-S, -S, 0)),  # 45 degree corner
    ((-3700.0, -4300.0, 1000.0), (C.ARENA_CORNER_SUM - 8000.0) * S, (S, S, 0)),
    ((0.0, 5500.0, 100.0), 100.0, (0, 0, 1)),  # goal floor, inside the net
    ((0.0, -5500.0, 600.0), C.GOAL_HEIGHT - 600.0, (0, 0, -1)),  # goal roof
    ((0.0, 5950.0, 300.0), 50.0, (0, -1, 0)),  # back of the net
    ((850.0, 5600.0, 300.0), C.GOAL_HALF_WIDTH - 850.0, (-1, 0, 0)),  # side of the net
])
def test_distance_and_normal_at_known_points(point, dist, normal):
    d, nx, ny, nz = arena_sdf(*point)
    assert d == pytest.approx(dist, abs=1e-9)
    np.testing.assert_allclose((nx, ny, nz), normal, atol=1e-12)


@pytest.mark.parametrize("centre,direction", [
    ((C.ARENA_EXTENT_X - R, 0.0, R), (S, 0.0, -S)),  # floor to side wall, 45 degrees round the fillet centre
    ((2500.0, -(C.ARENA_EXTENT_Y - R), R), (0.0, -S, -S)),  # floor to back wall, beside the goal
    ((-(C.ARENA_EXTENT_X - R), 500.0, C.ARENA_HEIGHT - R), (-S, 0.0, S)),  # side wall to ceiling
    ((2500.0, C.ARENA_EXTENT_Y - R, C.ARENA_HEIGHT - R), (0.0, S, S)),  # back wall to ceiling
])
def test_ramps_are_quarter_circles(centre, direction):
    """A point at 45 degrees round a fillet's centre, 30 uu in from the curved surface, is 30 uu from it, and
    its normal points back at the centre."""
    c, u = np.array(centre), np.array(direction)
    d, *n = arena_sdf(*(c + (R - 30.0) * u))
    assert d == pytest.approx(30.0, abs=1e-9)
    np.testing.assert_allclose(n, -u, atol=1e-12)
    assert arena_sdf(*(c + (R + 30.0) * u))[0] == pytest.approx(-30.0, abs=1e-9)


def test_vertical_corner_edges_are_rounded():
    """Where a side wall meets a 45 degree corner plane the edge is a vertical cylinder of radius r."""
    cx, cy = G.X_IN, G.V1_Y  # the inner octagon's vertex: the cylinder's axis
    a = math.radians(22.5)  # halfway between the side wall's normal (0 deg) and the corner plane's (45 deg)
    d, *n = arena_sdf(cx + (R - 10.0) * math.cos(a), cy + (R - 10.0) * math.sin(a), 1000.0)
    assert d == pytest.approx(10.0, abs=1e-9)
    np.testing.assert_allclose(n, (-math.cos(a), -math.sin(a), 0.0), atol=1e-12)


@pytest.mark.parametrize("point", [
    (2000.0, 5300.0, 100.0),  # behind the back wall, beside the goal
    (0.0, 5300.0, 800.0),  # above the crossbar
    (0.0, -5300.0, 700.0),
    (0.0, 0.0, -5.0),  # below the floor
    (0.0, 0.0, 2050.0),  # above the ceiling
    (4200.0, 0.0, 500.0),  # beyond a side wall
    (3600.0, 4600.0, 500.0),  # beyond a corner
    (0.0, 6100.0, 100.0),  # behind the net
    (1000.0, 5500.0, 100.0),  # beside the net
    (4096.0 - 10.0, 0.0, 10.0),  # inside the floor-to-wall ramp's solid
    (C.GOAL_HALF_WIDTH + 200.0, C.ARENA_EXTENT_Y - 20.0, 20.0),  # under the fairing's slope beside a post
])
def test_solid_regions_are_negative(point):
    assert arena_sdf(*point)[0] < 0.0
    assert not is_inside_arena(*point, 0.0)


def test_floor_is_flat_through_the_goal_mouth():
    for y in np.linspace(4000.0, 5950.0, 50):
        for x in (0.0, C.GOAL_HALF_WIDTH - 100.0, -(C.GOAL_HALF_WIDTH - 100.0)):
            d, nx, ny, nz = arena_sdf(x, y, 20.0)
            assert d == pytest.approx(20.0, abs=1e-9) and nz == 1.0
    # ... while beside the posts the floor curves up (the fairing's quarter pipe) onto the back-wall ramp
    assert arena_sdf(C.GOAL_HALF_WIDTH + 300.0, 5050.0, 20.0)[0] < 0.0


def test_distance_is_exact_near_the_surface_and_never_overestimates(mesh):
    """Mesh vertices are on the zero level and a step of s uu along the normal gains at most s; the field is
    1-Lipschitz; and no point is farther from the surface than from any mesh vertex (which lie on it)."""
    verts, _ = mesh
    rng = np.random.default_rng(1)
    for v in verts[rng.choice(len(verts), 300, replace=False)]:
        d0, *n = arena_sdf(*v)
        assert abs(d0) < 1e-6
        for s in (0.5, 5.0):
            assert arena_sdf(*(v + s * np.array(n)))[0] <= d0 + s + 1e-6
    pts = _random_interior(rng, 400)
    for p in pts:
        assert arena_sdf(*p)[0] <= np.min(np.linalg.norm(verts - p, axis=1)) + 1e-6
    q = pts + rng.normal(scale=60.0, size=pts.shape)
    dp, dq = arena_sdf_many(pts), arena_sdf_many(q)
    assert np.all(np.abs(dp - dq) <= np.linalg.norm(pts - q, axis=1) + 1e-9)


def test_surface_points_step_along_normal_one_for_one():
    """Away from the goal-post seams, distance grows exactly one for one along the normal of a surface point."""
    rng = np.random.default_rng(2)
    for _ in range(300):
        p = _random_interior(rng, 1, margin=40.0)[0]
        d = rng.normal(size=3)
        hit, t, *n = arena_raycast(*p, *(d / np.linalg.norm(d)), 1e5)
        assert hit
        h = p + t * d / np.linalg.norm(d)
        assert abs(arena_sdf(*h)[0]) < 1e-4
        if np.min(np.abs(np.abs(h[0]) - C.GOAL_HALF_WIDTH)) < 100 and abs(h[1]) > G.GOAL_START_Y - 100:
            continue  # near a post, where the union of field and goal box is only a lower bound inside
        assert arena_sdf(*(h + 3.0 * np.array(n)))[0] == pytest.approx(3.0, abs=1e-6)


def test_gradient_matches_finite_differences():
    rng = np.random.default_rng(0)
    pts = _random_interior(rng, 300, margin=2.0)
    h = 1e-4
    eye = np.eye(3)
    bad = 0
    for p in pts:
        n = np.array(arena_sdf(*p)[1:])
        fd = np.array([(arena_sdf(*(p + h * e))[0] - arena_sdf(*(p - h * e))[0]) / (2 * h) for e in eye])
        assert np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12)
        bad += not np.allclose(n, fd, atol=1e-5)  # a point within h of a medial surface (a kink) may differ
    assert bad <= 1
    assert len(pts) == 300


def test_is_inside_arena_applies_the_margin():
    assert is_inside_arena(0.0, 0.0, 100.0, 99.0)
    assert not is_inside_arena(0.0, 0.0, 100.0, 101.0)
    assert is_inside_arena(0.0, -5800.0, 300.0, 150.0)  # in the blue goal


def test_sdf_is_cheap_from_njit():
    @njit
    def loop(n):
        s = 0.0
        for i in range(n):
            s += arena_sdf((i % 8000) - 4000.0, ((i * 7) % 12000) - 6000.0, (i % 2000) + 10.0)[0]
        return s

    loop(10)
    n = 2_000_000
    # CPU time of this thread, not the wall clock: the cost of the calls, whatever else the machine's cores run
    t0 = time.thread_time()
    loop(n)
    per_call = (time.thread_time() - t0) / n
    assert per_call < 300e-9  # ~20 ns on a desktop core; this only catches a gross regression


# ================================================================= ray casts
def test_ray_down_hits_the_floor():
    hit, t, *n = arena_raycast(0.0, 0.0, 40.0, 0.0, 0.0, -1.0, 50.0)
    assert hit and t == pytest.approx(40.0, abs=1e-9) and n == pytest.approx([0, 0, 1], abs=1e-12)
    hit, t, *_ = arena_raycast(0.0, 0.0, 100.0, 0.0, 0.0, -1.0, 50.0)
    assert not hit and t == 50.0
    hit, t, *_ = arena_raycast(0.0, 5700.0, 30.0, 0.0, 0.0, -1.0, 50.0)  # in the goal
    assert hit and t == pytest.approx(30.0, abs=1e-9)


def test_ray_hits_side_wall_and_ceiling():
    hit, t, *n = arena_raycast(0.0, 0.0, 1000.0, 1.0, 0.0, 0.0, 10000.0)
    assert hit and t == pytest.approx(C.ARENA_EXTENT_X, abs=1e-6) and n == pytest.approx([-1, 0, 0], abs=1e-9)
    hit, t, *n = arena_raycast(100.0, -200.0, 1000.0, 0.0, 0.0, 1.0, 5000.0)
    assert hit and t == pytest.approx(C.ARENA_HEIGHT - 1000.0, abs=1e-6) and n == pytest.approx([0, 0, -1])


@pytest.mark.parametrize("z", [5.0, 50.0, 200.0, 390.0])
def test_ray_along_the_floor_meets_the_ramp_circle(z):
    """A horizontal ray towards the side wall meets the ramp where (x - cx)^2 + (z - r)^2 = r^2."""
    cx = C.ARENA_EXTENT_X - R
    x_hit = cx + math.sqrt(R ** 2 - (R - z) ** 2)
    hit, t, *n = arena_raycast(-1000.0, 300.0, z, 1.0, 0.0, 0.0, 10000.0)
    assert hit and t == pytest.approx(x_hit + 1000.0, abs=0.05)
    np.testing.assert_allclose(n, [-(x_hit - cx) / R, 0.0, (R - z) / R], atol=1e-6)


def test_ray_into_the_goal_hits_the_back_of_the_net():
    for x, z in ((0.0, 100.0), (800.0, 30.0), (-500.0, 600.0)):
        hit, t, *n = arena_raycast(x, 0.0, z, 0.0, 1.0, 0.0, 10000.0)
        assert hit and t == pytest.approx(G.GOAL_BACK_Y, abs=1e-6) and n == pytest.approx([0, -1, 0])
    # from inside one net, back across the field, through both mouths into the other net
    hit, t, *n = arena_raycast(0.0, 5900.0, 300.0, 0.0, -1.0, 0.0, 20000.0)
    assert hit and t == pytest.approx(5900.0 + G.GOAL_BACK_Y, abs=1e-6) and n == pytest.approx([0, 1, 0])
    # above the crossbar the ray stops at the back wall
    hit, t, *_ = arena_raycast(0.0, 0.0, 800.0, 0.0, 1.0, 0.0, 10000.0)
    assert hit and t == pytest.approx(C.ARENA_EXTENT_Y, abs=1e-6)


def test_ray_from_solid_hits_at_zero():
    hit, t, *n = arena_raycast(0.0, 0.0, -3.0, 0.0, 0.0, -1.0, 50.0)
    assert hit and t == 0.0 and n == pytest.approx([0, 0, 1])


def test_grazing_rays_along_the_floor_reach_the_far_wall():
    """Sphere tracing would need thousands of steps here; the interval solver is exact."""
    hit, t, *_ = arena_raycast(-3000.0, 0.0, 2.0, 1.0, 0.0, 0.0, 20000.0)
    cx = C.ARENA_EXTENT_X - R
    assert hit and t == pytest.approx(cx + math.sqrt(R ** 2 - (R - 2.0) ** 2) + 3000.0, abs=0.05)


def _reference_hit(p, d, max_len):
    """First sign change of the distance field along the ray: dense sampling, then bisection."""
    ts = np.arange(0.0, max_len + 1.0, 1.0)
    vals = arena_sdf_many(p + ts[:, None] * d)
    below = np.nonzero(vals < 0.0)[0]
    if len(below) == 0:
        return None
    lo, hi = ts[below[0] - 1], ts[below[0]]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if arena_sdf(*(p + mid * d))[0] >= 0.0 else (lo, mid)
    return hi


def test_random_rays_agree_with_a_dense_march():
    rng = np.random.default_rng(3)
    pts = _random_interior(rng, 150, margin=0.5)
    for i, p in enumerate(pts):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        max_len = 60.0 if i % 3 == 0 else 4000.0
        hit, t, *n = arena_raycast(*p, *d, max_len)
        ref = _reference_hit(p, d, max_len)
        assert hit == (ref is not None)
        if hit:
            assert t == pytest.approx(ref, abs=0.05)
            assert arena_sdf(*(p + t * d))[0] == pytest.approx(0.0, abs=0.05)
            assert np.dot(n, d) < 1e-9  # the normal faces back at the ray


def test_raycast_is_cheap_from_njit():
    @njit
    def loop(n, max_len):
        s = 0.0
        for i in range(n):
            a = i * 0.001
            s += arena_raycast((i % 8000) - 4000.0, ((i * 7) % 10000) - 5000.0, (i % 40) + 1.0,
                               0.3 * math.sin(a), 0.3 * math.cos(a), -math.sqrt(0.91), max_len)[1]
        return s

    loop(10, 50.0)
    n = 500_000
    t0 = time.thread_time()  # CPU time, as in test_sdf_is_cheap_from_njit
    loop(n, 50.0)
    assert (time.thread_time() - t0) / n < 1.5e-6  # ~0.1 us on a desktop core


# ================================================================= mesh
def test_mesh_vertices_lie_on_the_surface(mesh):
    verts, tris = mesh
    assert verts.dtype == np.float64 and verts.shape[1] == 3
    assert tris.dtype == np.int32 and tris.shape[1] == 3 and len(tris) < 20000
    assert tris.min() == 0 and tris.max() == len(verts) - 1
    assert np.abs(arena_sdf_many(verts)).max() < 0.5
    # flat parts exactly on their planes
    on_floor = np.abs(verts[:, 2]) < 1e-6
    assert np.all(verts[on_floor, 2] == 0.0) and on_floor.sum() > 100
    # the chords of the curved parts stay within a few uu of the surface, on the inside; where a fairing's slope
    # meets the ramp beside a post the surface folds the other way, and chords across the fold dip up to 3 uu
    # into the solid
    a, b, c = (verts[tris[:, k]] for k in range(3))
    centroid = (a + b + c) / 3.0
    sag = arena_sdf_many(centroid)
    at_fold = ((np.abs(centroid[:, 0]) > C.GOAL_HALF_WIDTH) & (np.abs(centroid[:, 0]) < FAIRING_END_X)
               & (np.abs(centroid[:, 1]) > C.ARENA_EXTENT_Y - R) & (centroid[:, 2] < R))
    assert sag[~at_fold].min() > -1e-6 and sag.max() < 5.0
    assert sag[at_fold].min() > -3.0


def test_mesh_normals_face_the_interior(mesh):
    verts, tris = mesh
    a, b, c = (verts[tris[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    area = np.linalg.norm(normal, axis=1)
    assert area.min() > 1e-3
    normal /= area[:, None]
    centroid = (a + b + c) / 3.0
    assert arena_sdf_many(centroid + 6.0 * normal).min() > 0.0  # 6 uu: clear of the fairings' folds (3 uu deep)
    assert np.all(arena_sdf_many(centroid + normal) > arena_sdf_many(centroid - normal))


def test_finer_fillets_follow_the_curve_closer():
    verts, tris = arena_mesh(fillet_segments=16)
    a, b, c = (verts[tris[:, k]] for k in range(3))
    assert np.abs(arena_sdf_many(verts)).max() < 0.5
    assert arena_sdf_many((a + b + c) / 3.0).max() < 1.5
    assert len(tris) > len(arena_mesh()[1])


@pytest.fixture(scope="module")
def bullet(mesh):
    verts, tris = mesh
    cid = pb.connect(pb.DIRECT)
    pb.setGravity(0, 0, C.GRAVITY_Z / C.UU_PER_M, physicsClientId=cid)
    pb.setPhysicsEngineParameter(fixedTimeStep=DT, numSubSteps=1, physicsClientId=cid)
    shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=(verts / C.UU_PER_M).tolist(), indices=tris.ravel().tolist(),
                                    flags=pb.GEOM_FORCE_CONCAVE_TRIMESH, physicsClientId=cid)
    pb.createMultiBody(0, shape, physicsClientId=cid)
    ball = pb.createMultiBody(C.BALL_MASS, pb.createCollisionShape(pb.GEOM_SPHERE, radius=BALL_R / C.UU_PER_M,
                                                                   physicsClientId=cid), physicsClientId=cid)
    pb.changeDynamics(ball, -1, restitution=C.BALL_RESTITUTION, lateralFriction=C.BALL_FRICTION,
                      activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=cid)
    yield cid, ball
    pb.disconnect(cid)


def test_mesh_has_no_holes_for_rays(bullet):
    """Every ray that meets the distance field's surface meets the mesh no later (the mesh's chords lie just
    inside the curved surface) and at a point of that surface: no gaps, in the field or the goals."""
    cid, _ = bullet
    rng = np.random.default_rng(4)
    origins = _random_interior(rng, 3000, margin=5.0)
    origins[:600] = rng.uniform([-800, 4900, 5], [800, 5990, 630], size=(600, 3))  # in and around the goals
    origins[:300, 1] *= -1
    origins = origins[arena_sdf_many(origins) > 5.0]  # clear of the chords, which cut up to ~2 uu inside
    dirs = rng.normal(size=origins.shape)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    L = 15000.0
    expected = np.array([arena_raycast(*o, *d, L)[1] for o, d in zip(origins, dirs)])
    ends = origins + L * dirs
    got = []
    for k in range(0, len(origins), 1000):  # rayTestBatch takes at most 16384 rays
        got += pb.rayTestBatch((origins[k:k + 1000] / C.UU_PER_M).tolist(), (ends[k:k + 1000] / C.UU_PER_M).tolist(),
                               physicsClientId=cid)
    frac = np.array([r[2] for r in got])
    hit_pos = np.array([r[3] for r in got]) * C.UU_PER_M
    miss = [i for i, r in enumerate(got) if r[0] < 0]
    assert not miss, (origins[miss[:5]], dirs[miss[:5]], expected[miss[:5]])  # every ray hits the mesh
    t_mesh = frac * L
    assert np.all(t_mesh <= expected + 0.5)
    d_hit = arena_sdf_many(hit_pos)
    assert d_hit.min() > -0.5 and d_hit.max() < 5.0


def _run_ball(cid, ball, pos, vel, ticks, check):
    pb.resetBasePositionAndOrientation(ball, (np.asarray(pos) / C.UU_PER_M).tolist(), (0, 0, 0, 1),
                                       physicsClientId=cid)
    pb.resetBaseVelocity(ball, (np.asarray(vel) / C.UU_PER_M).tolist(), (0, 0, 0), physicsClientId=cid)
    speed = float(np.linalg.norm(vel))
    for tick in range(ticks):
        pb.stepSimulation(physicsClientId=cid)
        p = np.array(pb.getBasePositionAndOrientation(ball, physicsClientId=cid)[0]) * C.UU_PER_M
        v = np.array(pb.getBaseVelocity(ball, physicsClientId=cid)[0]) * C.UU_PER_M
        # Bullet's contacts are discrete: a ball may sink up to one tick's travel into a surface before the
        # solver pushes it out. Anything beyond that would mean it passed a hole or a crack.
        allowed = max(speed, float(np.linalg.norm(v))) * DT + 5.0
        d = arena_sdf(*p)[0]
        assert d >= BALL_R - allowed, (pos, vel, tick, p, d)
        check(p)
        speed = float(np.linalg.norm(v))
    return p


def test_thrown_balls_stay_inside_the_pybullet_arena(bullet):
    """Balls thrown at up to 6000 uu/s at the walls, ramps, corners, ceiling and into both goals stay inside."""
    cid, ball = bullet
    rng = np.random.default_rng(5)
    targets = [(4096, 0, 100), (4096, 2000, 1900), (3000, 5120, 100), (3500, 4564, 100), (3500, 4564, 2000),
               (-3800, -4264, 1000), (0, 5500, 200), (0, -5500, 300), (800, 6000, 600), (-880, 5120, 640),
               (0, 5120, 700), (0, 0, 2048), (-4096, -3800, 0), (2000, -5120, 1000)]
    for k in range(len(targets) + 10):
        start = rng.uniform([-2000, -3000, 200], [2000, 3000, 1500])
        if k < len(targets):
            direction = np.array(targets[k], float) - start
        else:
            direction = rng.normal(size=3)
        vel = direction / np.linalg.norm(direction) * rng.uniform(2500.0, 6000.0)
        _run_ball(cid, ball, start, vel, 240, lambda p: None)


def test_ball_rolled_into_a_goal_stays_in_the_goal_box(bullet):
    cid, ball = bullet
    w, h, back = C.GOAL_HALF_WIDTH, C.GOAL_HEIGHT, G.GOAL_BACK_Y
    for sign, vx, vy in ((1.0, 0.0, 2500.0), (1.0, 700.0, 2000.0), (-1.0, -500.0, 3000.0), (-1.0, 300.0, 1500.0)):
        entered = []

        def check(p):
            if abs(p[1]) > C.GOAL_SCORE_THRESHOLD_Y + BALL_R:
                entered.append(p)
                assert abs(p[0]) <= w - BALL_R + 5.0 and p[2] <= h - BALL_R + 5.0
                assert abs(p[1]) <= back - BALL_R + 5.0

        p = _run_ball(cid, ball, (0.0, sign * 3500.0, C.BALL_REST_Z), (vx, sign * vy, 0.0), 480, check)
        assert entered and abs(p[1]) > C.GOAL_SCORE_THRESHOLD_Y + BALL_R  # it went in and stayed in
