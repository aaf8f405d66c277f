"""``RocketDRLEngine`` against RLGym's contract and against ``RocketSimEngine`` (the oracle) on the same configs."""
import random

import numpy as np
import pytest
from rlgym.rocket_league import common_values
from rlgym.rocket_league.api import GameState
from rlgym.rocket_league.done_conditions import GoalCondition, NoTouchTimeoutCondition
from rlgym.rocket_league.reward_functions import GoalReward, TouchReward
from rlgym.rocket_league.state_mutators import FixedTeamSizeMutator, KickoffMutator, MutatorSequence

from rlgym_helpers import ScriptedAction, SceneMutator, controls, new_car, readme_env, scene_env, seeded_reset
from rocketdrl_ma.physics import Arena
from rocketdrl_ma.rlgym import HITBOX_PRESETS, RocketDRLEngine

# RocketSim keeps its state in float32 in Bullet's metres (uu / 50): a kickoff spot such as y = -2560 reads back
# as -2560.0002 there and exactly here, 4.1e-8 in DefaultObs' units (measured); nothing else differs.
KICKOFF_OBS_ATOL = 1e-6
# 1 s (15 actions of 8 ticks) of scripted controls from a 2v2 kickoff, max |obs difference| in DefaultObs units
# over every agent, step and seed; measured: 1.5e-5, 0.0017, 0.0002, 1.5e-5.
SCRIPTS = {
    "boost": (1e-3, lambda step, agent: controls(throttle=1, boost=1)),
    "powerslide": (5e-3, lambda step, agent: controls(throttle=1, steer=1, handbrake=step > 3)),
    "steer_jump_flip": (2e-3, lambda step, agent: controls(throttle=1, steer=0.5 if agent.startswith("blue") else -0.5,
                                                           jump=step in (4, 6), pitch=-1 if step == 6 else 0)),
    "aerial": (1e-3, lambda step, agent: controls(throttle=1, jump=step in (2, 3, 4), pitch=0.6 if step >= 3 else 0,
                                                  boost=step >= 3, roll=0.3)),
}


@pytest.fixture
def engines(rocketsim_engine_cls):
    """A fresh pair (ours, RocketSim's); each test builds its envs on it."""
    ours, theirs = RocketDRLEngine(), rocketsim_engine_cls()
    yield ours, theirs
    ours.close()


def test_readme_config_runs_a_full_episode():
    env = readme_env(RocketDRLEngine())
    obs = seeded_reset(env, 0)
    assert sorted(obs) == ["blue-0", "blue-1", "orange-0", "orange-1"]
    rng = np.random.default_rng(0)
    for step in range(1, 4501):  # TimeoutCondition(300 s) ends it by step 4500 at the latest
        obs, rewards, terminated, truncated = env.step({a: rng.integers(0, 90, size=1) for a in env.agents})
        assert env.state.tick_count == 8 * step
        assert all(o.shape == (132,) and np.all(np.isfinite(o)) for o in obs.values())
        if any(terminated.values()) or any(truncated.values()):
            break
    else:
        pytest.fail("the episode never ended")
    assert all(terminated.values()) or all(truncated.values())
    assert env.state.goal_scored == all(terminated.values())
    env.close()


