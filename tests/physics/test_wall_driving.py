"""Cars driven from the floor over the fillets onto the walls of the game-shaped arena (``arena_shape="game"``),
against RocketSim on the game's collision meshes: 1 s of throttle (and boost) from 500 to 2,300 uu/s onto the side
walls and a back wall; issue 49's target is the car within 10 uu of RocketSim's on every tick."""
import math

import numpy as np
import pytest

from rocketdrl_ma import physics
from rocketsim_mesh_oracle import TICK_RATE, CarScene, car_trajectories_on_meshes, mesh_folder_or_skip

pytestmark = pytest.mark.slow  # one RocketSim subprocess for the grid, then 1 s per scene in ours

POSITION_TOLERANCE_UU = 10.0
SPEEDS = (500.0, 800.0, 1400.0, 2200.0)
WALLS = {  # start (x, y) and heading: the fillet begins about 340 uu (side walls) or 460 uu (back wall) ahead
    "side_wall_+x": ((3500.0, 0.0), 0.0),
    "side_wall_-x": ((-3500.0, 500.0), math.pi),
    "back_wall_+y": ((-2500.0, 4500.0), math.pi / 2),
    "back_wall_-y": ((2450.0, -4500.0), -math.pi / 2),   # where the vertical rounding begins
    "back_wall_+y_inner": ((1700.0, 4500.0), math.pi / 2),
}


def _scene(wall: str, speed: float, boost: bool) -> CarScene:
    (x, y), yaw = WALLS[wall]
    return CarScene(pos=(x, y, 17.03), vel=(speed * math.cos(yaw), speed * math.sin(yaw), 0.0), ticks=TICK_RATE,
                    yaw=yaw, controls=(("throttle", 1.0), ("boost", boost)))


SCENES = {f"{wall}-{speed:g}-{'boost' if boost else 'throttle'}": _scene(wall, speed, boost)
          for wall in WALLS for speed in SPEEDS for boost in (False, True)}


def _ours(scene: CarScene) -> np.ndarray:
    arena = physics.Arena(tick_rate=TICK_RATE, arena_shape="game")
    try:
        arena.ball.set_state(physics.BallState(pos=np.array([0.0, 3000.0, 93.15])))
        car = arena.add_car(0, preset=scene.preset)
        car.set_state(physics.CarState(pos=np.array(scene.pos), vel=np.array(scene.vel),
                                       rot_mat=physics.state.yaw_rot_mat(scene.yaw), boost=scene.boost))
        car.set_controls(physics.CarControls(**dict(scene.controls)))
        path = []
        for _ in range(scene.ticks):
            arena.step(1)
            path.append(car.get_state().pos)
        return np.array(path)
    finally:
        arena.close()


@pytest.fixture(scope="module")
def rocketsim_paths():
    folder = mesh_folder_or_skip()
    return dict(zip(SCENES, (t.pos for t in car_trajectories_on_meshes(list(SCENES.values()), folder))))


# Measured worst gap (uu) of the cells that miss, all with boost or at 2,200 uu/s: the hitbox meets the fillet or
# the wall for a few ticks (RocketSim's box on the game's triangles, ours on our own mesh's)
# (docs/experiments/arena-mesh.md).
MISSES_UU = {"side_wall_+x-2200-boost": 16.5, "side_wall_-x-2200-boost": 12.3, "back_wall_+y-800-boost": 11.2,
             "back_wall_+y-2200-boost": 11.7, "back_wall_+y_inner-2200-throttle": 15.9,
             "back_wall_+y_inner-2200-boost": 10.3}


def _param(name: str):
    if name not in MISSES_UU:
        return name
    return pytest.param(name, marks=pytest.mark.xfail(
        strict=True, reason=f"up to {MISSES_UU[name]} uu from RocketSim's car within the second"))


@pytest.mark.parametrize("name", [_param(n) for n in SCENES])
def test_car_drives_up_the_wall_as_rocketsim(rocketsim_paths, name):
    theirs, ours = rocketsim_paths[name], _ours(SCENES[name])
    assert theirs[:, 2].max() > 60.0, f"{name}: RocketSim's car never reached the fillet; the scene is off"
    gap = np.linalg.norm(theirs - ours, axis=1)
    print(f"{name}: worst {gap.max():.1f} uu on tick {int(gap.argmax())}, after 1 s {gap[-1]:.1f} uu")
    assert gap.max() < POSITION_TOLERANCE_UU, (f"{name}: {gap.max():.1f} uu from RocketSim's car on tick "
                                               f"{int(gap.argmax())} (RocketSim {np.round(theirs[-1], 1)}, ours "
                                               f"{np.round(ours[-1], 1)} after 1 s)")
