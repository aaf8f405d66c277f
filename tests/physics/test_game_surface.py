"""The surface game logic uses: MutatorConfig, typed events, boost pads, ball hit info, the car's extra state."""
import math

import numpy as np
import pytest

from rocketdrl_ma.physics import (Arena, ArenaBatch, BallState, BallTouch, BoostPadState, BoostPadTaken, CarBumped,
                                  CarControls, CarDemolished, CarExtraState, CarState, DemoMode, MutatorConfig,
                                  yaw_rot_mat)
from rocketdrl_ma.physics import constants as C

UP_Y = math.pi / 2


@pytest.fixture
def arena():
    a = Arena(seed=0)
    yield a
    a.close()


def _grounded(x=0.0, y=0.0, yaw=UP_Y, vel=(0.0, 0.0, 0.0), **kw):
    return CarState(pos=np.array([x, y, 17.0]), rot_mat=yaw_rot_mat(yaw), vel=np.array(vel, float), on_ground=True,
                    wheels_in_contact=(True,) * 4, **kw)


# ------------------------------------------------------------------ boost pads
def test_pads_are_in_rocketsims_order(rocketsim_oracle):
    import RocketSim as rs
    rs_arena = rs.Arena(rs.GameMode.SOCCAR)  # held: its pads point into it
    theirs = [(p.get_pos().as_numpy().tolist(), p.is_big) for p in rs_arena.get_boost_pads()]
    ours = Arena().get_boost_pads()
    assert [p.index for p in ours] == list(range(34))
    assert [(p.pos.tolist(), p.is_big) for p in ours] == theirs


def test_pads_are_in_rlgyms_order():
    common = pytest.importorskip("rlgym.rocket_league.common_values", reason="rlgym (the rlgym extra) not installed")
    # RLGym lists (-940, 3310, 70): a typo for 3308 (RocketSim and the RLBot wiki); the order is what matters.
    np.testing.assert_allclose(C.BOOST_PAD_POSITIONS, np.array(common.BOOST_LOCATIONS), atol=2.0)


def test_pad_state_pickup_event_and_cooldown(arena):
    car = arena.add_car(team=0)
    pads = arena.get_boost_pads()
    big = next(p for p in pads if p.is_big)
    small = next(p for p in pads if not p.is_big)
    small.set_state(BoostPadState(cooldown_s=1.5))
    assert not small.get_state().is_active and arena.boost_pad_timers()[small.index] == 1.5
    with pytest.raises(ValueError, match="cooldown_s"):
        small.set_state(BoostPadState(cooldown_s=-1.0))
    car.set_state(_grounded(x=big.pos[0], y=big.pos[1], boost=30.0))
    arena.step(1)
    pickups = [e for e in arena.drain_events() if isinstance(e, BoostPadTaken)]
    assert pickups == [BoostPadTaken(tick=arena.tick_count, arena=0, car_id=car.id, pad_index=big.index, amount=70.0)]
    assert big.get_state().cooldown_s == pytest.approx(C.BOOST_PAD_BIG_COOLDOWN)
    assert small.get_state().cooldown_s == pytest.approx(1.5 - 1 / 120)
    arena.set_boost_pad_timers(np.zeros(34))
    assert all(p.get_state().is_active for p in pads)


# ------------------------------------------------------------------ mutators
@pytest.mark.parametrize("field, value, message", [
    ("demo_mode", "sometimes", "demo_mode: must be one of"), ("boost_pads", 1, "boost_pads: must be true or false"),
    ("gravity_z_uu_s2", math.nan, "gravity_z_uu_s2: must be a finite number"),
    ("boost_used_per_second", -1.0, "boost_used_per_second: must be >= 0"),
    ("car_spawn_boost", 150.0, "car_spawn_boost: must be in"), ("ball_max_speed_uu_s", 0.0, "ball_max_speed_uu_s"),
    ("ball_drag", 1.0, "ball_drag: must be in"), ("respawn_delay_s", "3", "respawn_delay_s: must be a finite number")])
def test_mutator_config_names_the_bad_field(field, value, message):
    with pytest.raises(ValueError, match=message):
        MutatorConfig(**{field: value})