@pytest.mark.parametrize("team_size", [1, 2, 3])
def test_default_obs_after_kickoff_equals_rocketsim(engines, team_size):
    envs = [readme_env(engine, team_size) for engine in engines]
    for seed in range(5):
        ours, theirs = (seeded_reset(env, seed) for env in envs)
        assert list(ours) == list(theirs)
        for agent in ours:
            assert ours[agent].shape == theirs[agent].shape == (52 + 40 * team_size,)
            np.testing.assert_allclose(ours[agent], theirs[agent], rtol=0, atol=KICKOFF_OBS_ATOL)
        a_state, b_state = (env.state for env in envs)
        np.testing.assert_array_equal(a_state.boost_pad_timers, b_state.boost_pad_timers)
        for agent, car in a_state.cars.items():
            other = b_state.cars[agent]
            assert car.physics.position.dtype == other.physics.position.dtype == np.float32
            np.testing.assert_array_equal(car.physics.rotation_mtx, other.physics.rotation_mtx)
            for field in ("team_num", "hitbox_type", "ball_touches", "bump_victim_id", "boost_amount",
                          "wheels_with_contact", "is_holding_jump", "has_jumped", "has_flipped", "demo_respawn_timer"):
                assert getattr(car, field) == pytest.approx(getattr(other, field)), field


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_default_obs_follows_rocketsim_for_one_second(engines, script):
    tolerance, policy = SCRIPTS[script]
    worst = 0.0
    for seed in range(3):
        envs = [readme_env(engine) for engine in engines]
        for env in envs:
            env.action_parser = ScriptedAction(8)
            seeded_reset(env, seed)
        for step in range(15):
            actions = {agent: policy(step, agent) for agent in envs[0].agents}
            ours, theirs = (env.step(actions)[0] for env in envs)
            worst = max(worst, max(float(np.abs(ours[a] - theirs[a]).max()) for a in ours))
    assert worst <= tolerance
    assert envs[0].state.tick_count == envs[1].state.tick_count == 120


def test_car_fields_follow_rocketsim_tick_by_tick(engines):
    """Every Car field RLGym's components read, through a boost, a jump, a front flip, a jump with yaw and a
    powerslide, on every tick: flags equal, timers (jump, flip, air time, supersonic, boost, auto-flip) within 2e-6 s
    (RocketSim's float32 timers)."""
    def script(tick):
        s = tick // 8
        return controls(throttle=1, steer=0.3, jump=s in (3, 5, 9), pitch=-1 if s == 5 else 0,
                        yaw=0.5 if s == 9 else 0, boost=s < 4, handbrake=s > 11)
    cars = {"car": new_car(0, (0, -2000, 17), yaw=np.pi / 2, vel=(0, 1500, 0))}
    envs = [scene_env(engine, SceneMutator(cars, (3000, 4000, 93.15)), repeats=1) for engine in engines]
    for env in envs:
        env.reset()
    for tick in range(160):
        for env in envs:
            env.step({"car": script(tick)})
        ours, theirs = (env.state.cars["car"] for env in envs)
        for field in ("is_holding_jump", "has_jumped", "is_jumping", "has_flipped", "has_double_jumped", "can_flip",
                      "on_ground", "wheels_with_contact", "is_boosting", "is_autoflipping", "bump_victim_id",
                      "ball_touches", "team_num", "hitbox_type", "is_demoed", "is_supersonic"):
            assert getattr(ours, field) == getattr(theirs, field), (tick, field)
        for field in ("jump_time", "flip_time", "air_time_since_jump", "supersonic_time", "boost_active_time",
                      "autoflip_timer", "demo_respawn_timer"):
            assert getattr(ours, field) == pytest.approx(getattr(theirs, field), abs=2e-6), (tick, field)
        for field in ("boost_amount", "handbrake", "autoflip_direction"):
            assert getattr(ours, field) == pytest.approx(getattr(theirs, field), abs=2e-3), (tick, field)
        np.testing.assert_allclose(ours.flip_torque, theirs.flip_torque, atol=1e-4)
        np.testing.assert_allclose(ours.physics.position, theirs.physics.position, atol=3.0)


@pytest.mark.parametrize("hitbox", range(6))
def test_hitbox_ids_map_to_rocketsim_cars(engines, hitbox):
    """Each id settles at its own ride height: the same as RocketSim's car of that id."""
    cars = {"car": new_car(0, (0, 0, 60), hitbox=hitbox, on_ground=False)}
    envs = [scene_env(engine, SceneMutator(cars, (3000, 4000, 93.15))) for engine in engines]
    heights = []
    for env in envs:
        env.reset()
        assert env.state.cars["car"].hitbox_type == hitbox
        for _ in range(15):
            env.step({"car": controls()})
        heights.append(float(env.state.cars["car"].physics.position[2]))
    assert engines[0].arena.cars[0].config.name == HITBOX_PRESETS[hitbox]
    assert heights[0] == pytest.approx(heights[1], abs=0.5)


