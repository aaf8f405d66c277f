"""The ``.cmf`` reader against RocketSim (the same bytes, the same placement in the arena), and the signed distance
from our analytic arena to the game's meshes: every surface family reported, and where both already agree."""
import math
import struct

import numpy as np
import pytest

from arena_mesh_distance import FAMILIES, distance_table, format_table, sample_game_surface
from arena_mesh_profile import fit_circle, measure_game_arena
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.arena_geometry import arena_sdf_many
from rocketdrl_ma.physics.mesh_file import (BT_TO_UU, find_soccar_meshes, installed_rlgym_mesh_folder, read_cmf,
                                            read_collision_mesh, read_soccar_arena)
from rocketsim_mesh_oracle import BallScene, ball_trajectories_on_meshes

# RocketSim's MeshHashSet for soccar (src/RocketSim.cpp): it warns when a loaded mesh matches none of these
ROCKETSIM_SOCCAR_HASHES = {0xA160BAF9, 0x2811EEE8, 0xB81AC8B9, 0x760358D3, 0x73AE4940, 0x918F4A4E, 0x1F8EE550,
                           0x255BA8C1, 0x14B84668, 0xEC759EBF, 0x94FB0D5C, 0xDEA07102, 0xBD4FBEA8, 0x39A47F63,
                           0x3D79D25D, 0xD84C7A68}
SOCCAR_MESH_COUNT = 16
N_SAMPLE = 20_000  # mesh points of the distance test (the benchmark samples 100,000)


@pytest.fixture(scope="module")
def mesh_folder():
    folder = installed_rlgym_mesh_folder()
    if folder is None:
        pytest.skip("rlgym-rocket-league's collision meshes are not installed (pip install --no-deps "
                    "rlgym-rocket-league==2.0.1)")
    return folder


@pytest.fixture(scope="module")
def table(mesh_folder):
    sample = sample_game_surface(mesh_folder, N_SAMPLE, seed=0)
    return sample, arena_sdf_many(sample.points), distance_table(sample)


def _rocketsim_hash(vertices_bt: np.ndarray, triangles: np.ndarray) -> int:
    """CollisionMeshFile::UpdateHash: each used coordinate cast to uint32 (truncated, wrapped), mixed in."""
    mask = 0xFFFFFFFF
    h = (len(vertices_bt) + len(triangles) * len(vertices_bt)) & mask
    for value in vertices_bt[triangles].reshape(-1).tolist():
        c = int(math.trunc(value)) & mask
        for _ in range(2):
            c = (((c >> 16) ^ c) * 0x45D9F3B) & mask
        c = ((c >> 16) ^ c) & mask
        h = (h ^ ((c + 0x9E3779B9 + ((h << 6) & mask) + (h >> 2)) & mask)) & mask
    return h


# ================================================================= the reader
def test_reader_reads_the_bytes_rocketsim_reads(mesh_folder):
    files = find_soccar_meshes(mesh_folder)
    assert len(files) == SOCCAR_MESH_COUNT
    assert {_rocketsim_hash(*read_cmf(p)) for p in files} == ROCKETSIM_SOCCAR_HASHES


def test_vertices_are_in_uu_in_our_frame(mesh_folder):
    vertices, triangles, owner = read_soccar_arena(mesh_folder)
    assert vertices.dtype == np.float32 and triangles.dtype == np.int32 and len(owner) == len(triangles)
    # the field's walls, the back of the nets and the ceiling; the meshes run a few uu past RocketSim's planes
    assert C.ARENA_EXTENT_X < np.abs(vertices[:, 0]).max() < C.ARENA_EXTENT_X + 15.0
    assert np.abs(vertices[:, 1]).max() == pytest.approx(C.ARENA_EXTENT_Y + C.GOAL_DEPTH, abs=0.1)
    assert -15.0 < vertices[:, 2].min() < 0.0 and C.ARENA_HEIGHT < vertices[:, 2].max() < C.ARENA_HEIGHT + 30.0
    # the flat up-facing pieces (the nets' floors) start on the floor
    a, b, c = (vertices[triangles[:, k]].astype(np.float64) for k in range(3))
    normal = np.cross(b - a, c - a)
    up = normal[:, 2] / np.linalg.norm(normal, axis=1) > 0.999
    assert up.any() and np.concatenate([a[up], b[up], c[up]])[:, 2].min() == pytest.approx(0.0, abs=0.01)


