"""Game mechanics beyond the fidelity figures: boost, supersonic, jumps, flips, demos, walls, goals."""
import numpy as np
import pytest

from rocketdrl_ma.physics import Arena, BallState, CarBumped, CarControls, CarDemolished, CarState, yaw_rot_mat
from rocketdrl_ma.physics import constants as C

AWAY_BALL = BallState(pos=np.array([2500.0, 3000.0, C.BALL_REST_Z]))


@pytest.fixture
def arena():
    a = Arena(seed=0)
    a.ball.set_state(AWAY_BALL)
    yield a
    a.close()


def _grounded(x=0.0, y=-2000.0, yaw=np.pi / 2, **kw):
    return CarState(pos=np.array([x, y, 17.03]), rot_mat=yaw_rot_mat(yaw), on_ground=True, **kw)


def test_boost_lasts_three_seconds_and_makes_the_car_supersonic(arena):
    car = arena.add_car(team=0)
    car.set_state(_grounded(x=-1500.0, y=-4000.0, boost=100.0))
    car.set_controls(CarControls(throttle=1.0, boost=True))
    arena.step(240)
    s = car.get_state()
    assert s.is_supersonic and np.linalg.norm(s.vel) == pytest.approx(C.CAR_MAX_SPEED, abs=1.0)
    assert s.boost == pytest.approx(100.0 - 240 / 120 * C.BOOST_USED_PER_SECOND, abs=0.5)
    arena.step(121)
    assert car.get_state().boost == 0.0


def test_supersonic_is_lost_below_2100_when_coasting(arena):
    car = arena.add_car(team=0)
    car.set_state(_grounded(y=-4000.0, vel=np.array([0.0, 2300.0, 0.0]), is_supersonic=True))
    arena.step(1)
    assert car.get_state().is_supersonic
    arena.step(60)  # coasting at -525 uu/s^2 takes the car below 2100 within 0.4 s
    s = car.get_state()
    assert np.linalg.norm(s.vel) < C.SUPERSONIC_MAINTAIN_MIN_SPEED and not s.is_supersonic


def test_jump_height_depends_on_hold(arena):
    car = arena.add_car(team=0)
    apexes = []
    for hold_ticks in (1, 6, 24):
        car.set_state(_grounded())
        car.set_controls(CarControls())
        arena.step(30)
        car.set_controls(CarControls(jump=True))
        arena.step(hold_ticks)
        car.set_controls(CarControls())
        heights = []
        for _ in range(150):
            arena.step(1)
            heights.append(car.get_state().pos[2])
        apexes.append(max(heights))
    assert apexes[0] < apexes[1] < apexes[2]
    assert apexes[0] == pytest.approx(89.15, rel=0.1)  # RocketSim tap jump
    assert apexes[2] == pytest.approx(231.8, rel=0.05)


def test_double_jump_window_closes_after_1_25_s(arena):
    car = arena.add_car(team=0)
    for wait_s, expect_double in ((1.0, True), (1.4, False)):
        car.set_state(_grounded())
        car.set_controls(CarControls())
        arena.step(30)
        car.set_controls(CarControls(jump=True))
        arena.step(24)
        car.set_controls(CarControls())
        arena.step(int(wait_s * 120))
        vz_before = car.get_state().vel[2]
        car.set_controls(CarControls(jump=True))
        arena.step(1)
        s = car.get_state()
        assert s.has_double_jumped == expect_double
        assert (s.vel[2] - vz_before > 200.0) == expect_double


def test_flip_spins_the_car_and_locks_pitch(arena):
    car = arena.add_car(team=0)
    car.set_state(CarState(pos=np.array([0.0, -2000.0, 600.0]), rot_mat=yaw_rot_mat(np.pi / 2), has_jumped=True))
    car.set_controls(CarControls(pitch=-1.0))
    arena.step(1)
    car.set_controls(CarControls(pitch=-1.0, jump=True))
    arena.step(1)
    s = car.get_state()
    assert s.has_flipped and s.is_flipping
    assert s.vel[1] == pytest.approx(500.0, abs=1.0)  # forward is +y at this yaw
    arena.step(6)
    s = car.get_state()
    pitch_rate = s.rot_mat[:, 1] @ s.ang_vel  # about the car's right axis: nose going down
    assert pitch_rate == pytest.approx(C.CAR_MAX_ANG_SPEED, abs=0.1)
    assert not car.get_state().has_double_jumped


