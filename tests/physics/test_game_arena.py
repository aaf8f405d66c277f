"""The game-shaped arena (``arena_shape="game"``, ``physics/game_arena.py``): its distance field, contacts, ray casts
and Bullet mesh agree with each other, and the option selects it without touching the classic arena."""
import copy

import numpy as np
import pybullet as pb
import pytest

from rocketdrl_ma import physics
from rocketdrl_ma.physics.arena_geometry import arena_sdf
from rocketdrl_ma.physics.arena_shape import ARENA_SHAPES, arena_shape_index
from rocketdrl_ma.physics.state import yaw_rot_mat
from rocketdrl_ma.physics.game_arena import (GAME_ARENA, game_arena_mesh, game_arena_raycast, game_arena_sdf,
                                             game_arena_sdf_many, game_surface_contacts)
from rocketdrl_ma.physics.world import M_PER_UU

MESH_TOLERANCE_UU = 2.0  # the brief's "within a couple of uu" between the cars' Bullet mesh and the distance field


def test_arena_shape_is_validated_and_classic_by_default():
    assert ARENA_SHAPES == ("classic", "game")
    with pytest.raises(ValueError, match=r"arena_shape: must be one of 'classic', 'game', got 'round'"):
        arena_shape_index("round")
    with pytest.raises(ValueError, match="arena_shape"):
        physics.Arena(arena_shape="round")
    arena = physics.Arena()
    try:
        assert arena.batch.arena_shape == "classic"
    finally:
        arena.close()


def test_dimensions_are_data():
    with pytest.raises(AttributeError):
        GAME_ARENA.floor_fillet = 300.0  # frozen
    assert (GAME_ARENA.floor_fillet, GAME_ARENA.back_floor_fillet, GAME_ARENA.post_floor_fillet) == (256.0, 160.0, 96.0)
    assert GAME_ARENA.ceiling_fillet == 512.0 and GAME_ARENA.goal_half_width == 896.0


@pytest.mark.parametrize("point", [
    (0.0, 0.0, 100.0),          # above the open floor
    (0.0, 0.0, 1948.0),         # under the ceiling
    (3996.0, 0.0, 1000.0),      # in front of a side wall
    (2000.0, 5020.0, 1000.0),   # in front of a back wall
    (0.0, 5200.0, 100.0),       # over the net's flat floor
    (0.0, 5900.0, 256.0),       # in front of the net's back (a half cylinder reaching 6000)
    (796.0, 5600.0, 300.0),     # beside the net's side wall
])
def test_distance_on_the_flat_parts(point):
    assert game_arena_sdf(*point)[0] == pytest.approx(100.0, abs=1e-6)


def test_the_net_floor_rises_16_uu_to_the_back():
    slope = np.arctan(16.0 / 405.0)
    assert game_arena_sdf(0.0, 5500.0, 100.0)[0] == pytest.approx((100.0 - 16.0 * 145.0 / 405.0) * np.cos(slope))


def test_normals_are_the_distance_gradient():
    rng = np.random.default_rng(1)
    points = rng.uniform([-4000.0, -5900.0, 10.0], [4000.0, 5900.0, 2040.0], size=(3000, 3))
    points = points[game_arena_sdf_many(points) > 5.0]
    h = 1e-3
    for p in points[:500]:
        _, nx, ny, nz = game_arena_sdf(*p)
        grad = [(game_arena_sdf(*(p + h * e))[0] - game_arena_sdf(*(p - h * e))[0]) / (2 * h) for e in np.eye(3)]
        # where the floor fillet's radius changes along the wall (round the corner-to-back roundings, beside the
        # posts) the normal is the profile's and leaves out that change
        constant_radius = abs(p[1]) < 4000.0 or p[2] > GAME_ARENA.floor_fillet
        assert np.allclose(grad, (nx, ny, nz), atol=1e-4 if constant_radius else 0.05), p