@pytest.mark.parametrize("mirror", [(-1.0, 1.0, 1.0), (1.0, -1.0, 1.0)], ids=["x", "y"])
def test_meshes_are_mirror_symmetric(mesh_folder, mirror):
    vertices = read_soccar_arena(mesh_folder)[0].astype(np.float64)
    mirrored = vertices * np.array(mirror)
    nearest = np.array([np.linalg.norm(vertices - m, axis=1).min() for m in mirrored])
    assert nearest.max() < 0.05


def test_rocketsim_collides_where_the_reader_puts_the_back_wall(mesh_folder):
    """A slow zero-g ball into the back wall above the fillet in RocketSim-with-meshes turns round one ball radius
    in front of the wall our reader finds there."""
    pytest.importorskip("RocketSim", reason="the rocketsim package (test extra) is the physics oracle")
    x, z = 1800.0, 1000.0
    vertices, triangles, _ = read_soccar_arena(mesh_folder)
    wall_y = _mesh_y_along(vertices.astype(np.float64), triangles, x, z)
    (run,) = ball_trajectories_on_meshes([BallScene((x, 4800.0, z), (0.0, 200.0, 0.0), 240, gravity_z=0.0)],
                                         str(mesh_folder))
    assert run.vel[-1, 1] < 0.0, "the ball must have bounced"
    assert run.pos[:, 1].max() == pytest.approx(wall_y - C.BALL_RADIUS, abs=2.0)


def _mesh_y_along(vertices: np.ndarray, triangles: np.ndarray, x: float, z: float) -> float:
    """The largest y where the line (x, *, z) meets a mesh triangle (barycentric test in the x-z plane)."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    e1, e2, p = b - a, c - a, np.array([x, z]) - a[:, [0, 2]]
    det = e1[:, 0] * e2[:, 2] - e1[:, 2] * e2[:, 0]
    ok = np.abs(det) > 1e-9
    u = np.where(ok, (p[:, 0] * e2[:, 2] - p[:, 1] * e2[:, 0]) / np.where(ok, det, 1.0), -1.0)
    v = np.where(ok, (e1[:, 0] * p[:, 1] - e1[:, 2] * p[:, 0]) / np.where(ok, det, 1.0), -1.0)
    hit = (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0)
    assert hit.any()
    return float((a[:, 1] + u * e1[:, 1] + v * e2[:, 1])[hit].max())


def test_read_collision_mesh_scales_bullet_units_to_uu(tmp_path):
    path = _write_cmf(tmp_path / "one.cmf", [(0, 1, 2)], [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, -2.0, 0.5)])
    vertices, triangles = read_collision_mesh(path)
    np.testing.assert_array_equal(vertices, np.array([[0, 0, 0], [1, 0, 0], [0, -2, 0.5]]) * BT_TO_UU)
    np.testing.assert_array_equal(triangles, [[0, 1, 2]])


@pytest.mark.parametrize("tris,verts,extra,message", [
    ([(0, 1, 2)], [(0.0, 0.0, 0.0)] * 3, b"\0", "need 56 bytes, the file has 57"),
    ([(0, 1, 3)], [(0.0, 0.0, 0.0)] * 3, b"", "indices must be in 0..2"),
    ([], [(0.0, 0.0, 0.0)] * 3, b"", "triangle count 0 and vertex count 3 must be in"),
])
def test_read_cmf_rejects_broken_files(tmp_path, tris, verts, extra, message):
    path = _write_cmf(tmp_path / "bad.cmf", tris, verts, extra)
    with pytest.raises(ValueError, match=message):
        read_cmf(path)


def test_find_soccar_meshes_takes_either_folder_in_natural_order(tmp_path):
    soccar = tmp_path / "soccar"
    soccar.mkdir()
    for name in ("mesh_10.cmf", "mesh_2.cmf", "notes.txt"):
        (soccar / name).write_bytes(b"")
    assert [p.name for p in find_soccar_meshes(tmp_path)] == ["mesh_2.cmf", "mesh_10.cmf"]
    assert find_soccar_meshes(soccar) == find_soccar_meshes(tmp_path)
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="holds no"):
        find_soccar_meshes(tmp_path / "empty")
    with pytest.raises(ValueError, match="must be a directory"):
        find_soccar_meshes(tmp_path / "missing")


def _write_cmf(path, tris, verts, extra=b""):
    with open(path, "wb") as f:
        f.write(struct.pack("<ii", len(tris), len(verts)))
        for t in tris:
            f.write(struct.pack("<iii", *t))
        for v in verts:
            f.write(struct.pack("<fff", *v))
        f.write(extra)
    return path


# ================================================================= our arena against the meshes
def test_distance_table_reports_every_family_and_the_worst(table):
    _, signed, rows = table
    by_name = {r.family: r for r in rows}
    assert set(FAMILIES) | {"all"} == set(by_name)
    worst = max((r for r in rows if r.family != "all"), key=lambda r: r.abs_max)
    assert by_name["all"].abs_max == worst.abs_max == pytest.approx(float(np.abs(signed).max()))
    text = format_table(rows)
    assert all(f"| {name} |" in text for name in FAMILIES) and f"{worst.abs_max:.2f}" in text


def test_floor_and_walls_above_the_fillets_agree_today(table):
    """The floor away from the walls and goals, and the flat side and back walls above 400 uu (away from the
    corners and the goal frame), are where our arena already matches the game's (to float precision)."""
    sample, signed, rows = table
    by_name = {r.family: r for r in rows}
    x, y = np.abs(sample.points[:, 0]), np.abs(sample.points[:, 1])
    open_floor = (sample.family == FAMILIES.index("floor")) & (x < 3000.0) & (y < 4000.0)
    assert open_floor.sum() > 1000 and np.abs(signed[open_floor]).max() < 0.01
    assert by_name["floor"].abs_percentiles[1] < 0.5  # p90: only the ramps by the posts differ
    walls = by_name["walls above 400 uu"]
    assert walls.points > 3000 and walls.abs_max < 0.01
    side_walls = (sample.family == FAMILIES.index("walls above 400 uu")) & (x == C.ARENA_EXTENT_X)
    back_walls = (sample.family == FAMILIES.index("walls above 400 uu")) & (y > 5000.0)
    assert side_walls.sum() > 1000 and back_walls.sum() > 1000  # both kinds of wall are in the family