def test_rotation_comes_from_rotation_mtx_quaternion_or_euler(engines):
    euler = np.array([0.4, -2.0, 1.1], dtype=np.float32)
    cars = {"by_euler": new_car(0, (-1000, 0, 800), on_ground=False),
            "by_mtx": new_car(1, (0, 0, 800), on_ground=False),
            "by_quat": new_car(1, (1000, 0, 800), on_ground=False)}
    cars["by_euler"].physics.euler_angles = euler
    cars["by_mtx"].physics.rotation_mtx = new_car(0, (0, 0, 0)).physics.rotation_mtx
    cars["by_mtx"].physics.euler_angles = euler
    cars["by_mtx"].physics.rotation_mtx = cars["by_mtx"].physics.rotation_mtx.copy()
    cars["by_quat"].physics.euler_angles = euler
    cars["by_quat"].physics.quaternion = cars["by_quat"].physics.quaternion.copy()
    states = []
    for engine in engines:
        env = scene_env(engine, SceneMutator(cars, (3000, 4000, 93.15)))
        env.reset()
        states.append(env.state)
        for agent in cars:
            np.testing.assert_allclose(env.state.cars[agent].physics.euler_angles, euler, atol=1e-5)
    for agent in cars:
        np.testing.assert_allclose(states[0].cars[agent].physics.rotation_mtx,
                                   states[1].cars[agent].physics.rotation_mtx, atol=1e-6)


@pytest.mark.parametrize("rlbot_delay", [True, False])
def test_rlbot_delay_as_rocketsim(rocketsim_engine_cls, rlbot_delay):
    """With the delay, the first tick of an action runs on the previous controls (none after a reset)."""
    speeds = {}
    for name, engine in (("ours", RocketDRLEngine(rlbot_delay=rlbot_delay)),
                         ("rocketsim", rocketsim_engine_cls(rlbot_delay=rlbot_delay))):
        assert engine.config == {"rlbot_delay": rlbot_delay}
        env = scene_env(engine, SceneMutator({"car": new_car(0, (0, -1000, 17.01), yaw=np.pi / 2)},
                                             (3000, 4000, 93.15)), repeats=4)
        env.reset()
        trace = []
        for _ in range(3):
            env.step({"car": controls(throttle=1)})
            trace.append(float(env.state.cars["car"].physics.linear_velocity[1]))
        env.step({"car": controls()})
        trace.append(float(env.state.cars["car"].physics.linear_velocity[1]))
        speeds[name] = trace
    np.testing.assert_allclose(speeds["ours"], speeds["rocketsim"], atol=0.5)
    ours = RocketDRLEngine(rlbot_delay=False)
    ours.config = {"rlbot_delay": True}
    assert ours.config == {"rlbot_delay": True}


def test_rlbot_delay_shifts_controls_by_one_tick():
    """A boosting car in the air: with the delay, tick n + 1 carries the boost the undelayed engine gave tick n."""
    by_tick = {}
    for delay in (True, False):
        env = scene_env(RocketDRLEngine(rlbot_delay=delay),
                        SceneMutator({"car": new_car(0, (0, -1000, 1000), yaw=np.pi / 2, on_ground=False,
                                                     boost=100)}, (3000, 4000, 93.15)), repeats=1)
        env.reset()
        trace = []
        for _ in range(6):
            env.step({"car": controls(boost=1)})
            trace.append(float(env.state.cars["car"].physics.linear_velocity[1]))
        by_tick[delay] = trace
    assert by_tick[True][0] == pytest.approx(0.0, abs=1e-3)  # the first tick ran with no input
    assert by_tick[False][0] > 5.0
    np.testing.assert_allclose(by_tick[True][1:], by_tick[False][:-1], atol=1e-3)


