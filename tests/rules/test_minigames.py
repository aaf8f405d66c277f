"""Minigame rules on real PyBullet worlds: scripted shots (set state, then controls), misses, timeouts, rounds."""
import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import Arena, ArenaBatch, BallState, CarState, yaw_rot_mat
from rocketdrl_ma.physics import constants as C

# seed action layout: throttle, steer, jump, boost, drift (buttons pressed above 0)
DRIVE_BOOST = np.array([1.0, 0.0, -1.0, 1.0, -1.0], np.float32)
IDLE = np.array([0.0, 0.0, -1.0, -1.0, -1.0], np.float32)


def place(env, car_pos, ball_pos, car_vel=(0.0, 0.0, 0.0), ball_vel=(0.0, 0.0, 0.0), yaw=np.pi / 2, agent="blue_0"):
    rules = env.unwrapped.rules
    rules.cars[agent].set_state(CarState(pos=np.array(car_pos, float), vel=np.array(car_vel, float),
                                         rot_mat=yaw_rot_mat(yaw), boost=100.0, on_ground=True,
                                         wheels_in_contact=(True,) * 4))
    rules.arena.ball.set_state(BallState(pos=np.array(ball_pos, float), vel=np.array(ball_vel, float)))
    env.unwrapped._state = rules.game_state()


def run(env, action=DRIVE_BOOST, agent="blue_0", max_steps=2000, others=IDLE):
    """Step until the episode ends; returns (rewards of ``agent`` per step, the last infos, steps)."""
    rewards, infos = [], {}
    for _ in range(max_steps):
        if not env.agents:
            break
        actions = {a: (action if a == agent else others) for a in env.agents}
        _, r, term, trunc, infos = env.step(actions)
        rewards.append(r[agent])
    assert not env.agents, "the episode did not end"
    return rewards, infos


def straight_shot(env, x=0.0):
    """The car 600 uu behind a ball 2000 uu out, both on the goal's axis (or at ``x``), driving at it."""
    place(env, car_pos=(x, C.ARENA_EXTENT_Y - 2600.0, C.CAR_SPAWN_REST_Z),
          ball_pos=(x, C.ARENA_EXTENT_Y - 2000.0, C.BALL_REST_Z), car_vel=(0.0, 1200.0, 0.0))


# ------------------------------------------------------------------ penalty
def test_penalty_scripted_shot_scores_and_gets_ten():
    env = rocketdrl_ma.parallel_env("minigames/penalty.yaml")
    env.reset(seed=0)
    straight_shot(env)
    rewards, infos = run(env)
    info = infos["blue_0"]
    assert rewards[-1] == pytest.approx(10.0 - 0.01)
    assert all(r == pytest.approx(-0.01) for r in rewards[:-1])
    assert info["reward_terms"]["goal"] == pytest.approx(10.0)
    summary = info["summary"]
    assert summary["is_success"] is True and summary["goals"] == 1 and summary["misses"] == 0
    assert summary["stats"]["blue_0"]["touches"] >= 1 and summary["stats"]["blue_0"]["shots"] >= 1
    assert 0.5 < summary["time_to_goal_s"] < 5.0
    assert any(e.kind == "goal" and e.scorer == "blue_0" for e in info["events"])
    env.close()


@pytest.mark.parametrize("ball_pos, ball_vel, reason, overrides", [
    ((2000.0, 4000.0, C.BALL_REST_Z), (0.0, 2500.0, 0.0), "wide", {}),   # into the end wall beside the goal
    ((0.0, 4000.0, 900.0), (0.0, 2500.0, 0.0), "wide", {}),              # over the crossbar
    ((0.0, 1000.0, C.BALL_REST_Z), (0.0, -3000.0, 0.0), "retreat", {}),  # back over the halfway line
    ((0.0, -4000.0, C.BALL_REST_Z), (0.0, -3000.0, 0.0), "own_goal", {"miss_line_y": -C.ARENA_EXTENT_Y}),
])
def test_penalty_miss_gets_minus_ten_and_ends(ball_pos, ball_vel, reason, overrides):
    env = rocketdrl_ma.parallel_env("minigames/penalty.yaml", **overrides)
    env.reset(seed=1)
    place(env, car_pos=(-2500.0, 0.0, C.CAR_SPAWN_REST_Z), ball_pos=ball_pos, ball_vel=ball_vel)
    rewards, infos = run(env, action=IDLE)
    assert rewards[-1] == pytest.approx(-10.0 - 0.01)
    summary = infos["blue_0"]["summary"]
    assert summary["is_success"] is False and summary["misses"] == 1
    assert summary["results"][0]["reason"] == reason
    assert len(rewards) < 100  # it ended on the miss, long before the timeout
    env.close()