# ================================================================= the game's dimensions
def test_fit_circle_finds_a_circle_and_needs_three_points():
    angles = np.linspace(0.1, 1.4, 7)
    u, v, radius, residual = fit_circle(np.column_stack([3.0 + 256.0 * np.cos(angles), -2.0 + 256.0 * np.sin(angles)]))
    assert (u, v, radius) == pytest.approx((3.0, -2.0, 256.0), abs=1e-6) and residual < 1e-6
    with pytest.raises(ValueError, match="points_2d"):
        fit_circle(np.zeros((2, 2)))


def test_the_game_arena_measures_as_the_game(mesh_folder):
    """The measuring tool on the meshes: the fillet radii, corner roundings and goal size of Rocket League's soccar
    arena (256 / 512 uu side and corner fillets, 160 at the back walls, a 896 x 640 goal 880 deep)."""
    game = {m.name: m for m in measure_game_arena(mesh_folder)}
    expected = {"side wall to floor fillet": 256.0, "corner wall to floor fillet": 256.0,
                "back wall to floor fillet": 160.0, "side wall to ceiling fillet": 512.0,
                "back wall to ceiling fillet": 512.0, "corner wall to ceiling fillet": 512.0,
                "goal half width (net side wall)": 896.0, "goal height (roof behind the crossbar)": 640.0,
                "back of the net": C.ARENA_EXTENT_Y + C.GOAL_DEPTH}
    for name, value in expected.items():
        assert game[name].game == pytest.approx(value, abs=3.0), name
        assert game[name].fit_residual < 2.0, name


def test_the_game_shape_is_within_2_uu_of_the_meshes(table):
    """The game shape (``arena_shape="game"``) against the meshes: issue 49's target, p99.9 <= 2 uu and max <= 5 uu
    overall and on every surface family, but for the floor fillets' p99.9 on this test's smaller sample (the seam
    where the corner's mesh overlaps the back wall's; docs/experiments/arena-mesh.md, the game shape)."""
    sample, _, _ = table
    rows = {r.family: r for r in distance_table(sample, "game")}
    for family in (*FAMILIES, "all"):
        p999 = 2.5 if family == "floor-wall fillet" else 2.0
        assert rows[family].abs_percentiles[3] <= p999 and rows[family].abs_max <= 5.0, family