def test_mutator_config_is_per_arena_and_gravity_per_batch():
    batch = ArenaBatch(2)
    batch.arenas[1].set_mutator_config(MutatorConfig(demo_mode=DemoMode.DISABLED, boost_pads=False))
    assert batch.arenas[0].get_mutator_config() == MutatorConfig()
    assert batch.arenas[1].get_mutator_config().demo_mode is DemoMode.DISABLED
    with pytest.raises(ValueError, match="gravity_z_uu_s2: the arenas of a batch share one gravity"):
        batch.arenas[0].set_mutator_config(MutatorConfig(gravity_z_uu_s2=-300.0))
    with pytest.raises(ValueError, match="config: expected MutatorConfig"):
        batch.set_mutator_config({"demo_mode": "disabled"})
    batch.set_mutator_config(MutatorConfig(gravity_z_uu_s2=-300.0))
    for a in batch.arenas:
        a.ball.set_state(BallState(pos=[0, 0, 1000], vel=[0, 0, -1e-3]))
    batch.step(120)
    for a in batch.arenas:  # 1 s of free fall at 300 uu/s^2 (the ball's drag takes 3 % a second)
        assert a.ball.get_state().pos[2] == pytest.approx(1000.0 - 150.0, abs=3.0)
    batch.close()


def _bumper_hit(arena, attacker_team, speed, supersonic):
    attacker, victim = arena.add_car(team=0), arena.add_car(team=attacker_team)
    attacker.set_state(_grounded(y=-1500.0, vel=(0.0, speed, 0.0), is_supersonic=supersonic, boost=100.0))
    victim.set_state(_grounded(y=-1250.0, yaw=0.0))
    attacker.set_controls(CarControls(throttle=1.0, boost=supersonic))
    events = []
    for _ in range(40):
        arena.step(1)
        events += [e for e in arena.drain_events() if isinstance(e, (CarBumped, CarDemolished))]
        if events:
            break
    return attacker, victim, events


@pytest.mark.parametrize("mode, team_demos, other_team, speed, supersonic, expect", [
    (DemoMode.NORMAL, False, 1, 1400.0, False, CarBumped), (DemoMode.NORMAL, False, 1, 2290.0, True, CarDemolished),
    (DemoMode.NORMAL, False, 0, 2290.0, True, CarBumped), (DemoMode.NORMAL, True, 0, 2290.0, True, CarDemolished),
    (DemoMode.ON_CONTACT, False, 1, 1000.0, False, CarDemolished),
    (DemoMode.DISABLED, False, 1, 2290.0, True, CarBumped)])
def test_demo_modes(arena, mode, team_demos, other_team, speed, supersonic, expect):
    arena.set_mutator_config(MutatorConfig(demo_mode=mode, team_demos=team_demos, respawn_delay_s=0.5))
    attacker, victim, events = _bumper_hit(arena, other_team, speed, supersonic)
    assert [(type(e), e.attacker_id, e.victim_id) for e in events] == [(expect, attacker.id, victim.id)]
    assert victim.get_state().is_demoed == (expect is CarDemolished)
    if expect is CarDemolished:
        assert victim.get_state().demo_respawn_timer == pytest.approx(0.5, abs=1.01 / 120)
        arena.step(61)
        assert not victim.get_state().is_demoed


def test_mutators_change_boost_jumps_and_the_ball(arena):
    arena.set_mutator_config(MutatorConfig(boost_used_per_second=0.0, jump_immediate_vel_uu_s=600.0,
                                           ball_max_speed_uu_s=1000.0, car_spawn_boost=50.0, boost_pads=False))
    car = arena.add_car(team=0)
    arena.reset_kickoff(seed=1)
    assert car.get_state().boost == pytest.approx(50.0)
    car.set_state(_grounded(y=-2000.0, boost=40.0))
    car.set_controls(CarControls(boost=True, jump=True))
    arena.step(2)
    s = car.get_state()
    assert s.boost == pytest.approx(40.0)  # boost never runs out
    assert s.vel[2] > 600.0  # the stronger first jump (the game's is 292)
    arena.ball.set_state(BallState(pos=[0, 0, 1000], vel=[3000, 0, 0]))
    arena.step(1)
    assert np.linalg.norm(arena.ball.get_state().vel) == pytest.approx(1000.0)


def test_unlimited_flips(arena):
    arena.set_mutator_config(MutatorConfig(unlimited_flips=True))
    car = arena.add_car(team=0)
    car.set_state(CarState(pos=np.array([0.0, 0.0, 1000.0]), rot_mat=yaw_rot_mat(UP_Y)))
    for _ in range(3):  # three dodges in one flight: each adds its forward push
        car.set_controls(CarControls(jump=True, pitch=-1.0))
        arena.step(1)
        car.set_controls(CarControls())
        arena.step(2)
    assert car.get_state().vel[1] == pytest.approx(3 * C.FLIP_INITIAL_VEL_SCALE, rel=0.02)