def test_penalty_timeout_ends_the_episode_after_exactly_timeout_s():
    env = rocketdrl_ma.parallel_env("minigames/penalty.yaml", timeout_s=2.0, tick_skip=5)
    env.reset(seed=2)
    rewards, infos = run(env, action=IDLE)
    assert len(rewards) == 2.0 * C.TICK_RATE_HZ / 5
    assert infos["blue_0"]["summary"]["results"][0]["reason"] == "timeout"
    assert sum(rewards) == pytest.approx(-10.0 - 0.01 * len(rewards))
    env.close()


def test_rounds_accumulate_score_until_the_last_round():
    env = rocketdrl_ma.parallel_env("minigames/penalty.yaml", rounds=3, timeout_s=2.5, info_format="numeric")
    env.reset(seed=3)
    straight_shot(env)
    rewards, infos = run(env)  # round 1: the shot; rounds 2-3: driving straight from random spawns
    info = infos["blue_0"]
    assert info["rounds_played"] == 3.0 and info["goals"] >= 1.0 and info["goals"] + info["misses"] == 3.0
    assert info["score_blue"] == info["goals"] and info["score_orange"] == info["misses"]
    assert sum(rewards) == pytest.approx(10.0 * info["goals"] - 10.0 * info["misses"] - 0.01 * len(rewards))
    env.close()


def test_difficulty_zero_spawns_on_the_goal_axis_and_one_spreads_along_the_width():
    env = rocketdrl_ma.parallel_env("minigames/penalty.yaml", difficulty=0.0)
    xs = []
    for seed in range(4):
        env.reset(seed=seed)
        state = env.unwrapped.rules.game_state()
        assert state.ball.pos[0] == 0.0 and state.cars["blue_0"].pos[0] == 0.0
        env.unwrapped.rules.set_difficulty(1.0)
        env.reset(seed=seed)
        state = env.unwrapped.rules.game_state()
        xs.append(state.ball.pos[0])
        assert state.ball.pos[1] == pytest.approx(C.ARENA_EXTENT_Y - 2000.0)
        assert state.cars["blue_0"].pos[1] == pytest.approx(C.ARENA_EXTENT_Y - 3000.0)
        env.unwrapped.rules.set_difficulty(0.0)
    assert max(np.abs(xs)) > 100.0 and max(np.abs(xs)) <= 1500.0
    env.close()


# ------------------------------------------------------------------ static boxes in the physics
def roll_ball_at(arena):
    """Roll the ball along the floor from y = 1000 towards +y at 1500 uu/s for one second."""
    arena.ball.set_state(BallState(pos=np.array([0.0, 1000.0, C.BALL_RADIUS]), vel=np.array([0.0, 1500.0, 0.0])))
    arena.step(120)
    return arena.ball.get_state()


def test_static_box_bounces_the_ball_moves_and_goes_away():
    arena = Arena(seed=0)
    box = arena.add_static_box([0.0, 2000.0, 150.0], [400.0, 50.0, 150.0])
    ball = roll_ball_at(arena)
    # Bounced back (and, rolling on the floor into the face, up: RocketSim merges the floor's and the face's
    # contact into one, so the ball leaves the corner upwards)
    assert ball.pos[1] < 2000.0 - 50.0 - C.BALL_RADIUS + 1.0 and ball.vel[1] < -50.0 and ball.vel[2] > 300.0
    arena.move_static_box(box, [0.0, 2000.0, 600.0])  # lifted: the rolling ball passes under
    assert roll_ball_at(arena).pos[1] > 2100.0
    arena.move_static_box(box, [0.0, 2000.0, -140.0])  # sunk to a 10 uu kerb: the ball bumps up over it
    ball = roll_ball_at(arena)
    assert ball.pos[1] > 2000.0 + 50.0 and ball.vel[2] > 100.0
    with pytest.raises(ValueError, match="top half extent"):  # sunk out of sight
        arena.move_static_box(box, [0.0, 2000.0, -160.0])
    arena.move_static_box(box, [0.0, 2000.0, 150.0])
    arena.remove_static_box(box)
    assert roll_ball_at(arena).pos[1] > 2100.0
    with pytest.raises(ValueError, match="box_id"):
        arena.remove_static_box(box)
    with pytest.raises(ValueError, match="half_extents_uu"):
        arena.add_static_box([0.0, 0.0, 100.0], [100.0, 0.0, 100.0])
    with pytest.raises(ValueError, match="center"):
        arena.add_static_box([0.0, 9000.0, 100.0], [100.0, 100.0, 100.0])
    with pytest.raises(ValueError, match="center"):
        arena.add_static_box([0.0, np.nan, 100.0], [100.0, 100.0, 100.0])
    arena.close()