def test_ray_casts_stop_on_the_surface():
    rng = np.random.default_rng(2)
    origins = rng.uniform([-3800.0, -5000.0, 50.0], [3800.0, 5000.0, 2000.0], size=(400, 3))
    dirs = rng.normal(size=(400, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    for o, d in zip(origins, dirs):
        if game_arena_sdf(*o)[0] <= 0.0:
            continue
        hit, t, nx, ny, nz = game_arena_raycast(*o, *d, 20000.0)
        assert hit
        q = o + t * d
        assert abs(game_arena_sdf(*q)[0]) < 1e-3
        assert np.dot((nx, ny, nz), d) < 0.0  # the hit normal faces the ray


def test_a_ball_on_the_floor_and_in_a_fillet_corner():
    out = np.zeros((8, 4))
    n = game_surface_contacts(0.0, 0.0, 90.0, 93.0, out)
    assert n == 1 and np.allclose(out[0], (90.0, 0.0, 0.0, 1.0))
    # resting on the side wall's fillet polygon: the chord under it, nothing else
    d, nx, ny, nz = game_arena_sdf(3950.0, 0.0, 120.0)
    n = game_surface_contacts(3950.0 - 60.0 * nx, 0.0, 120.0 - 60.0 * nz, 93.0, out)
    assert n >= 1 and min(out[:n, 0]) == pytest.approx(d - 60.0, abs=1e-6)


MOUTH_LINES = [(x, z, sy) for x in (-700.0, -300.0, 0.0, 300.0, 700.0) for z in (93.15, 200.0, 450.0)
               for sy in (1.0, -1.0)]


def test_a_ball_goes_into_either_goal_across_the_whole_mouth():
    """The back walls' floor fillets stop at the goal mouths: a ball rolled or flown at the goal anywhere across
    its mouth goes in and scores (the contact query once kept the fillet's chords across the opening)."""
    batch = physics.ArenaBatch(len(MOUTH_LINES), arena_shape="game")
    try:
        for arena, (x, z, sy) in zip(batch.arenas, MOUTH_LINES):
            arena.ball.set_state(physics.BallState(pos=np.array([x, sy * 4300.0, z]),
                                                   vel=np.array([0.0, sy * 1500.0, 0.0])))
        batch.step(90)
        for arena, (x, z, sy) in zip(batch.arenas, MOUTH_LINES):
            pos = arena.ball.get_state().pos
            assert sy * pos[1] > GAME_ARENA.back_y + 200.0, f"ball from x = {x}, z = {z} stopped at {pos}"
            assert arena.scoring_team() == (0 if sy > 0 else 1)
    finally:
        batch.close()


def test_bullet_mesh_lies_on_the_distance_field_away_from_the_goal_mouths():
    verts, tris = game_arena_mesh(with_floor_and_ceiling=False)
    away = (np.abs(verts[:, 1]) < 4700.0) | (np.abs(verts[:, 0]) > 1500.0)
    d = game_arena_sdf_many(verts[away])
    assert np.abs(d).max() < 0.25  # the fitted roundings meet the corner walls 0.2 uu off tangent
    centroids = verts[tris].mean(axis=1)
    # chords of the vertical roundings sag at most r (1 - cos(half a segment's angle)): 0.3 uu
    assert np.abs(game_arena_sdf_many(centroids)).max() < 1.0


def test_bullet_mesh_covers_every_wall_ray():
    """Rays from the field at every wall and the roundings' ends meet the cars' mesh where they meet the distance
    field (the mesh once left out the walls between each flat wall's last station and the vertical rounding,
    floor to ceiling: cars' boxes went through them)."""
    verts, tris = game_arena_mesh(with_floor_and_ceiling=False)
    cid = pb.connect(pb.DIRECT)
    try:
        shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=(verts * M_PER_UU).tolist(),
                                        indices=tris.reshape(-1).tolist(), flags=pb.GEOM_FORCE_CONCAVE_TRIMESH,
                                        physicsClientId=cid)
        pb.createMultiBody(0, shape, physicsClientId=cid)
        rng = np.random.default_rng(7)
        yaw = rng.uniform(0.0, 2.0 * np.pi, 2000)
        z = rng.uniform(30.0, 2000.0, 2000)
        origins = np.column_stack([np.zeros(2000), np.zeros(2000), z])
        dirs = np.column_stack([np.cos(yaw), np.sin(yaw), rng.uniform(-0.2, 0.2, 2000)])
        dirs /= np.linalg.norm(dirs, axis=1)[:, None]
        expected = np.array([game_arena_raycast(*o, *d, 20000.0)[1] for o, d in zip(origins, dirs)])
        hits = pb.rayTestBatch((origins * M_PER_UU).tolist(), ((origins + dirs * 20000.0) * M_PER_UU).tolist(),
                               physicsClientId=cid)
    finally:
        pb.disconnect(cid)
    found = np.array([h[2] * 20000.0 if h[0] >= 0 else np.inf for h in hits])
    hit = origins + dirs * expected[:, None]
    walls = (hit[:, 2] > 1.0) & (hit[:, 2] < GAME_ARENA.height - 1.0)  # the floor and ceiling are the world's planes
    # (a ray grazing the goal frame's bevels can slip between their vertices and the back wall's)
    walls &= ~((np.abs(hit[:, 1]) > 5100.0) & (np.abs(hit[:, 0]) < 920.0) & (hit[:, 2] < 660.0))
    assert walls.sum() > 1000
    assert np.abs(found - expected)[walls].max() < 2.0  # the vertical roundings' chords sag 1.1 uu


def _arena_contacts(arena, car) -> np.ndarray:
    """The points (uu) where the car's PyBullet box touches the arena's mesh (not the floor or ceiling planes)."""
    world = arena.batch
    body = world._slot(car.id).body
    mesh_body = world._static_bodies[2 + arena.index]
    points = pb.getContactPoints(bodyA=body, bodyB=mesh_body, physicsClientId=world.client)
    return np.array([p[6] for p in points]).reshape(-1, 3) / M_PER_UU - world.origins[arena.index]


def _rot(roll: float) -> np.ndarray:
    c, s = np.cos(roll), np.sin(roll)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def test_a_car_dropped_on_its_side_onto_a_fillet_touches_the_mesh_on_the_distance_field():
    arena = physics.Arena(arena_shape="game")
    try:
        car = arena.add_car(0)
        # facing +y, rolled onto its side, above the side wall's floor fillet
        car.set_state(physics.CarState(pos=np.array([3920.0, 0.0, 160.0]), rot_mat=_rot(np.pi / 2)))
        touched = []
        for _ in range(120):
            arena.step(1)
            touched.extend(_arena_contacts(arena, car))
        touched = np.array(touched)
        assert len(touched) > 10
        assert np.abs(game_arena_sdf_many(touched)).max() < MESH_TOLERANCE_UU
        assert np.all(touched[:, 2] < GAME_ARENA.floor_fillet) and np.all(touched[:, 0] > 3840.0)  # on the fillet
    finally:
        arena.close()


def test_a_car_sliding_into_the_side_wall_fillet_touches_the_mesh_on_the_distance_field():
    """Sideways, so the hitbox meets the fillet (driven straight at it, a car rides up on its wheels and its
    hitbox never touches, as RocketSim's on the meshes)."""
    arena = physics.Arena(arena_shape="game")
    try:
        car = arena.add_car(0)
        car.set_state(physics.CarState(pos=np.array([3900.0, 0.0, 17.0]), rot_mat=yaw_rot_mat(0.5 * np.pi),
                                       vel=np.array([2000.0, 0.0, 0.0])))
        touched, heights = [], []
        for _ in range(240):
            arena.step(1)
            touched.extend(_arena_contacts(arena, car))
            heights.append(car.get_state().pos[2])
        assert max(heights) > 400.0  # thrown up the fillet
        assert len(touched) > 10  # the hitbox's side meets the fillet's polygon
        assert np.abs(game_arena_sdf_many(np.array(touched))).max() < MESH_TOLERANCE_UU
    finally:
        arena.close()


def test_the_classic_shape_is_untouched():
    """The classic arena's distance is ``arena_geometry``'s (the game shape is a separate module)."""
    assert arena_sdf(2000.0, 5000.0, 100.0)[0] < game_arena_sdf(2000.0, 5000.0, 100.0)[0] - 10.0
    assert arena_sdf(3900.0, 0.0, 100.0)[0] == pytest.approx(-(np.hypot(3900.0 - 3696.0, 100.0 - 400.0) - 400.0))


def test_a_copy_of_a_game_shaped_arena_keeps_its_shape():
    arena = physics.Arena(arena_shape="game")
    try:
        arena.ball.set_state(physics.BallState(pos=np.array([3500.0, 0.0, 250.0]), vel=np.array([1500.0, 0.0, 0.0])))
        twin = copy.deepcopy(arena)
        try:
            assert twin.batch.arena_shape == "game"
            arena.step(60)
            twin.step(60)
            assert np.array_equal(arena.ball.get_state().vel, twin.ball.get_state().vel)
            assert arena.ball.get_state().vel[2] > 100.0  # turned up by the top chord of the side wall's fillet
        finally:
            twin.close()
    finally:
        arena.close()