# ------------------------------------------------------------------ events and hit info
def test_ball_touch_events_and_hit_info():
    batch = ArenaBatch(2)
    cars = [a.add_car(team=0) for a in batch.arenas]
    for car, a in zip(cars, batch.arenas):
        car.set_state(_grounded(y=-400.0, vel=(0.0, 1000.0, 0.0)))
        car.set_controls(CarControls(throttle=1.0))
        a.ball.set_state(BallState(pos=[0, 0, C.BALL_REST_Z]))
    batch.arenas[1].ball.set_state(BallState(pos=[0, 3000, C.BALL_REST_Z]))  # out of reach
    touches, first_info = [], None
    for _ in range(40):
        batch.step(1)
        touches += batch.arenas[0].drain_events()
        first_info = first_info or cars[0].get_ball_hit_info()
    assert batch.arenas[1].drain_events() == [] and cars[1].get_ball_hit_info() is None
    assert touches and all(isinstance(e, BallTouch) and e.car_id == cars[0].id and e.arena == 0 for e in touches)
    first = touches[0]
    assert first.extra_impulse and first_info.tick == first_info.extra_impulse_tick == first.tick
    assert np.linalg.norm(first_info.extra_hit_vel) > 300.0
    rel = np.array(first.contact_point) - np.array(first_info.ball_pos)
    assert np.linalg.norm(rel) == pytest.approx(C.BALL_RADIUS, abs=3.0)  # the point lies on the ball's surface
    np.testing.assert_allclose(first_info.relative_pos_on_ball, rel)
    assert np.dot(first.contact_normal, -rel / np.linalg.norm(rel)) > 0.95  # car -> ball
    info = cars[0].get_ball_hit_info()
    assert info.tick == touches[-1].tick
    assert [e.tick for e in touches if e.extra_impulse] == [first.tick]  # one push per touch, as in RocketSim
    assert info.extra_impulse_tick == first.tick
    assert np.linalg.norm(batch.arenas[0].ball.get_state().vel) > 1000.0
    batch.close()


# ------------------------------------------------------------------ the car's extra state
def _flip_snapshot(arena, car):
    car.set_state(CarState(pos=np.array([0.0, 0.0, 800.0]), vel=np.array([0.0, 500.0, 0.0]),
                           rot_mat=yaw_rot_mat(UP_Y), has_jumped=True))
    car.set_controls(CarControls(jump=True, pitch=-0.6, yaw=0.8, boost=True))
    arena.step(3)
    return car.get_state(), car.get_extra_state()


def _continue(arena, car, ticks=40):
    out = []
    for _ in range(ticks):
        arena.step(1)
        out.append(np.concatenate([car.get_state().pos, car.get_state().ang_vel]))
    return np.array(out)


@pytest.mark.parametrize("restore_extra", [True, False])
def test_extra_state_restores_a_flip_exactly(restore_extra):
    a, b = Arena(), Arena()
    car_a, car_b = a.add_car(team=0), b.add_car(team=0)
    state, extra = _flip_snapshot(a, car_a)
    assert extra.holding_jump and extra.boost_active_time_s > 0.0 and extra.flip_torque != (0.0, 0.0, 0.0)
    car_b.set_state(state)
    if restore_extra:
        car_b.set_extra_state(extra)
        assert car_b.get_extra_state() == extra
    car_b.set_controls(car_a.get_controls())
    # Only the rotation's round trip through a quaternion differs (1e-16): the flip plays on as it was.
    gap = np.abs(_continue(a, car_a) - _continue(b, car_b)).max()
    assert (gap < 1e-6) if restore_extra else (gap > 1.0)  # without it, the flip's torque is lost
    a.close()
    b.close()


def test_extra_state_checks_its_car_contact(arena):
    car = arena.add_car(team=0)
    with pytest.raises(ValueError, match="car_contact_id"):
        car.set_extra_state(CarExtraState(car_contact_id=car.id, car_contact_cooldown_s=0.1))
    with pytest.raises(ValueError, match="auto_flip_direction"):
        CarExtraState(auto_flip_direction=0.5)


def test_batch_arrays_are_read_only_views():
    batch = ArenaBatch(2)
    car = batch.arenas[1].add_car(team=1)
    car.set_state(_grounded(x=100.0, boost=42.0))
    arrays = batch.arrays()
    assert arrays.car_boost[car.batch_row] == 42.0 and arrays.car_arena[car.batch_row] == 1
    assert arrays.car_pos[car.batch_row, 0] == pytest.approx(100.0)
    with pytest.raises(ValueError):
        arrays.car_boost[car.batch_row] = 0.0
    batch.close()