def test_static_box_stays_in_its_own_arena_of_a_batch():
    batch = ArenaBatch(2, seed=0)
    batch.arenas[1].add_static_box([0.0, 2000.0, 150.0], [400.0, 50.0, 150.0])
    for arena in batch.arenas:
        arena.ball.set_state(BallState(pos=np.array([0.0, 1000.0, C.BALL_RADIUS]), vel=np.array([0.0, 1500.0, 0.0])))
    batch.step(120)
    assert batch.arenas[0].ball.get_state().pos[1] > 2100.0  # no box in arena 0
    assert batch.arenas[1].ball.get_state().vel[1] < -50.0  # bounced back (and up) off its box
    batch.close()


# ------------------------------------------------------------------ barrier
FIXED_BARRIER = {"difficulty": 0.0, "lift_probability": 0.0}  # ball 2000 out on the axis, barrier 700 in front


def barrier_env(**overrides):
    env = rocketdrl_ma.parallel_env("minigames/barrier.yaml", **{**FIXED_BARRIER, **overrides})
    env.reset(seed=0)
    return env


def test_barrier_is_placed_on_the_ball_goal_line_and_exposed_as_an_obstacle():
    env = barrier_env()
    state = env.unwrapped.rules.game_state()
    (barrier,) = state.obstacles
    assert np.allclose(barrier.center, [0.0, C.ARENA_EXTENT_Y - 2000.0 + 700.0, 150.0])
    assert np.allclose(barrier.half_extents, [400.0, 50.0, 150.0])
    env.close()


def test_barrier_blocks_a_ground_shot_that_scores_without_it():
    env = barrier_env()
    straight_shot(env)
    _, infos = run(env)
    summary = infos["blue_0"]["summary"]
    assert summary["goals"] == 0 and summary["results"][0]["reason"] in ("retreat", "timeout")
    env.close()

    env = barrier_env()  # the same shot with the barrier moved out of the way
    rules = env.unwrapped.rules
    rules.arena.move_static_box(rules.barrier_id, [0.0, -3000.0, 1500.0])
    straight_shot(env)
    rewards, infos = run(env)
    assert infos["blue_0"]["summary"]["goals"] == 1 and rewards[-1] == pytest.approx(10.0 - 0.01)
    env.close()


def rolling_shot(env):
    """The ball rolling on the floor at 2000 uu/s straight at the goal (a low shot); the car far away."""
    place(env, car_pos=(-2500.0, 0.0, C.CAR_SPAWN_REST_Z), ball_pos=(0.0, C.ARENA_EXTENT_Y - 2000.0, C.BALL_RADIUS),
          ball_vel=(0.0, 2000.0, 0.0))


@pytest.mark.parametrize("lift_uu, scores", [(0.0, False), (260.0, True)])
def test_a_lifted_barrier_lets_a_low_shot_pass_under_it(lift_uu, scores):
    lift = {"lift_probability": 1.0, "lift_min_uu": lift_uu, "lift_max_uu": lift_uu}
    env = barrier_env(**lift)
    (barrier,) = env.unwrapped.rules.game_state().obstacles
    assert barrier.center[2] - barrier.half_extents[2] == pytest.approx(lift_uu)
    rolling_shot(env)
    _, infos = run(env, action=IDLE)
    assert infos["blue_0"]["summary"]["goals"] == int(scores)
    env.close()

    env = barrier_env(**lift)  # a car's shot pops the ball up (to ~230 uu here): it hits even the lifted barrier
    straight_shot(env)
    _, infos = run(env)
    assert infos["blue_0"]["summary"]["goals"] == 0
    env.close()