def test_tick_count_pad_timers_and_config_are_set(engines):
    timers = np.linspace(0.0, 9.9, 34).astype(np.float32)
    states = []
    for engine in engines:
        env = scene_env(engine, SceneMutator({"car": new_car(0, (0, -3000, 17.01))}, (3000, 4000, 93.15)))
        desired = engine.create_base_state()
        env.state_mutator.apply(desired, {})
        desired.tick_count = 1000
        desired.boost_pad_timers = timers.copy()
        desired.config.gravity, desired.config.boost_consumption = 0.5, 2.0
        state = engine.set_state(desired, {})
        assert state.tick_count == 1000
        np.testing.assert_array_equal(state.boost_pad_timers, timers)
        env.reset = None  # only the engine is used below
        state = engine.step({"car": np.repeat(controls(boost=1)[None], 8, axis=0)}, {})
        assert state.tick_count == 1008 and state.config.gravity == 0.5
        states.append(state)
    np.testing.assert_allclose(states[0].boost_pad_timers, states[1].boost_pad_timers, atol=1e-5)
    np.testing.assert_allclose(states[0].boost_pad_timers, np.maximum(timers - 8 / 120, 0), atol=1e-5)
    # half gravity and double boost use act as in RocketSim
    ours, theirs = (s.cars["car"] for s in states)
    assert ours.boost_amount == pytest.approx(theirs.boost_amount, abs=1e-3)
    assert ours.boost_amount < 33.3 - 2 * 33.3 * 7 / 120 + 0.5
    np.testing.assert_allclose(ours.physics.linear_velocity, theirs.physics.linear_velocity, atol=0.5)


def test_pad_order_equals_rocketsim_and_rlgym(rocketsim_engine_cls):
    import RocketSim as rs
    rocketsim_engine_cls()  # RocketSim initialised
    arena = rs.Arena(rs.GameMode.SOCCAR)  # its pads live as long as it does
    theirs = arena.get_boost_pads()
    ours = Arena().get_boost_pads()
    assert len(ours) == len(theirs) == len(common_values.BOOST_LOCATIONS) == 34
    for index, (a, b, loc) in enumerate(zip(ours, theirs, common_values.BOOST_LOCATIONS)):
        assert a.index == index
        assert a.is_big == b.is_big
        np.testing.assert_allclose(a.pos[:2], np.asarray(b.get_pos())[:2], atol=1e-3)
        np.testing.assert_allclose(a.pos[:2], loc[:2], atol=2.5)  # BOOST_LOCATIONS has (-940, 3310) for 3308


@pytest.mark.parametrize("pad_index", [7, 13, 15, 20])
def test_a_taken_pad_shows_at_the_same_index(engines, pad_index):
    x, y, _ = common_values.BOOST_LOCATIONS[pad_index]
    cars = {"car": new_car(0, (x, y - 400, 17.01), yaw=np.pi / 2, vel=(0, 1000, 0), boost=0)}
    timers = []
    for engine in engines:
        env = scene_env(engine, SceneMutator(cars, (3000, 4000, 93.15) if x < 2500 else (-3000, 4000, 93.15)))
        env.reset()
        for _ in range(8):
            env.step({"car": controls(throttle=1)})
        timers.append(env.state.boost_pad_timers)
    taken = [set(np.flatnonzero(t).tolist()) for t in timers]
    assert taken[0] == taken[1] == {pad_index}
    np.testing.assert_allclose(timers[0], timers[1], atol=1e-4)


def _done_steps(engines, mutator, make_conditions, steps, action):
    """Per engine: the step of each signal (termination, truncation, reward) for ``steps`` steps."""
    out = []
    for engine in engines:
        termination, truncation, reward = make_conditions()
        env = scene_env(engine, mutator, reward_fn=reward, termination_cond=termination, truncation_cond=truncation)
        env.reset()
        log = []
        for step in range(steps):
            _, rewards, terminated, truncated = env.step({a: action for a in env.agents})
            log.append((tuple(terminated.values()), tuple(truncated.values()), tuple(rewards.values()),
                        env.state.goal_scored, env.state.scoring_team))
        out.append(log)
    return out


