"""Every hitbox placed still and level at a spawn height settles as RocketSim's: z = 17 (where RLGym's
``KickoffMutator`` puts every car, below the Plank's, Breakout's and Merc's rest heights, so their wheels start
inside the hard stop), 36 (RocketSim's respawn height) and heights from deep in the suspension to a short drop;
then a jump on the first tick.

RocketSim solves the wheels' hard stop with Bullet's solver time step, which a new arena leaves at Bullet's
default (1/60 s) until its first step: only a fresh arena's first tick pushes half as hard. RLGym's
``RocketSimEngine`` keeps one arena for all its episodes, so the oracle arena here steps once before the car is
placed.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from rocketsim_oracle import OursAdapter

HITBOXES = ("octane", "dominus", "plank", "breakout", "hybrid", "merc")
SPAWN_Z = (14.0, 17.0, 20.0, 25.0, 36.0, 55.0)
GROUNDED_SPAWN_Z = (14.0, 17.0, 20.0)  # every wheel's ray reaches the floor
SETTLE_TICKS = 60


def _settle(sim_cls, preset: str, z: float, jump_on_first_tick: bool, claimed_on_ground: bool) -> np.ndarray:
    """Velocity after each tick of a car placed still at height ``z``, no input (or jump held from tick 0)."""
    sim = sim_cls()
    if sim_cls is not OursAdapter:
        sim.step(1)  # see the module docstring
    sim.add_car(preset)
    sim.set_car((0.0, -2000.0, z), yaw=0.25 * math.pi)
    if claimed_on_ground:  # as RLGym's FixedTeamSizeMutator leaves a new car: on the ground, every wheel touching
        if sim_cls is OursAdapter:
            state = sim._car.get_state()
            state.on_ground, state.wheels_in_contact = True, (True,) * 4
        else:
            state = sim._car.get_state()
            state.is_on_ground, state.wheels_with_contact = True, [True] * 4
        sim._car.set_state(state)
    trace = []
    for _ in range(SETTLE_TICKS):
        sim.set_controls(jump=jump_on_first_tick)
        sim.step(1)
        trace.append(sim.car()["vel"])
    sim.close()
    return np.array(trace)


@pytest.mark.parametrize("z", SPAWN_Z)
@pytest.mark.parametrize("preset", HITBOXES)
def test_spawned_car_settles_as_rocketsim(rocketsim_oracle, preset, z):
    theirs = _settle(rocketsim_oracle, preset, z, False, False)
    ours = _settle(OursAdapter, preset, z, False, False)
    gap = np.abs(theirs - ours).max(axis=1)
    assert gap.max() < 1.0, (f"{preset} at z={z}: velocity {gap.max():.2f} uu/s off RocketSim's on tick "
                             f"{int(gap.argmax())}")


@pytest.mark.parametrize("claimed_on_ground", [False, True])
@pytest.mark.parametrize("z", GROUNDED_SPAWN_Z)
@pytest.mark.parametrize("preset", HITBOXES)
def test_first_tick_jump_from_the_spawn_as_rocketsim(rocketsim_oracle, preset, z, claimed_on_ground):
    theirs = _settle(rocketsim_oracle, preset, z, True, claimed_on_ground)
    ours = _settle(OursAdapter, preset, z, True, claimed_on_ground)
    assert theirs[0, 2] > 250.0, f"{preset} at z={z}: RocketSim's car did not jump; the scene is off"
    assert abs(ours[0, 2] - theirs[0, 2]) < 1.0, (f"{preset} at z={z}: first-tick jump speed {ours[0, 2]:.2f} vs "
                                                  f"RocketSim {theirs[0, 2]:.2f}")
    assert np.abs(theirs - ours).max() < 1.0