def test_the_curriculum_grows_the_standing_barrier_from_its_easy_height():
    env = barrier_env(easy_barrier_height_uu=60.0)  # difficulty 0: a 300 uu box sunk 240 uu into the floor
    (barrier,) = env.unwrapped.rules.game_state().obstacles
    assert barrier.center[2] + barrier.half_extents[2] == pytest.approx(60.0)
    assert np.allclose(barrier.half_extents, [400.0, 50.0, 150.0])
    straight_shot(env)  # the car pops the ball (~230 uu) over the low wall: the shot the full wall blocks
    _, infos = run(env)
    assert infos["blue_0"]["summary"]["goals"] == 1
    env.close()

    env = barrier_env(easy_barrier_height_uu=60.0, difficulty=1.0, barrier_x_jitter_uu=0.0)
    for seed in range(5):  # at difficulty 1 it is the full wall on the floor, whatever the easy end
        env.reset(seed=seed)
        (barrier,) = env.unwrapped.rules.game_state().obstacles
        assert barrier.center[2] == pytest.approx(150.0)
    env.close()
    with pytest.raises(ValueError, match="easy_barrier_height_uu"):
        barrier_env(easy_barrier_height_uu=301.0)


def test_a_car_bounces_off_the_barrier():
    env = barrier_env()
    (barrier,) = env.unwrapped.rules.game_state().obstacles
    face_y = barrier.center[1] - barrier.half_extents[1]
    place(env, car_pos=(300.0, face_y - 800.0, C.CAR_SPAWN_REST_Z), ball_pos=(-2500.0, 0.0, C.BALL_REST_Z),
          car_vel=(0.0, 1400.0, 0.0))
    max_y = -np.inf
    for _ in range(24):  # one second of throttle into the wall
        env.step({"blue_0": np.array([1.0, 0.0, -1.0, -1.0, -1.0], np.float32)})
        car = env.unwrapped.rules.cars["blue_0"].get_state()
        max_y = max(max_y, car.pos[1])
    assert max_y < face_y  # the car's centre never got to the barrier's face
    assert car.vel[1] < 300.0  # it was stopped (a free car would be near 1400 uu/s)
    env.close()


# ------------------------------------------------------------------ aerial
def aerial_env(**overrides):
    env = rocketdrl_ma.parallel_env("minigames/aerial.yaml", **{"difficulty": 0.0, **overrides})
    env.reset(seed=0)
    return env


def aerial_shot(env):
    """The car airborne at the frozen ball's height (550 uu, car centre 540), 250 uu behind it, flying at the goal."""
    rules = env.unwrapped.rules
    ball = rules.arena.ball.get_state().pos
    rules.cars["blue_0"].set_state(CarState(pos=np.array([0.0, ball[1] - 250.0, ball[2] - 10.0]),
                                            vel=np.array([0.0, 1500.0, 0.0]), rot_mat=yaw_rot_mat(np.pi / 2),
                                            on_ground=False, has_jumped=True))
    env.unwrapped._state = rules.game_state()


def test_aerial_ball_hangs_for_three_seconds_then_a_floor_landing_is_a_miss():
    env = aerial_env(timeout_s=8.0)
    rules = env.unwrapped.rules
    start = rules.arena.ball.get_state().pos
    assert start[2] == pytest.approx(550.0)
    steps_to_release = int(3.0 * C.TICK_RATE_HZ / 5)
    for step in range(steps_to_release):
        obs, *_ = env.step({"blue_0": IDLE})
        state = env.unwrapped._state
        frozen = step < steps_to_release - 1
        assert state.mode_state["ball_frozen"] is frozen and obs["blue_0"][18] == float(frozen)
        if frozen:
            assert np.array_equal(state.ball.pos, start)
    rewards, infos = run(env, action=IDLE)
    summary = infos["blue_0"]["summary"]
    assert summary["results"][0]["reason"] == "ball_on_ground" and rewards[-1] == pytest.approx(-10.01)
    assert summary["results"][0]["time_s"] == pytest.approx(3.0 + np.sqrt(2 * (550.0 - 96.25) / 650.0), abs=0.05)
    env.close()