@pytest.mark.parametrize("side", [1, -1])
def test_goal_condition_fires_alike(engines, side):
    mutator = SceneMutator({"blue": new_car(0, (-2500, 0, 17.01)), "orange": new_car(1, (2500, 0, 17.01))},
                           (300, side * 4700, 93.15), (0, side * 2000, 0))
    ours, theirs = _done_steps(engines, mutator, lambda: (GoalCondition(), None, GoalReward()), 8, controls())
    assert ours == theirs
    first = next(i for i, entry in enumerate(ours) if entry[0][0])
    assert all(entry[0] == (True, True) for entry in ours[first:])
    assert ours[first][4] == (0 if side == 1 else 1)
    assert ours[first][2] == ((1.0, -1.0) if side == 1 else (-1.0, 1.0))
    assert not any(entry[3] for entry in ours[:first])


@pytest.mark.parametrize("distance", [200.0, 600.0, 1200.0])
def test_touch_reward_fires_alike(engines, distance):
    """The first touch comes on the same step, give or take one (a tick's difference in arrival can straddle
    a step boundary), and the reward fires exactly when ball_touches says so."""
    mutator = SceneMutator({"car": new_car(0, (0, -distance, 17.01), yaw=np.pi / 2)}, (0, 0, 93.15))
    ours, theirs = _done_steps(engines, mutator, lambda: (None, None, TouchReward()), 20,
                               controls(throttle=1, boost=1))
    first = [next(i for i, entry in enumerate(log) if entry[2] == (1.0,)) for log in (ours, theirs)]
    assert abs(first[0] - first[1]) <= 1
    assert all(entry[2] == (0.0,) for entry in ours[:first[0]])


@pytest.mark.parametrize("timeout_s, distance", [(0.5, 3000.0), (1.0, 3000.0), (1.0, 700.0)])
def test_no_touch_timeout_fires_alike(engines, timeout_s, distance):
    """A car that never reaches the ball ends the episode at the timeout; one that touches it restarts the clock."""
    mutator = SceneMutator({"car": new_car(0, (0, -distance, 17.01), yaw=np.pi / 2)}, (0, 0, 93.15))
    ours, theirs = _done_steps(engines, mutator,
                               lambda: (None, NoTouchTimeoutCondition(timeout_s), TouchReward()), 40,
                               controls(throttle=1))
    assert [entry[1] for entry in ours] == [entry[1] for entry in theirs]
    assert [entry[2] for entry in ours] == [entry[2] for entry in theirs]
    assert any(entry[1] == (True,) for entry in ours)


def test_bump_and_demo_alike(engines):
    """A fast car hits a parked opponent: bump_victim_id names it while the cooldown runs; supersonic, it demos."""
    for speed, demo in ((1200.0, False), (2290.0, True)):
        cars = {"attacker": new_car(0, (0, -600, 17.01), yaw=np.pi / 2, vel=(0, speed, 0)),
                "victim": new_car(1, (0, 0, 17.01))}
        logs = []
        for engine in engines:
            env = scene_env(engine, SceneMutator(cars, (3000, 4000, 93.15)), repeats=4)
            env.reset()
            log = []
            for _ in range(20):
                env.step({"attacker": controls(throttle=1, boost=demo), "victim": controls()})
                s = env.state.cars
                log.append((s["attacker"].bump_victim_id, s["victim"].is_demoed))
            logs.append(log)
        assert ("victim", demo) in logs[0]
        hits = [[i for i, entry in enumerate(log) if entry[0] == "victim"] for log in logs]
        assert abs(hits[0][0] - hits[1][0]) <= 1
        assert [entry[1] for entry in logs[0]] == [entry[1] for entry in logs[1]]


