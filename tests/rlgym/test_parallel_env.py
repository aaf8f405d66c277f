"""``RLGymParallelEnv`` on our engine and on RocketSim's: PettingZoo's own tests plus multi-step determinism."""
import numpy as np
import pytest
from gymnasium import spaces
from pettingzoo.test import parallel_api_test, parallel_seed_test
from rlgym.rocket_league.done_conditions import GoalCondition, TimeoutCondition

from rlgym_helpers import SceneMutator, new_car, readme_env, scene_env
from rocketdrl_ma.rlgym import RLGymParallelEnv, RocketDRLEngine, gymnasium_space

ENGINES = ["ours", "rocketsim"]


@pytest.fixture
def make_engine(rocketsim_engine_cls):
    return {"ours": RocketDRLEngine, "rocketsim": rocketsim_engine_cls}.__getitem__


def readme_parallel_env(engine_cls, team_size=2):
    return RLGymParallelEnv(readme_env(engine_cls(), team_size))


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("team_size", [1, 2])
def test_parallel_api(make_engine, engine, team_size):
    env = readme_parallel_env(make_engine(engine), team_size)
    assert env.possible_agents == [f"{team}-{i}" for team in ("blue", "orange") for i in range(team_size)]
    assert env.observation_space("blue-0") == spaces.Box(-np.inf, np.inf, (52 + 40 * team_size,), np.float32)
    assert env.action_space("blue-0") == spaces.Discrete(90)
    parallel_api_test(env, num_cycles=200)
    env.close()


@pytest.mark.parametrize("engine", ENGINES)
def test_parallel_seed(make_engine, engine):
    parallel_seed_test(lambda: readme_parallel_env(make_engine(engine)), num_cycles=50)


def rollout(env, seed, steps):
    """Observations, rewards and flags of ``steps`` steps with seeded random actions, across episode ends."""
    rng = np.random.default_rng(seed)
    obs, _ = env.reset(seed=seed)
    log = [obs]
    for _ in range(steps):
        if not env.agents:
            obs, _ = env.reset()
            log.append(obs)
            continue
        actions = {a: int(rng.integers(env.action_space(a).n)) for a in env.agents}
        log.append(env.step(actions)[:4])
    return log


def assert_same(a, b):
    if isinstance(a, dict):
        assert list(a) == list(b)
        for key in a:
            assert_same(a[key], b[key])
    elif isinstance(a, (tuple, list)):
        for x, y in zip(a, b, strict=True):
            assert_same(x, y)
    else:
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("engine", ENGINES)
def test_multi_step_determinism(make_engine, engine):
    """Two envs with one seed play the same 400 steps (several short episodes) bit for bit; another seed differs."""
    def make():
        env = readme_env(make_engine(engine)())
        env.truncation_cond = TimeoutCondition(6.0)
        return RLGymParallelEnv(env)
    first, second, other = make(), make(), make()
    a, b = rollout(first, 7, 400), rollout(second, 7, 400)
    assert sum(isinstance(entry, dict) for entry in a) >= 4  # the episodes ended and restarted
    assert_same(a, b)
    c = rollout(other, 8, 400)
    with pytest.raises(AssertionError):
        assert_same(a, c)


def test_episode_end_removes_every_agent():
    """A goal terminates the scorers' episode; RLGym's episode is over for everyone, so all agents leave."""
    scene = SceneMutator({"blue": new_car(0, (-2500, 0, 17.01)), "orange": new_car(1, (2500, 0, 17.01))},
                         (0, 4900, 93.15), (0, 2500, 0))
    env = RLGymParallelEnv(scene_env(RocketDRLEngine(), scene, termination_cond=GoalCondition(),
                                     truncation_cond=TimeoutCondition(10.0)))
    assert isinstance(env.observation_space("blue"), spaces.Box)
    assert isinstance(env.action_space("blue"), spaces.Box)
    env.reset(seed=0)
    for _ in range(10):
        obs, rewards, terminations, truncations, infos = env.step({a: np.zeros(8, np.float32) for a in env.agents})
        if not env.agents:
            break
    assert terminations == {"blue": True, "orange": True} and truncations == {"blue": False, "orange": False}
    assert env.rlgym_state.goal_scored
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
    env.reset()
    assert env.agents == ["blue", "orange"]


def test_spaces_and_bad_input():
    assert gymnasium_space(("real", 4)) == spaces.Box(-np.inf, np.inf, (4,), np.float32)
    assert gymnasium_space(("discrete", 3)) == spaces.Discrete(3)
    assert gymnasium_space(("multi_discrete", [3, 2])) == spaces.MultiDiscrete([3, 2])
    with pytest.raises(ValueError, match="after a reset"):
        gymnasium_space(("real", -1), "observation_space('blue-0')")
    with pytest.raises(ValueError, match="rlgym_env"):
        RLGymParallelEnv(object())
    with pytest.raises(ValueError, match="render_mode"):
        RLGymParallelEnv(readme_env(RocketDRLEngine(), 1), render_mode="ansi")
    with pytest.raises(ValueError, match="rgb_renderer"):
        RLGymParallelEnv(readme_env(RocketDRLEngine(), 1), rgb_renderer=object())
    env = RLGymParallelEnv(readme_env(RocketDRLEngine(), 1))
    env.reset(seed=1)
    with pytest.raises(ValueError, match=r"missing for agents \['orange-0'\]"):
        env.step({"blue-0": 0})