def test_aerial_touch_then_goal_earns_five_then_ten():
    env = aerial_env()
    aerial_shot(env)
    obs_seen, rewards = [], []
    while env.agents:
        obs, r, _, _, infos = env.step({"blue_0": IDLE})
        obs_seen.append(obs["blue_0"])
        rewards.append(r["blue_0"])
    assert sum(r == pytest.approx(5.0 - 0.01) for r in rewards) == 1 and rewards[-1] == pytest.approx(10.0 - 0.01)
    assert sum(rewards) == pytest.approx(15.0 - 0.01 * len(rewards))
    summary = infos["blue_0"]["summary"]
    assert summary["is_success"] is True and summary["aerial_touches"] == 1
    assert obs_seen[-1][20] == 1.0 and obs_seen[-1][21] == 1.0  # aerial touch done; touched, waiting for reset
    env.close()


def test_a_scripted_double_jump_scores_the_aerial_with_the_seed_actions():
    """Drive at the hanging ball at 600 uu/s, jump 750 uu before it (held 0.21 s), double-jump: the car meets
    the ball near its apex (~440 uu), which is an aerial touch, and knocks it in."""
    env = aerial_env()
    rules = env.unwrapped.rules
    jump_step = None
    for step in range(400):
        if not env.agents:
            break
        car, ball = rules.cars["blue_0"].get_state(), rules.arena.ball.get_state()
        action = np.array([1.0 if car.vel @ car.rot_mat[:, 0] < 600.0 else 0.0, 0.0, -1.0, -1.0, -1.0], np.float32)
        if jump_step is None and np.linalg.norm((ball.pos - car.pos)[:2]) < 750.0:
            jump_step = step
        if jump_step is not None:
            action[2] = 1.0 if step - jump_step < 5 or step - jump_step == 6 else -1.0
        _, rewards, _, _, infos = env.step({"blue_0": action})
    summary = infos["blue_0"]["summary"]
    assert summary["is_success"] is True and summary["aerial_touches"] == 1
    assert any(e.kind == "goal" for e in infos["blue_0"]["events"]) and rewards["blue_0"] == pytest.approx(9.99)
    env.close()


def test_the_aerial_curriculum_starts_from_a_ball_one_jump_reaches():
    easy = {"easy_ball_height_uu": 260.0, "easy_aerial_min_height_uu": 100.0}
    env = aerial_env(**easy)  # difficulty 0: the ball hangs at 260 uu and a car above 100 uu touches in the air
    rules = env.unwrapped.rules
    ball = rules.arena.ball.get_state().pos
    assert ball[2] == pytest.approx(260.0) and rules.aerial_height_needed_uu == pytest.approx(100.0)
    place(env, car_pos=(ball[0], ball[1] - 300.0, C.CAR_SPAWN_REST_Z), ball_pos=ball, car_vel=(0.0, 500.0, 0.0))
    touched_at = None
    for step in range(30):  # roll under the ball and jump (held): the roof meets it on the way up
        jump = 1.0 if step >= 6 else -1.0
        env.step({"blue_0": np.array([0.0, 0.0, jump, -1.0, -1.0], np.float32)})
        if rules.stats["blue_0"]["aerial_touches"]:
            touched_at = step
            break
    assert touched_at is not None and rules.cars["blue_0"].get_state().pos[2] > 100.0
    env.close()

    env = aerial_env(**easy, difficulty=1.0)  # at difficulty 1 it is the seed's task, whatever the easy end
    rules = env.unwrapped.rules
    for seed in range(5):
        env.reset(seed=seed)
        assert 550.0 <= rules.arena.ball.get_state().pos[2] <= 900.0
        assert rules.aerial_height_needed_uu == pytest.approx(400.0)
    env.close()
    with pytest.raises(ValueError, match="easy_aerial_min_height_uu"):
        aerial_env(easy_aerial_min_height_uu=500.0)


def test_aerial_goal_without_an_aerial_touch_does_not_count():
    env = aerial_env(aerial_min_height_uu=600.0)  # the same shot, but the car at 540 uu is now too low
    aerial_shot(env)
    rewards, infos = run(env, action=IDLE)
    summary = infos["blue_0"]["summary"]
    assert summary["results"][0]["reason"] == "goal_not_counted" and summary["aerial_touches"] == 0
    assert all(r == pytest.approx(-0.01) for r in rewards[:-1])  # no +5
    assert rewards[-1] == pytest.approx(-10.01) and summary["goals"] == 0
    env.close()

    env = aerial_env()  # thrown in without any touch
    rules = env.unwrapped.rules
    rules.arena.ball.set_state(BallState(pos=np.array([0.0, 4000.0, 500.0]), vel=np.array([0.0, 2000.0, 0.0])))
    rewards, infos = run(env, action=IDLE)
    assert infos["blue_0"]["summary"]["results"][0]["reason"] == "goal_not_counted"
    env.close()