def test_touch_counts_every_tick_in_contact(engines):
    """ball_touches is the number of ticks in contact since the last state, as RocketSim's callback counts."""
    mutator = SceneMutator({"car": new_car(0, (0, -300, 17.01), yaw=np.pi / 2)}, (0, 0, 93.15))
    counts = []
    for engine in engines:
        env = scene_env(engine, mutator, repeats=1)
        env.reset()
        log = []
        for _ in range(60):
            env.step({"car": controls(throttle=1)})
            log.append(env.state.cars["car"].ball_touches)
        counts.append(log)
    assert counts[0] == counts[1]
    assert sum(counts[0]) >= 1


def test_bad_input_is_a_clear_error_and_changes_nothing():
    engine = RocketDRLEngine()
    env = scene_env(engine, SceneMutator({"car": new_car(0, (0, 0, 17.01))}, (3000, 4000, 93.15)))
    env.reset()
    before = engine.state
    bad = engine.create_base_state()
    SceneMutator({"x": new_car(0, (0, 0, 17.01), hitbox=7)}, (0, 0, 93.15)).apply(bad, {})
    with pytest.raises(ValueError, match=r"cars\['x'\].hitbox_type: must be one of 0..5"):
        engine.set_state(bad, {})
    bad.cars["x"].hitbox_type = 0
    bad.cars["x"].flip_torque = None
    with pytest.raises(ValueError, match=r"cars\['x'\].flip_torque: not set"):
        engine.set_state(bad, {})
    bad.cars["x"].flip_torque = np.zeros(3)
    bad.cars["x"].bump_victim_id = "nobody"
    with pytest.raises(ValueError, match="bump_victim_id"):
        engine.set_state(bad, {})
    assert engine.agents == ["car"] and engine.state is before
    with pytest.raises(KeyError, match="missing"):
        engine.step({}, {})
    with pytest.raises(ValueError, match=r"shape \(ticks, 8\)"):
        engine.step({"car": np.zeros(8)}, {})
    with pytest.raises(ValueError, match="finite"):
        engine.step({"car": np.full((1, 8), np.nan)}, {})
    assert engine.state.tick_count == before.tick_count


def test_controls_are_clamped_and_buttons_read_as_bool():
    """As RocketSim: axes outside [-1, 1] are clamped, any non-zero button is pressed."""
    finals = []
    for action in (controls(throttle=5, jump=0.3), controls(throttle=1, jump=1)):
        env = scene_env(RocketDRLEngine(), SceneMutator({"car": new_car(0, (0, 0, 17.01))}, (3000, 4000, 93.15)))
        env.reset()
        env.step({"car": action})
        finals.append(env.state.cars["car"].physics.position.copy())
    np.testing.assert_array_equal(finals[0], finals[1])


def _ball_off_the_side_wall_fillet(engine: RocketDRLEngine) -> np.ndarray:
    """The ball's velocity 0.5 s after it is sent at 1,500 uu/s into the side wall at z = 250."""
    state = engine.create_base_state()
    SceneMutator({}, (3500, 0, 250)).apply(state, {})
    state.ball.linear_velocity = np.array([1500, 0, 0], dtype=np.float32)
    engine.set_state(state, {})
    for _ in range(60):
        state = engine.step({}, {})
    return state.ball.linear_velocity


def test_the_engine_takes_the_arena_shape():
    game, classic = RocketDRLEngine(arena_shape="game"), RocketDRLEngine()
    assert game.arena.batch.arena_shape == "game" and classic.arena.batch.arena_shape == "classic"
    assert np.linalg.norm(_ball_off_the_side_wall_fillet(game) - _ball_off_the_side_wall_fillet(classic)) > 200.0
    with pytest.raises(ValueError, match=r"arena_shape: must be one of 'classic', 'game', got 'round'"):
        RocketDRLEngine(arena_shape="round")


