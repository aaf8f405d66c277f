"""Boost activity tick by tick against RocketSim: the timer RLGym reads as ``boost_active_time`` (its
``Car.is_boosting`` is that timer > 0) and the tank, on full, small and empty tanks, held, tapped inside the 0.1 s
minimum, and refilled by a pad while the button is held on an empty tank."""
from __future__ import annotations

import math

import pytest

from rocketsim_oracle import CAR_REST_Z, OursAdapter

YAW_PLUS_Y = math.pi / 2
SMALL_PAD_Y = -2816.0  # the small pad on the centre line in blue's half (x = 0)


def _boost_trace(sim_cls, start_y: float, speed: float, tank: float, pressed, ticks: int, z: float = CAR_REST_Z):
    """(boost amount, boost active time) after every tick, the car going +y with throttle held."""
    sim = sim_cls()
    sim.add_car()
    sim.set_car((0.0, start_y, z), vel=(0.0, speed, 0.0), yaw=YAW_PLUS_Y, boost=tank)
    trace = []
    for t in range(ticks):
        sim.set_controls(throttle=1.0, boost=pressed(t))
        sim.step(1)
        state = sim._car.get_state()
        if sim_cls is OursAdapter:
            active_s = sim._car.get_extra_state().boost_active_time_s
        else:
            active_s = state.time_spent_boosting
        trace.append((float(state.boost), float(active_s)))
    sim.close()
    return trace


def _assert_same_trace(theirs, ours, label):
    for t, ((boost_rs, active_rs), (boost_us, active_us)) in enumerate(zip(theirs, ours)):
        assert (active_us > 0.0) == (active_rs > 0.0), (label, t, "is_boosting", active_rs, active_us)
        assert active_us == pytest.approx(active_rs, abs=1e-6), (label, t, "boost_active_time")
        assert boost_us == pytest.approx(boost_rs, abs=1e-4), (label, t, "boost")


PRESSES = {
    "held": lambda t: t >= 2,
    "tap_1_tick": lambda t: t == 2,        # boosting lasts the 0.1 s minimum, if the tank lasts
    "tap_5_ticks": lambda t: 2 <= t < 7,
    "taps": lambda t: t % 20 < 3,          # pressed again as each minimum ends
    "never": lambda t: False,
}


@pytest.mark.parametrize("tank", [0.0, 0.1, 1.0, 3.0, 100.0 / 3.0])
@pytest.mark.parametrize("press", sorted(PRESSES))
@pytest.mark.parametrize("airborne", [False, True])
def test_boost_activity_follows_rocketsim(rocketsim_oracle, tank, press, airborne):
    """0 whenever the tank is empty: pressing on an empty tank never starts it, and running dry stops it and
    clears the timer at once, even inside the 0.1 s minimum."""
    z = 800.0 if airborne else CAR_REST_Z
    theirs = _boost_trace(rocketsim_oracle, -2000.0, 0.0, tank, PRESSES[press], 90, z)
    ours = _boost_trace(OursAdapter, -2000.0, 0.0, tank, PRESSES[press], 90, z)
    _assert_same_trace(theirs, ours, f"{press} tank={tank}")
    if tank == 0.0:
        assert all(active == 0.0 for _, active in ours)


@pytest.mark.parametrize("press", ["held", "taps"])
def test_a_pad_refills_an_empty_tank_while_boost_is_held(rocketsim_oracle, press):
    """Boost held on an empty tank over a small pad: boosting starts the tick after the pickup, as RocketSim's."""
    start_y = SMALL_PAD_Y - 500.0
    theirs = _boost_trace(rocketsim_oracle, start_y, 1400.0, 0.0, PRESSES[press], 120)
    ours = _boost_trace(OursAdapter, start_y, 1400.0, 0.0, PRESSES[press], 120)
    assert max(boost for boost, _ in theirs) > 0.0, "RocketSim's car missed the pad: the scene is off"
    _assert_same_trace(theirs, ours, press)