def test_supersonic_car_demolishes_an_opponent_and_it_respawns(arena):
    attacker, victim = arena.add_car(team=0), arena.add_car(team=1)
    attacker.set_state(_grounded(y=-1500.0, vel=np.array([0.0, 2290.0, 0.0]), is_supersonic=True, boost=100.0))
    victim.set_state(_grounded(y=-1200.0, yaw=0.0))
    attacker.set_controls(CarControls(throttle=1.0, boost=True))
    for _ in range(30):
        arena.step(1)
        if victim.get_state().is_demoed:
            break
    assert victim.get_state().is_demoed
    demos = [e for e in arena.drain_events() if isinstance(e, CarDemolished)]
    assert [(e.attacker_id, e.victim_id) for e in demos] == [(attacker.id, victim.id)]
    arena.step(int(C.DEMO_RESPAWN_TIME * 120) + 2)
    s = victim.get_state()
    assert not s.is_demoed
    assert abs(s.pos[1]) == pytest.approx(4608.0, abs=60.0) and s.pos[1] > 0  # orange respawns on its side
    assert s.boost == pytest.approx(C.BOOST_SPAWN_AMOUNT, abs=1.0)


def test_slow_car_bumps_instead_of_demolishing(arena):
    attacker, victim = arena.add_car(team=0), arena.add_car(team=1)
    attacker.set_state(_grounded(y=-1500.0, vel=np.array([0.0, 1400.0, 0.0])))
    victim.set_state(_grounded(y=-1250.0, yaw=0.0))
    attacker.set_controls(CarControls(throttle=1.0))
    bumps = []
    for _ in range(40):
        arena.step(1)
        bumps += [e for e in arena.drain_events() if isinstance(e, CarBumped)]
        if bumps:
            break
    arena.step(1)
    assert not victim.get_state().is_demoed
    assert victim.get_state().vel[1] > 1100.0  # pushed along the attacker's direction (RocketSim: 1558)
    assert [(e.attacker_id, e.victim_id) for e in bumps] == [(attacker.id, victim.id)]
    extra = attacker.get_extra_state()
    assert extra.car_contact_id == victim.id and 0.0 < extra.car_contact_cooldown_s <= C.BUMP_COOLDOWN_TIME


def test_car_drives_up_the_side_wall(arena):
    car = arena.add_car(team=0)
    car.set_state(_grounded(x=3000.0, y=0.0, yaw=0.0, vel=np.array([1800.0, 0.0, 0.0]), boost=100.0))
    car.set_controls(CarControls(throttle=1.0, boost=True))
    arena.step(90)
    s = car.get_state()
    assert s.pos[2] > 400.0, s.pos  # up the curved ramp and onto the wall
    assert s.rot_mat[0, 2] < -0.8  # the car's up vector points away from the wall at x = +4096
    assert sum(s.wheels_in_contact) >= 3


def test_ball_rolled_into_the_goal_scores(arena):
    arena.ball.set_state(BallState(pos=np.array([0.0, 4500.0, C.BALL_REST_Z]), vel=np.array([0.0, 1500.0, 0.0])))
    assert arena.scoring_team() is None
    arena.step(120)
    assert arena.scoring_team() == 0
    assert arena.ball.get_state().pos[1] < 6000.0  # the net holds it


def test_ball_bounces_off_the_back_wall_beside_the_goal(arena):
    arena.ball.set_state(BallState(pos=np.array([2500.0, 4500.0, 300.0]), vel=np.array([0.0, 2000.0, 0.0])))
    arena.step(120)
    b = arena.ball.get_state()
    assert b.pos[1] < 5120.0 and b.vel[1] < 0.0
    assert arena.scoring_team() is None


def test_head_on_hit_sends_the_ball_faster_than_the_car(arena):
    car = arena.add_car(team=0)
    arena.ball.set_state(BallState(pos=np.array([0.0, 0.0, C.BALL_REST_Z])))
    car.set_state(_grounded(y=-600.0, vel=np.array([0.0, 1400.0, 0.0])))
    car.set_controls(CarControls(throttle=1.0))
    arena.step(60)
    ball_speed = np.linalg.norm(arena.ball.get_state().vel)
    assert ball_speed == pytest.approx(1882.0, rel=0.1)  # RocketSim: 1401 -> 1882


@pytest.mark.parametrize("x", [0.0, 300.0, -2500.0])
def test_a_rolling_ball_stays_on_the_floor_all_the_way_into_the_goal(arena, x):
    """Regression: coplanar floor triangles in the collision mesh kicked a rolling ball up at their edges."""
    arena.ball.set_state(BallState(pos=[x, -4000.0, C.BALL_RADIUS], vel=[0.0, 2500.0, 0.0]))
    max_vz = 0.0
    for _ in range(int(C.TICK_RATE_HZ * 10)):
        arena.step(1)
        ball = arena.ball.get_state()
        if abs(ball.pos[1]) > C.ARENA_EXTENT_Y - 600.0 and ball.pos[1] > 0.0:
            break  # the far end: the ramp (or, at x = 0, the goal) begins
        max_vz = max(max_vz, abs(ball.vel[2]))
    assert ball.pos[1] > 4000.0
    assert max_vz < 5.0