def test_no_cars_steps_one_tick():
    engine = RocketDRLEngine()
    state = engine.create_base_state()
    SceneMutator({}, (0, 0, 500)).apply(state, {})
    state.ball.linear_velocity = np.array([0, 0, 100], dtype=np.float32)
    engine.set_state(state, {})
    assert engine.step({}, {}).tick_count == 1
    assert engine.agents == [] and engine.max_num_agents >= 8


def test_the_kickoff_mutators_run_unchanged():
    """RLGym's own mutators, as RLGym's README uses them."""
    engine = RocketDRLEngine()
    desired = engine.create_base_state()
    random.seed(1)
    MutatorSequence(FixedTeamSizeMutator(3, 3), KickoffMutator()).apply(desired, {})
    state = engine.set_state(desired, {})
    assert isinstance(state, GameState) and len(state.cars) == 6
    assert {car.team_num for car in state.cars.values()} == {0, 1}
    assert all(car.boost_amount == pytest.approx(33.3) for car in state.cars.values())


def test_a_demolished_car_is_set_and_respawns_alike(engines):
    demoed = new_car(0, (0, -2000, 17.01))
    demoed.demo_respawn_timer = 0.5
    logs = []
    for engine in engines:
        env = scene_env(engine, SceneMutator({"car": demoed}, (3000, 4000, 93.15)))
        env.reset()
        log = [(env.state.cars["car"].is_demoed, round(env.state.cars["car"].demo_respawn_timer, 3))]
        for _ in range(10):
            env.step({"car": controls()})
            log.append((env.state.cars["car"].is_demoed, round(env.state.cars["car"].demo_respawn_timer, 3)))
        logs.append(log)
    assert logs[0][0] == (True, 0.5)
    assert logs[0] == logs[1]
    assert logs[0][-1] == (False, 0.0)


class HitboxMutator:
    """Gives every car of the state the RLGym hitbox id ``hitbox`` (after ``FixedTeamSizeMutator`` made them)."""

    def __init__(self, hitbox: int):
        self.hitbox = hitbox

    def apply(self, state: GameState, shared_info: dict) -> None:
        for car in state.cars.values():
            car.hitbox_type = self.hitbox


@pytest.mark.parametrize("hitbox", range(6))
def test_kickoff_with_every_hitbox_follows_rocketsim_until_the_first_touch(engines, hitbox):
    """A 1v1 kickoff of each hitbox, boost held until the tank runs dry and on: DefaultObs within 1e-3 and
    ``is_boosting`` equal on every step before the first touch (RLGym's ``KickoffMutator`` spawns at z = 17, inside
    the Plank's, Breakout's and Merc's hard stop). The first tick of a new RocketSim arena runs its solver on
    Bullet's default 1/60 s step, so each engine plays one step before the compared episodes."""
    envs = []
    for engine in engines:
        env = readme_env(engine, team_size=1)
        env.state_mutator = MutatorSequence(FixedTeamSizeMutator(1, 1), KickoffMutator(), HitboxMutator(hitbox))
        env.action_parser = ScriptedAction(8)
        seeded_reset(env, 0)
        env.step({a: controls() for a in env.agents})
        envs.append(env)
    compared = []
    for seed in range(3):
        for env in envs:
            seeded_reset(env, seed)
        compared.append(0)
        for _ in range(30):
            actions = {a: controls(throttle=1, boost=1) for a in envs[0].agents}
            ours, theirs = (env.step(actions)[0] for env in envs)
            if any(car.ball_touches for env in envs for car in env.state.cars.values()):
                break
            compared[-1] += 1
            for agent in ours:
                np.testing.assert_allclose(ours[agent], theirs[agent], rtol=0, atol=1e-3, err_msg=agent)
                assert envs[0].state.cars[agent].is_boosting == envs[1].state.cars[agent].is_boosting
    # 33.3 boost lasts 15 steps: every kickoff is compared past the empty tank
    assert min(compared) >= 16, compared
