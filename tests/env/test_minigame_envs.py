"""Every minigame through the PettingZoo env: PettingZoo's own tests, determinism, numeric infos, sensors."""
import numpy as np
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test, state_test
from pettingzoo.utils.conversions import parallel_to_aec

import rocketdrl_ma
from rocketdrl_ma.env.observations import ARENA_DIAGONAL, RAY_CLASSES
from rocketdrl_ma.physics import BallState, CarState, yaw_rot_mat
from rocketdrl_ma.physics import constants as C

CONFIGS = ["minigames/penalty.yaml", "minigames/barrier.yaml", "minigames/aerial.yaml", "minigames/penalty_duel.yaml"]
SHORT = {"timeout_s": 3.0}  # short rounds: the tests see many episodes end


@pytest.mark.parametrize("config", CONFIGS)
def test_parallel_api(config):
    env = rocketdrl_ma.parallel_env(config, **SHORT)
    parallel_api_test(env, num_cycles=200)
    env.close()


@pytest.mark.parametrize("config", CONFIGS)
def test_aec_api(config):
    env = rocketdrl_ma.env(config, **SHORT)
    api_test(env, num_cycles=200)
    env.close()


@pytest.mark.parametrize("config", CONFIGS)
def test_parallel_seed(config):
    parallel_seed_test(lambda: rocketdrl_ma.parallel_env(config, **SHORT), num_cycles=50)


@pytest.mark.parametrize("config", CONFIGS)
def test_state(config):
    par = rocketdrl_ma.parallel_env(config, **SHORT)
    aec = parallel_to_aec(rocketdrl_ma.parallel_env(config, **SHORT))
    state_test(aec, par)
    par.close()
    aec.close()


@pytest.mark.parametrize("config", CONFIGS)
def test_same_seed_and_actions_give_the_same_episodes(config):
    """Spawns, barrier placement and outcomes are a function of the seed (parallel_seed_test checks one step)."""
    envs = [rocketdrl_ma.parallel_env(config, **SHORT) for _ in range(2)]
    rng = np.random.default_rng(0)
    for episode in range(3):
        obs = [e.reset(seed=episode)[0] for e in envs]
        assert all(np.array_equal(obs[0][a], obs[1][a]) for a in obs[0])
        while envs[0].agents:
            actions = {a: rng.uniform(-1, 1, envs[0].action_space(a).shape).astype(np.float32)
                       for a in envs[0].agents}
            outs = [e.step(actions) for e in envs]
            for a in actions:
                assert np.array_equal(outs[0][0][a], outs[1][0][a])
                assert outs[0][1][a] == outs[1][1][a]
        assert envs[1].agents == []
    for e in envs:
        e.close()


@pytest.mark.parametrize("config", CONFIGS)
def test_numeric_infos_keep_their_keys_and_report_success_at_the_end(config):
    env = rocketdrl_ma.parallel_env(config, info_format="numeric", timeout_s=1.0)
    _, infos = env.reset(seed=0)
    keys = {a: set(info) for a, info in infos.items()}
    assert {"goals", "misses", "is_success", "success_rate", "rounds_played", "clock_s"} <= keys["blue_0"]
    rng = np.random.default_rng(1)
    while env.agents:
        actions = {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}
        _, _, _, _, infos = env.step(actions)
        for a, info in infos.items():
            assert set(info) == keys[a] and all(isinstance(v, float) for v in info.values())
    assert infos["blue_0"]["rounds_played"] == 1.0
    assert infos["blue_0"]["goals"] + infos["blue_0"]["misses"] == 1.0
    env.close()


def test_barrier_sensors_see_the_barrier():
    """barrier_sensors's barrier -> ball vector, and the rays' barrier class, on a barrier 700 uu in front of the ball."""
    env = rocketdrl_ma.parallel_env("minigames/barrier.yaml", difficulty=0.0, lift_probability=0.0)
    obs, _ = env.reset(seed=0)
    rules = env.unwrapped.rules
    (barrier,) = rules.game_state().obstacles
    ball = rules.arena.ball.get_state().pos
    assert env.observation_space("blue_0").shape == (21 + 40,)
    assert np.allclose(obs["blue_0"][18:21], (ball - barrier.center) / ARENA_DIAGONAL, atol=1e-6)
    # the car 1000 uu in front of the barrier's face, facing it, the ball out of the way
    face_y = barrier.center[1] - barrier.half_extents[1]
    rules.cars["blue_0"].set_state(CarState(pos=np.array([0.0, face_y - 1000.0, C.CAR_SPAWN_REST_Z]),
                                            rot_mat=yaw_rot_mat(np.pi / 2), on_ground=True))
    rules.arena.ball.set_state(BallState(pos=np.array([-3000.0, 0.0, C.BALL_RADIUS])))
    obs = env.step({"blue_0": np.zeros(5, np.float32)})[0]["blue_0"]
    rays = obs[21:].reshape(8, 5)
    barrier_rays = rays[rays[:, 1 + RAY_CLASSES.index("barrier")] == 1.0]
    assert len(barrier_rays) >= 2
    assert barrier_rays[:, 0].min() == pytest.approx(1000.0 / np.cos(np.radians(5.0)) / 4000.0, rel=0.02)
    env.close()


@pytest.mark.parametrize("config", CONFIGS)
def test_every_minigame_ends_by_its_timeout(config):
    """Doing nothing never keeps an episode going: each round ends by its timeout at the latest."""
    env = rocketdrl_ma.parallel_env(config, timeout_s=1.5, rounds=2)
    env.reset(seed=0)
    idle = np.zeros(env.action_space("blue_0").shape, np.float32)
    steps = 0
    while env.agents:
        _, _, terminations, truncations, infos = env.step({a: idle for a in env.agents})
        steps += 1
    assert all(terminations.values()) and not any(truncations.values())
    assert steps <= 2 * 1.5 * C.TICK_RATE_HZ / env.unwrapped.tick_skip
    assert infos["blue_0"]["summary"]["rounds_played"] == 2
    env.close()


def test_play_command_runs_a_minigame():
    from rocketdrl_ma.cli import play
    summary = play("minigames/penalty_duel.yaml", "ball_chaser", "goalie", video=None, seed=0, clock_s=None,
                   quiet=True)
    assert summary["rounds_played"] == 1 and summary["goals"] + summary["misses"] == 1
    assert set(summary["stats"]) == {"blue_0", "orange_0"}


def test_barrier_is_rendered():
    env = rocketdrl_ma.parallel_env("minigames/barrier.yaml", render_mode="rgb_array", difficulty=0.0,
                                    lift_probability=0.0)
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3
    assert np.array_equal(env.render(), frame)  # the same state draws the same picture
    env.unwrapped.rules.obstacles = ()
    env.unwrapped._state = env.unwrapped.rules.game_state()
    assert not np.array_equal(env.render(), frame)  # the barrier was in the picture
    env.close()


def test_minigame_sensors_read_zeros_outside_their_minigame():
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", kickoff_countdown_s=0.0, observation="barrier_sensors+aerial_sensors")
    obs, _ = env.reset(seed=0)
    assert env.observation_space("blue_0").shape == (21 + 22,)
    for _ in range(5):
        for agent, o in obs.items():
            assert env.observation_space(agent).contains(o)
            assert not o[18:21].any() and not o[21 + 18:].any()
        obs = env.step({a: env.action_space(a).sample() for a in env.agents})[0]
    env.close()
