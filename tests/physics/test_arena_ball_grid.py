"""A zero-g ball off every surface family of the game-shaped arena (``arena_shape="game"``) against RocketSim on the
game's collision meshes (``arena_ball_scenes``): fillets, the walls above the fillets' tops and high up, a corner
wall, a post, the crossbar and the net's back, at 500-3,000 uu/s and 15-75 degrees of incidence, each cell at 8
sub-tick phases. Issue 49's target: the outgoing speed within 5 % and the direction within 2 degrees on every cell
at every phase."""
import numpy as np
import pytest

import arena_ball_scenes as grid
from bullet_triangle_contacts import TriangleContacts, manifold_normals, velocity_after_contact
from rocketsim_mesh_oracle import ball_trajectories_on_meshes, mesh_folder_or_skip

pytestmark = pytest.mark.slow  # one RocketSim subprocess for the 720 scenes, then the same in ours

SPEED_TOLERANCE = 0.05
ANGLE_TOLERANCE_DEG = 2.0
SCENES = grid.ball_grid()
CELLS = list(dict.fromkeys(grid.cell_of(s.key) for s in SCENES))


@pytest.fixture(scope="module")
def meshes():
    """The collision mesh folder RocketSim loads (skips without RocketSim or the meshes)."""
    folder = mesh_folder_or_skip()
    return folder


@pytest.fixture(scope="module")
def rocketsim(meshes):
    """RocketSim's trajectory of every scene on the meshes."""
    return ball_trajectories_on_meshes([s.scene for s in SCENES], meshes)


@pytest.fixture(scope="module")
def outgoing(rocketsim):
    """Per scene key: (RocketSim's outgoing velocity, ours)."""
    return grid.outgoing_pairs(SCENES, [t.vel for t in rocketsim], grid.run_ours(SCENES))


# Measured worst error per missing cell (speed %, degrees), over its 8 phases (docs/experiments/arena-mesh.md, the
# ball grid). The fillets' and the net's misses are Bullet counting one contact per mesh triangle and keeping four
# per mesh (test_rocketsim_counts_one_contact_per_triangle below): how the game's meshes split their quads decides
# them, which an analytic surface does not know; the crossbar's are deep first contacts at its convex edges.
MISSES = {  # cell: (speed %, degrees)
    "floor_fillet_side-500-15": (0.2, 3.9),
    "floor_fillet_side-500-45": (0.0, 5.2),
    "floor_fillet_side-1500-45": (0.0, 2.6),
    "floor_fillet_back-500-15": (0.2, 5.6),
    "floor_fillet_back-500-45": (0.1, 9.4),
    "floor_fillet_back-1500-15": (0.7, 10.6),
    "floor_fillet_back-1500-45": (0.0, 3.9),
    "floor_fillet_back-3000-15": (0.8, 16.1),
    "floor_fillet_back-3000-45": (0.3, 11.4),
    "ceiling_fillet_side-3000-15": (0.3, 7.7),
    "ceiling_fillet_side-3000-45": (0.0, 2.6),
    "crossbar-1500-15": (1.6, 15.4),
    "crossbar-3000-15": (11.8, 16.0),
    "crossbar-3000-45": (2.0, 19.1),
    "goal_back-1500-15": (0.9, 6.6),
    "goal_back-1500-45": (0.1, 4.2),
    "goal_back-3000-15": (0.9, 6.6),
    "goal_back-3000-45": (0.1, 4.2),
}


def _param(cell: str):
    if cell not in MISSES:
        return cell
    speed, angle = MISSES[cell]
    return pytest.param(cell, marks=pytest.mark.xfail(
        strict=True, reason=f"up to {speed} % in speed and {angle} degrees off RocketSim on the meshes"))


@pytest.mark.parametrize("cell", [_param(c) for c in CELLS])
def test_ball_leaves_the_surface_as_rocketsim(outgoing, cell):
    keys = [s.key for s in SCENES if grid.cell_of(s.key) == cell]
    assert len(keys) == grid.PHASES
    for key in keys:
        theirs, ours = outgoing[key]
        speed_error, angle = grid.speed_and_angle_error(ours, theirs)
        assert abs(speed_error) <= SPEED_TOLERANCE and angle <= ANGLE_TOLERANCE_DEG, (
            f"{key}: ours {np.round(ours, 1).tolist()} vs RocketSim {np.round(theirs, 1).tolist()}: "
            f"speed {100 * speed_error:+.1f} %, {angle:.2f} deg apart")


def test_the_grid_is_the_issue_s():
    """Every surface family the issue names, 500-3,000 uu/s, 15-75 degrees, at least 8 phases."""
    families = set(grid.FAMILIES)
    for needed in ("floor_fillet_side", "wall_low_side", "wall_high_side", "corner", "post", "crossbar",
                   "goal_back"):
        assert needed in families
    assert min(grid.SPEEDS_UU_S) == 500.0 and max(grid.SPEEDS_UU_S) == 3000.0
    assert min(grid.INCIDENCES_DEG) == 15.0 and max(grid.INCIDENCES_DEG) == 75.0
    assert grid.PHASES >= 8


# Families whose mesh edges are all flat or concave (no convex edge to clamp a normal at), and the grid's misses
# among them that the triangles explain.
TRIANGLE_FAMILIES = ("floor_fillet_side", "ceiling_fillet_side", "wall_low_side", "wall_low_back", "wall_high_side",
                     "corner", "goal_back")
CONTACT_TICK_TOLERANCE_UU_S = 0.5


def test_rocketsim_counts_one_contact_per_triangle(meshes, rocketsim):
    """RocketSim's velocity after the first contact tick is the merged contact of one contact per mesh triangle
    within reach, four kept per mesh (``bullet_triangle_contacts``), in every scene of these families whose
    manifolds kept all their points (the rest depend on the meshes' tree order); one contact per face, as an
    analytic surface gives, misses the grid's missing cells among them."""
    model = TriangleContacts(meshes)
    drag = (1.0 - 0.03) ** (1.0 / grid.TICK_RATE)
    checked, face_misses = 0, set()
    for scene, theirs in zip(SCENES, rocketsim):
        if scene.family not in TRIANGLE_FAMILIES:
            continue
        tick = grid.first_contact_tick(theirs.vel, np.array(scene.scene.vel))
        contacts = model.contacts(theirs.pos[tick - 1])
        before = theirs.vel[tick - 1] * drag, theirs.ang_vel[tick - 1]
        normals, dropped = manifold_normals(contacts)
        if not dropped:
            checked += 1
            error = np.linalg.norm(velocity_after_contact(normals, *before) - theirs.vel[tick])
            assert error <= CONTACT_TICK_TOLERANCE_UU_S, f"{scene.key}: {error:.2f} uu/s off RocketSim's contact tick"
        per_face, _ = manifold_normals(contacts, per_face=True)
        if np.linalg.norm(velocity_after_contact(per_face, *before) - theirs.vel[tick]) > 5.0:
            face_misses.add(grid.cell_of(scene.key))
    assert checked >= 450
    assert {c for c in MISSES if c.rsplit("-", 2)[0] in TRIANGLE_FAMILIES} <= face_misses
