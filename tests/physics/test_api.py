"""The single-arena API: construction, state round trips, kickoff, validation errors."""
import math

import numpy as np
import pytest

from rocketdrl_ma.physics import Arena, BallState, CarControls, CarState, PRESETS, yaw_rot_mat
from rocketdrl_ma.physics import constants as C


@pytest.fixture
def arena():
    a = Arena(tick_rate=120, seed=0)
    yield a
    a.close()


def test_car_state_round_trip(arena):
    car = arena.add_car(team=0, preset="octane")
    rot = yaw_rot_mat(0.7)
    state = CarState(pos=np.array([100.0, -200.0, 500.0]), vel=np.array([300.0, 20.0, -5.0]),
                     ang_vel=np.array([0.1, -0.2, 0.3]), rot_mat=rot, boost=55.0, has_jumped=True)
    car.set_state(state)
    got = car.get_state()
    np.testing.assert_allclose(got.pos, state.pos, atol=1e-6)
    np.testing.assert_allclose(got.vel, state.vel, atol=1e-6)
    np.testing.assert_allclose(got.ang_vel, state.ang_vel, atol=1e-9)
    np.testing.assert_allclose(got.rot_mat, rot, atol=1e-9)
    assert got.boost == pytest.approx(55.0)
    assert got.has_jumped


def test_rot_mat_columns_follow_the_game_convention():
    rot = yaw_rot_mat(math.pi / 2)
    np.testing.assert_allclose(rot[:, 0], [0, 1, 0], atol=1e-12)  # forward
    np.testing.assert_allclose(rot[:, 1], [-1, 0, 0], atol=1e-12)  # right
    np.testing.assert_allclose(np.cross(rot[:, 0], rot[:, 1]), rot[:, 2], atol=1e-12)


def test_car_settles_on_its_wheels(arena):
    car = arena.add_car(team=0)
    car.set_state(CarState(pos=np.array([0.0, 0.0, 60.0])))
    arena.step(240)
    s = car.get_state()
    assert s.on_ground and all(s.wheels_in_contact)
    assert 12.0 < s.pos[2] < 22.0  # RocketSim: Octane rests with its centre of mass at 17.03
    assert np.linalg.norm(s.vel) < 1.0


def test_every_preset_drives(arena):
    for name in PRESETS:
        car = arena.add_car(team=0, preset=name)
        car.set_state(CarState(pos=np.array([0.0, 0.0, 30.0])))
        car.set_controls(CarControls(throttle=1.0))
        arena.step(120)
        s = car.get_state()
        assert s.on_ground, name
        assert 800.0 < s.vel[0] < 1300.0, (name, s.vel)
        arena.remove_car(car)
    assert arena.cars == []


def test_kickoff_spots_are_mirrored_and_standard(arena):
    blue = [arena.add_car(team=0) for _ in range(4)]
    orange = [arena.add_car(team=1) for _ in range(4)]
    arena.reset_kickoff(seed=3)
    spots = {(x, y) for x, y, _ in C.KICKOFF_SPOTS_BLUE}
    for b, o in zip(blue, orange):
        sb, so = b.get_state(), o.get_state()
        assert (sb.pos[0], sb.pos[1]) in spots
        np.testing.assert_allclose(so.pos[:2], -sb.pos[:2])
        np.testing.assert_allclose(so.rot_mat[:2, 0], -sb.rot_mat[:2, 0], atol=1e-9)
        assert sb.boost == pytest.approx(100 / 3)
    assert len({tuple(c.get_state().pos[:2]) for c in blue}) == 4
    ball = arena.ball.get_state()
    np.testing.assert_allclose(ball.pos, [0, 0, C.BALL_REST_Z])


def test_kickoff_ball_hangs_until_touched(arena):
    arena.add_car(team=0)
    arena.reset_kickoff(seed=0)
    arena.step(120)
    ball = arena.ball.get_state()
    np.testing.assert_allclose(ball.pos, [0, 0, C.BALL_REST_Z], atol=1e-9)
    assert not ball.vel.any()


def test_kickoff_is_a_function_of_the_seed(arena):
    cars = [arena.add_car(team=0) for _ in range(2)]
    arena.reset_kickoff(seed=11)
    first = [c.get_state().pos.copy() for c in cars]
    arena.reset_kickoff(seed=11)
    assert all(np.array_equal(a, c.get_state().pos) for a, c in zip(first, cars))


@pytest.mark.parametrize("field,value,message", [
    ("pos", [0.0, 0.0, float("nan")], "pos"),
    ("pos", [0.0, 0.0], "pos"),
    ("vel", [np.inf, 0.0, 0.0], "vel"),
    ("boost", 150.0, "boost"),
    ("rot_mat", np.eye(3) * 2.0, "rot_mat"),
])
def test_car_state_rejects_bad_fields(field, value, message):
    with pytest.raises(ValueError, match=message):
        CarState(**{field: value})


def test_set_state_rejects_positions_outside_the_arena(arena):
    car = arena.add_car(team=0)
    with pytest.raises(ValueError, match="pos"):
        car.set_state(CarState(pos=np.array([5000.0, 0.0, 100.0])))
    with pytest.raises(ValueError, match="pos"):
        arena.ball.set_state(BallState(pos=np.array([0.0, 0.0, -300.0])))


@pytest.mark.parametrize("kwargs,name", [({"throttle": 2.0}, "throttle"), ({"steer": float("nan")}, "steer"),
                                         ({"roll": -1.5}, "roll")])
def test_controls_reject_out_of_range(kwargs, name):
    with pytest.raises(ValueError, match=name):
        CarControls(**kwargs)


def test_unknown_preset_names_the_allowed_ones(arena):
    with pytest.raises(ValueError, match="octane"):
        arena.add_car(team=0, preset="batmobile")
    with pytest.raises(ValueError, match="team"):
        arena.add_car(team=2)


def test_boost_pad_pickup_and_respawn(arena):
    car = arena.add_car(team=0)
    big = int(np.flatnonzero(C.BOOST_PAD_IS_BIG)[0])
    px, py, _ = C.BOOST_PAD_POSITIONS[big]
    car.set_state(CarState(pos=np.array([px, py, C.CAR_SPAWN_REST_Z]), boost=10.0))
    arena.step(1)
    assert car.get_state().boost == pytest.approx(100.0)
    assert arena.boost_pad_timers()[big] == pytest.approx(C.BOOST_PAD_BIG_COOLDOWN, abs=1e-9)
    arena.step(int(C.BOOST_PAD_BIG_COOLDOWN * 120) + 1)
    assert arena.boost_pad_timers()[big] == 0.0


def test_boost_pads_are_the_standard_34():
    assert len(C.BOOST_PAD_POSITIONS) == 34 and C.BOOST_PAD_IS_BIG.sum() == 6
    xy = {(float(x), float(y)) for x, y, _ in C.BOOST_PAD_POSITIONS}
    assert len(xy) == 34 and all((-x, -y) in xy and (-x, y) in xy for x, y in xy)  # the field's symmetry
    big = C.BOOST_PAD_POSITIONS[C.BOOST_PAD_IS_BIG]
    assert sorted(map(tuple, np.abs(big[:, :2]).tolist())) == [(3072.0, 4096.0)] * 4 + [(3584.0, 0.0)] * 2
    assert set(C.BOOST_PAD_POSITIONS[:, 2]) == {C.BOOST_PAD_SMALL_Z, C.BOOST_PAD_BIG_Z}
