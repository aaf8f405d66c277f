"""Our arena against RocketSim on the game's collision meshes (``rocketsim_mesh_oracle``), where the planes-only
oracle of the other fidelity tests cannot look: the walls below the fillets' tops, the crossbar and the posts. The
classic arena (the default) and the game shape (``arena_shape="game"``)."""
import numpy as np
import pytest

from rocketdrl_ma import physics
from rocketsim_mesh_oracle import TICK_RATE, BallScene, ball_trajectories_on_meshes, mesh_folder_or_skip

SPEED_TOLERANCE = 0.05  # issue 49's target: outgoing speed within 5 % and direction within 2 degrees
ANGLE_TOLERANCE_DEG = 2.0


def _ours(scene: BallScene, arena_shape: str = "classic") -> np.ndarray:
    arena = physics.Arena(tick_rate=TICK_RATE, arena_shape=arena_shape)
    try:
        arena.set_mutator_config(physics.MutatorConfig(gravity_z_uu_s2=scene.gravity_z))
        arena.ball.set_state(physics.BallState(pos=np.array(scene.pos), vel=np.array(scene.vel),
                                               ang_vel=np.array(scene.ang_vel)))
        arena.step(scene.ticks)
        return np.array(arena.ball.get_state().vel, dtype=np.float64)
    finally:
        arena.close()


@pytest.mark.xfail(strict=True, reason="our 400 uu fillet vs the game's ~256 uu: issue 49")
def test_zero_g_ball_off_the_back_wall_below_the_fillet_top():
    """1,500 uu/s straight into the back wall at z = 200, beside the goal: the game's wall is flat there (its ramp
    ends at 256 uu), so the ball comes straight back; ours meets our ramp and is sent up."""
    scene = BallScene(pos=(1500.0, 4500.0, 200.0), vel=(0.0, 1500.0, 0.0), ticks=TICK_RATE, gravity_z=0.0)
    _assert_outgoing_velocity_as_rocketsims(scene, "classic", "back wall at z = 200")


GAME_SHAPE_SCENES = {
    "back wall at z = 200": BallScene(pos=(1500.0, 4500.0, 200.0), vel=(0.0, 1500.0, 0.0), ticks=TICK_RATE,
                                      gravity_z=0.0),
    "side wall at z = 250": BallScene(pos=(3500.0, 0.0, 250.0), vel=(1500.0, 0.0, 0.0), ticks=TICK_RATE,
                                      gravity_z=0.0),
    "crossbar at z = 640": BallScene(pos=(0.0, 4500.0, 640.0), vel=(0.0, 1500.0, 0.0), ticks=TICK_RATE,
                                     gravity_z=0.0),
    "post at x = 900": BallScene(pos=(900.0, 4500.0, 300.0), vel=(0.0, 1500.0, 0.0), ticks=TICK_RATE, gravity_z=0.0),
    "into the goal mouth at z = 150": BallScene(pos=(300.0, 4500.0, 150.0), vel=(0.0, 1500.0, 0.0), ticks=60,
                                                gravity_z=0.0),
    # the same, 6 and 8 uu further on: the first contact tick finds the ball 2 to 4 uu less deep
    "crossbar at z = 640, shallow first contact": BallScene(pos=(128.0, 4506.0, 640.0), vel=(0.0, 1500.0, 0.0),
                                                            ticks=TICK_RATE, gravity_z=0.0),
    "post at x = 900, shallow first contact": BallScene(pos=(900.0, 4508.0, 300.0), vel=(0.0, 1500.0, 0.0),
                                                        ticks=TICK_RATE, gravity_z=0.0),
}


_DEEP_FIRST_CONTACT = ("RocketSim turns the ball further off the frame when its first contact tick finds it deeper; "
                       "ours gives the shallow answer (docs/experiments/arena-mesh.md, the game shape)")
_NOT_YET = {"crossbar at z = 640": _DEEP_FIRST_CONTACT, "post at x = 900": _DEEP_FIRST_CONTACT}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.xfail(strict=True, reason=_NOT_YET[n]))
                                  if n in _NOT_YET else n for n in GAME_SHAPE_SCENES])
def test_zero_g_ball_off_the_game_shaped_arena(name):
    """The game-shaped arena (``arena_shape="game"``) sends a zero-g ball off the walls below the fillets' tops,
    the crossbar and a post as RocketSim on the meshes does."""
    _assert_outgoing_velocity_as_rocketsims(GAME_SHAPE_SCENES[name], "game", name)


def _assert_outgoing_velocity_as_rocketsims(scene: BallScene, arena_shape: str, name: str) -> None:
    """The ball's velocity after the scene, in our arena of ``arena_shape`` and in RocketSim on the meshes: the same
    speed within SPEED_TOLERANCE and direction within ANGLE_TOLERANCE_DEG."""
    folder = mesh_folder_or_skip()
    (theirs,) = ball_trajectories_on_meshes([scene], folder)
    game, ours = theirs.vel[-1], _ours(scene, arena_shape)
    print(f"{name}: RocketSim on the meshes {np.round(game, 1)}, ours {np.round(ours, 1)}")
    cos = float(np.dot(game, ours) / (np.linalg.norm(game) * np.linalg.norm(ours)))
    angle = float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    speed_error = abs(np.linalg.norm(ours) / np.linalg.norm(game) - 1.0)
    assert speed_error < SPEED_TOLERANCE and angle < ANGLE_TOLERANCE_DEG, (
        f"RocketSim {np.round(game, 1)} vs ours {np.round(ours, 1)}: speed off {100 * speed_error:.1f} %, "
        f"direction off {angle:.1f} deg")