# ------------------------------------------------------------------ penalty duel
def test_duel_goal_pays_the_shooter_what_the_keeper_loses():
    env = rocketdrl_ma.parallel_env("minigames/penalty_duel.yaml")
    env.reset(seed=0)
    assert env.agents == ["blue_0", "orange_0"]
    keeper = env.unwrapped.rules.game_state().cars["orange_0"]
    assert keeper.pos[1] > C.ARENA_EXTENT_Y - 300.0 and keeper.rot_mat[1, 0] == pytest.approx(-1.0)  # faces out
    place(env, car_pos=(-2500.0, 4000.0, C.CAR_SPAWN_REST_Z), ball_pos=(-2500.0, 4500.0, C.BALL_REST_Z),
          agent="orange_0")  # the keeper parked by the side wall, out of the shot's way
    straight_shot(env)
    shooter, keeper = [], []
    while env.agents:
        _, r, _, _, infos = env.step({"blue_0": DRIVE_BOOST, "orange_0": IDLE})
        shooter.append(r["blue_0"])
        keeper.append(r["orange_0"])
    assert shooter[-1] == pytest.approx(10.0 - 0.01) and keeper[-1] == pytest.approx(-10.0 + 0.01)
    assert all(a == -b for a, b in zip(shooter, keeper))
    assert infos["orange_0"]["summary"]["winner"] == "blue"
    env.close()


def test_duel_keeper_save_wins_the_round_for_the_keeper():
    env = rocketdrl_ma.parallel_env("minigames/penalty_duel.yaml", timeout_s=3.0)
    env.reset(seed=0)
    place(env, car_pos=(0.0, 4870.0, C.CAR_SPAWN_REST_Z), ball_pos=(-3000.0, 0.0, C.BALL_REST_Z), yaw=-np.pi / 2,
          agent="orange_0")
    place(env, car_pos=(-2500.0, 0.0, C.CAR_SPAWN_REST_Z), ball_pos=(0.0, 4000.0, C.BALL_RADIUS),
          ball_vel=(0.0, 2000.0, 0.0))  # an on-target roller straight at the keeper
    rewards, infos = run(env, action=IDLE, agent="orange_0")
    summary = infos["orange_0"]["summary"]
    assert summary["goals"] == 0 and summary["stats"]["orange_0"]["saves"] == 1
    assert rewards[-1] == pytest.approx(10.0 + 0.01) and summary["winner"] == "orange"
    env.close()


# ------------------------------------------------------------------ config validation
@pytest.mark.parametrize("config", ["minigames/penalty.yaml", "minigames/barrier.yaml", "minigames/aerial.yaml",
                                    "minigames/penalty_duel.yaml"])
def test_config_validation_names_unknown_keys_and_bad_values(config):
    with pytest.raises(ValueError, match="ball_distanse_uu"):
        rocketdrl_ma.parallel_env(config, ball_distanse_uu=100.0)
    with pytest.raises(ValueError, match="orange_size"):  # a one-car minigame fixes its teams
        rocketdrl_ma.parallel_env(config, orange_size=2)
    with pytest.raises(ValueError, match="rewards: unknown term 'goals'"):
        rocketdrl_ma.parallel_env(config, rewards={"goals": 1.0})
    with pytest.raises(ValueError, match="difficulty"):
        rocketdrl_ma.parallel_env(config, difficulty=1.5)
    with pytest.raises(ValueError, match="timeout_s"):
        rocketdrl_ma.parallel_env(config, timeout_s=0.0)
    with pytest.raises(ValueError, match="rounds"):
        rocketdrl_ma.parallel_env(config, rounds=0)


def test_barrier_parameters_are_checked():
    with pytest.raises(ValueError, match="lift_min_uu"):
        rocketdrl_ma.parallel_env("minigames/barrier.yaml", lift_min_uu=400.0, lift_max_uu=300.0)
    with pytest.raises(ValueError, match="barrier_distance_max_uu"):
        rocketdrl_ma.parallel_env("minigames/barrier.yaml", barrier_distance_max_uu=1900.0)
    with pytest.raises(ValueError, match="lift_probability"):
        rocketdrl_ma.parallel_env("minigames/barrier.yaml", lift_probability=2.0)
