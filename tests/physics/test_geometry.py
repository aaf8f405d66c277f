"""The arena's distance field, ray casts and mesh agree with each other and with the game's dimensions."""
import math

import numpy as np
import pybullet as pb
import pytest

from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_geometry import arena_distance, arena_mesh, arena_raycast, arena_sdf

R = C.ARENA_FILLET_RADIUS


@pytest.mark.parametrize("point,dist,normal", [
    ((0.0, 0.0, 10.0), 10.0, (0, 0, 1)),  # floor
    ((0.0, 0.0, 2000.0), 48.0, (0, 0, -1)),  # ceiling
    ((4000.0, 0.0, 1000.0), 96.0, (-1, 0, 0)),  # side wall
    ((2500.0, 5000.0, 1000.0), 120.0, (0, -1, 0)),  # back wall beside the goal
    ((0.0, 5500.0, 100.0), 100.0, (0, 0, 1)),  # goal floor, inside the net
    ((0.0, 5950.0, 300.0), 50.0, (0, -1, 0)),  # back of the net
])
def test_distance_and_normal_at_known_points(point, dist, normal):
    d, nx, ny, nz = arena_sdf(*point)
    assert d == pytest.approx(dist, abs=1e-6)
    np.testing.assert_allclose((nx, ny, nz), normal, atol=1e-6)


@pytest.mark.parametrize("point", [(2000.0, 5300.0, 100.0), (0.0, 5300.0, 800.0), (0.0, 0.0, -5.0),
                                   (4200.0, 0.0, 500.0), (3600.0, 4600.0, 500.0), (0.0, 6100.0, 100.0)])
def test_solid_regions_are_negative(point):
    assert arena_distance(*point) < 0.0  # behind the back wall, above the crossbar, below the floor, ...


def test_corner_planes_sit_at_the_wiki_position():
    # far from the ramps the 45 degree corner is the plane |x| + |y| = 8064
    x, y = 3700.0, 4300.0
    assert arena_distance(x, y, 1000.0) == pytest.approx((C.ARENA_CORNER_SUM - x - y) / math.sqrt(2), abs=1e-6)


def test_ramp_is_a_quarter_circle_between_floor_and_wall():
    cx, cz = C.ARENA_EXTENT_X - R, R  # centre of the floor-to-side-wall ramp
    for angle in np.linspace(0.05, math.pi / 2 - 0.05, 7):
        px, pz = cx + (R - 30.0) * math.sin(angle), cz - (R - 30.0) * math.cos(angle)
        assert arena_distance(px, 0.0, pz) == pytest.approx(30.0, abs=1e-6)


def test_gradient_matches_finite_differences():
    rng = np.random.default_rng(0)
    for _ in range(200):
        p = rng.uniform([-4000, -5000, 10], [4000, 5000, 2000])
        d, *n = arena_sdf(*p)
        if d < 5.0:
            continue
        h = 1e-3
        fd = [(arena_distance(*(p + h * e)) - arena_distance(*(p - h * e))) / (2 * h) for e in np.eye(3)]
        np.testing.assert_allclose(n, fd, atol=1e-3)


def test_raycasts_hit_floor_wall_ramp_and_pass_through_the_goal_mouth():
    hit, t, *n = arena_raycast(0.0, 0.0, 40.0, 0.0, 0.0, -1.0, 100.0)
    assert hit and t == pytest.approx(40.0, abs=0.05) and n == pytest.approx([0, 0, 1], abs=1e-6)
    hit, t, *_ = arena_raycast(0.0, 0.0, 1000.0, 1.0, 0.0, 0.0, 10000.0)
    assert hit and t == pytest.approx(C.ARENA_EXTENT_X, abs=0.05)
    # a ray along the floor at z = 50 meets the ramp circle where (x - cx)^2 + (50 - R)^2 = R^2
    expected = C.ARENA_EXTENT_X - R + math.sqrt(R**2 - (R - 50.0) ** 2)
    hit, t, *_ = arena_raycast(0.0, 0.0, 50.0, 1.0, 0.0, 0.0, 10000.0)
    assert hit and t == pytest.approx(expected, abs=0.1)
    hit, t, *n = arena_raycast(0.0, 0.0, 100.0, 0.0, 1.0, 0.0, 10000.0)
    assert hit and t == pytest.approx(C.ARENA_EXTENT_Y + C.GOAL_DEPTH, abs=0.05)  # the back of the net
    hit, t, *_ = arena_raycast(0.0, 0.0, 100.0, 0.0, 0.0, -1.0, 50.0)
    assert not hit


def test_mesh_lies_on_the_surface_and_faces_inside():
    verts, tris = arena_mesh()
    assert tris.dtype == np.int32 and len(tris) < 20000
    assert max(abs(arena_distance(*v)) for v in verts) < 0.5
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    centroid = (a + b + c) / 3
    inside = [arena_distance(*(p + 6.0 * n)) for p, n in zip(centroid, normal)]  # clear of the fairings' folds
    assert min(inside) > 0.0


def test_thrown_balls_stay_inside_the_pybullet_arena():
    """A ball thrown hard at walls, ramps, corners and into both goals never leaves the mesh."""
    cid = pb.connect(pb.DIRECT)
    try:
        pb.setGravity(0, 0, C.GRAVITY_Z / 100, physicsClientId=cid)
        pb.setPhysicsEngineParameter(fixedTimeStep=1 / 120, physicsClientId=cid)
        verts, tris = arena_mesh()
        shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=(verts / 100).tolist(),
                                        indices=tris.ravel().tolist(), flags=pb.GEOM_FORCE_CONCAVE_TRIMESH,
                                        physicsClientId=cid)
        pb.createMultiBody(0, shape, physicsClientId=cid)
        ball = pb.createMultiBody(30, pb.createCollisionShape(pb.GEOM_SPHERE, radius=C.BALL_RADIUS / 100,
                                                              physicsClientId=cid), physicsClientId=cid)
        pb.changeDynamics(ball, -1, restitution=0.6, physicsClientId=cid)
        rng = np.random.default_rng(0)
        targets = [(4096, 0, 300), (3000, 5120, 300), (3600, 4500, 100), (0, 5500, 200), (0, -5500, 200),
                   (4000, 0, 1900), (0, 0, 2048), (2000, 4000, 0)]
        for target in targets:
            start = np.array([0.0, 0.0, 600.0])
            direction = np.array(target, float) - start
            vel = direction / np.linalg.norm(direction) * rng.uniform(3000, 6000)
            pb.resetBasePositionAndOrientation(ball, (start / 100).tolist(), (0, 0, 0, 1), physicsClientId=cid)
            pb.resetBaseVelocity(ball, (vel / 100).tolist(), (0, 0, 0), physicsClientId=cid)
            for _ in range(360):
                pb.stepSimulation(physicsClientId=cid)
                pos = np.array(pb.getBasePositionAndOrientation(ball, physicsClientId=cid)[0]) * 100
                assert arena_distance(*pos) > 0.0, (target, pos)
    finally:
        pb.disconnect(cid)
