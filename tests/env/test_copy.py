"""Copies of envs (``copy.deepcopy``, ``pickle``, ``cloudpickle``) are independent envs in the same state: their own
PyBullet world, the same observations and, under the same actions, the same future bit for bit. Also through the
clients that copy envs for you: SuperSuit's ``concat_vec_envs_v1`` and torchrl's multi-process collectors."""
import copy
import functools
import gc
import os
import pickle

import cloudpickle
import numpy as np
import pytest

import rocketdrl_ma
from rocketdrl_ma.env.vector_env import VectorEnv

COPIERS = {"deepcopy": copy.deepcopy, "pickle": lambda env: pickle.loads(pickle.dumps(env)),
           "cloudpickle": lambda env: cloudpickle.loads(cloudpickle.dumps(env))}


def random_actions(env, rng: np.random.Generator) -> dict:
    return {agent: env.action_space(agent).sample() if env.action_space(agent).shape == ()
            else rng.uniform(-1.0, 1.0, env.action_space(agent).shape).astype(np.float32)
            for agent in env.possible_agents}


def play(env, rng: np.random.Generator, decisions: int) -> None:
    for _ in range(decisions):
        if not env.agents:
            env.reset()
        env.step(random_actions(env, rng))


def assert_same_future(a, b, rng: np.random.Generator, decisions: int, same_infos: bool = True) -> None:
    """Step both with the same actions (resetting both, unseeded, when the episode ends): everything they return
    is equal, bit for bit (``same_infos=False``: all but the infos, whose event ticks count the world's ticks since
    it was made, not the episode's)."""
    for t in range(decisions):
        if not a.agents:
            assert not b.agents
            (obs_a, info_a), (obs_b, info_b) = a.reset(), b.reset()
            rewards_a = rewards_b = {}
        else:
            actions = random_actions(a, rng)
            obs_a, rewards_a, term_a, trunc_a, info_a = a.step(actions)
            obs_b, rewards_b, term_b, trunc_b, info_b = b.step(actions)
            assert (term_a, trunc_a) == (term_b, trunc_b), t
        assert obs_a.keys() == obs_b.keys()
        for agent in obs_a:
            np.testing.assert_array_equal(obs_a[agent], obs_b[agent], err_msg=f"decision {t}, {agent}")
        assert rewards_a == rewards_b, t
        assert info_a == info_b or not same_infos, t
    np.testing.assert_array_equal(a.state(), b.state())


# Configs and how long the original played first: right after a reset, mid-kickoff, in the middle of contacts
# (a 4v4 after bumps and wall play), across minigame rounds with a barrier box moved between them.
CASES = [("matches/1v1.yaml", 0), ("matches/2v2.yaml", 37), ("matches/4v4.yaml", 400),
         ("minigames/barrier.yaml", 150), ("minigames/aerial.yaml", 61), ("minigames/penalty_duel.yaml", 90)]


@pytest.mark.parametrize("how", list(COPIERS))
@pytest.mark.parametrize("config,played", CASES[:3])
def test_a_copy_of_a_played_env_has_its_state_and_its_future(config, played, how):
    rng = np.random.default_rng(played)
    env = rocketdrl_ma.parallel_env(config)
    env.reset(seed=11)
    play(env, rng, played)
    clone = COPIERS[how](env)
    assert clone.rules.arena.batch.client != env.rules.arena.batch.client  # a PyBullet world of its own
    assert clone.agents == env.agents
    np.testing.assert_array_equal(clone.state(), env.state())
    assert_same_future(env, clone, rng, 250)
    env.close()
    clone.close()


@pytest.mark.slow
@pytest.mark.parametrize("config,played", CASES[3:])
def test_minigame_copies_go_on_identically_across_rounds(config, played):
    rng = np.random.default_rng(played)
    env = rocketdrl_ma.parallel_env(config)
    env.reset(seed=5)
    play(env, rng, played)
    clone = pickle.loads(pickle.dumps(env))
    assert_same_future(env, clone, rng, 400)
    env.close()
    clone.close()


def test_a_copy_is_independent_and_deleting_it_leaves_the_original_working():
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", kickoff_countdown_s=0.0)
    env.reset(seed=2)
    rng = np.random.default_rng(0)
    play(env, rng, 20)
    before = env.state()
    clone = copy.deepcopy(env)
    play(clone, rng, 30)  # the copy moves on; the original is where it was
    np.testing.assert_array_equal(env.state(), before)
    twin = pickle.loads(pickle.dumps(env))
    del clone
    gc.collect()
    assert_same_future(env, twin, rng, 20)  # the original still steps (its PyBullet world is connected)
    env.close()
    twin.close()


def test_a_copy_of_an_env_never_reset_and_a_copy_of_a_reset_env_reset_with_a_seed_play_a_fresh_game():
    template = rocketdrl_ma.parallel_env("matches/2v2.yaml")
    unreset = copy.deepcopy(template)
    template.reset(seed=0)
    play(template, np.random.default_rng(1), 50)
    used = pickle.loads(pickle.dumps(template))
    fresh = rocketdrl_ma.parallel_env("matches/2v2.yaml")
    for env in (unreset, used, fresh):
        env.reset(seed=9)
    rng = np.random.default_rng(3)
    fresh_twin = copy.deepcopy(fresh)
    for env in (unreset, used):
        assert_same_future(copy.deepcopy(fresh_twin), env, np.random.default_rng(3), 120, same_infos=False)
    assert_same_future(fresh, fresh_twin, rng, 5)
    for env in (template, unreset, used, fresh, fresh_twin):
        env.close()


def test_a_copy_does_not_take_the_recording_or_the_renderer(tmp_path):
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", render_mode="rgb_array")
    env.reset(seed=0)
    env.render()
    env.start_replay(tmp_path / "original.npz")
    clone = copy.deepcopy(env)
    assert clone._replay is None and clone._renderer is None
    assert clone.render().shape == env.render().shape  # the copy draws with a renderer of its own
    env.step({agent: np.zeros(8, np.float32) for agent in env.agents})
    env.close()
    clone.close()
    assert (tmp_path / "original.npz").is_file()


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_vector_env_copies_with_every_arena(how):
    vec = VectorEnv("matches/2v2.yaml", n_games=3)
    vec.reset(seed=4)
    rng = np.random.default_rng(0)
    shape = (vec.n_games, vec.n_agents) + vec.action_space.shape
    for _ in range(60):
        vec.step(rng.uniform(-1, 1, shape).astype(np.float32))
    clone = COPIERS[how](vec)
    assert clone.batch.client != vec.batch.client
    assert all(game.rules.arena.batch is clone.batch for game in clone.games)
    for t in range(200):
        actions = rng.uniform(-1, 1, shape).astype(np.float32)
        obs_a, rew_a, term_a, trunc_a, _ = vec.step(actions)
        obs_b, rew_b, term_b, trunc_b, _ = clone.step(actions)
        np.testing.assert_array_equal(obs_a, obs_b, err_msg=f"decision {t}")
        np.testing.assert_array_equal(rew_a, rew_b)
        np.testing.assert_array_equal(term_a | trunc_a, term_b | trunc_b)
    vec.close()
    clone.close()


# In worker processes SuperSuit seeds process i's envs seed + i + j (its j-th env): one env per process keeps the
# lone envs' seeds seed + k.
@pytest.mark.parametrize("num_cpus,n_copies", [(0, 3), (2, 2)])
def test_supersuit_concat_vec_envs_of_a_reset_env_equals_lone_envs(num_cpus, n_copies):
    import supersuit as ss  # the test extra installs it: a missing SuperSuit is a failure, not a skip
    config = dict(config="matches/2v2.yaml", max_cycles=40)  # episodes end inside the test: autoreset too
    template = rocketdrl_ma.parallel_env(**config)
    template.reset(seed=123)
    play(template, np.random.default_rng(0), 10)  # a used env: its copies are what SuperSuit steps
    seed = 50
    vec = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(template), n_copies, num_cpus=num_cpus,
                                base_class="gymnasium")
    lones = [rocketdrl_ma.parallel_env(**config) for _ in range(n_copies)]
    try:
        obs, _ = vec.reset(seed=seed)
        lone_obs = [lone.reset(seed=seed + i)[0] for i, lone in enumerate(lones)]
        agents = template.possible_agents
        rng = np.random.default_rng(1)
        for t in range(90):
            expected = np.concatenate([np.stack([o[a] for a in agents]) for o in lone_obs])
            np.testing.assert_array_equal(obs, expected, err_msg=f"decision {t}")
            actions = rng.uniform(-1, 1, (n_copies * len(agents), 8)).astype(np.float32)
            obs, rewards, terms, truncs, _ = vec.step(actions)
            lone_obs = []
            for i, lone in enumerate(lones):
                rows = actions[i * len(agents):(i + 1) * len(agents)]
                o, r, *_ = lone.step(dict(zip(agents, rows)))
                np.testing.assert_array_equal(rewards[i * len(agents):(i + 1) * len(agents)],
                                              [r[a] for a in agents])
                lone_obs.append(o if lone.agents else lone.reset()[0])  # SuperSuit resets an ended env at once
    finally:
        vec.close()
        for env in (template, *lones):
            env.close()


def _linear_policy(n_obs: int):
    import torch
    from tensordict.nn import TensorDictModule
    torch.manual_seed(0)
    net = torch.nn.Sequential(torch.nn.Linear(n_obs, 8), torch.nn.Tanh())
    return TensorDictModule(net, in_keys=[("agents", "observation")], out_keys=[("agents", "action")])


def test_torchrl_env_copies_and_multisync_collector_given_env_objects_or_factories():
    torch = pytest.importorskip("torch")
    pytest.importorskip("torchrl")
    os.environ.setdefault("RL_WARNINGS", "0")
    from torchrl.collectors import MultiSyncCollector

    from rocketdrl_ma.env.torchrl_env import RocketDRLTorchEnv

    factory = functools.partial(RocketDRLTorchEnv, "matches/1v1.yaml", n_games=2, kickoff_countdown_s=0.0)
    env = factory()
    env.set_seed(0)
    env.rollout(7)
    # A copy of the torchrl env goes on as the original does.
    clone = pickle.loads(pickle.dumps(env))
    policy = _linear_policy(env.full_observation_spec["agents", "observation"].shape[-1])
    a = env.rollout(30, policy=policy, auto_reset=False, break_when_any_done=False, tensordict=env.reset())
    b = clone.rollout(30, policy=policy, auto_reset=False, break_when_any_done=False, tensordict=clone.reset())
    torch.testing.assert_close(a, b, rtol=0, atol=0)
    clone.close()

    def collect(create_env_fn) -> list:
        collector = MultiSyncCollector(create_env_fn, policy=policy, frames_per_batch=40, total_frames=80)
        collector.set_seed(7)
        try:
            return [batch.get(("next", "agents", "observation")).clone() for batch in collector]
        finally:
            collector.shutdown()

    from_objects = collect([env, env])  # each worker gets a copy of env with a PyBullet world of its own
    from_factories = collect([factory, factory])
    assert len(from_objects) == len(from_factories) == 2
    for x, y in zip(from_objects, from_factories):
        assert x.abs().sum() > 0
        torch.testing.assert_close(x, y, rtol=0, atol=0)
    assert env.rollout(3).batch_size == (2, 3)  # the original still steps in this process
    env.close()


def test_an_arena_batch_copies_after_cars_and_boxes_came_and_went():
    """The physics hook under the env's copies: a world's bodies are made again in their order (removals too), so a
    copy has the same body ids and steps as the original does."""
    from rocketdrl_ma.physics import ArenaBatch, CarControls
    batch = ArenaBatch(2, seed=0)
    cars = [batch.arenas[k % 2].add_car(team=k % 2) for k in range(4)]
    box = batch.arenas[0].add_static_box([0.0, -3000.0, 100.0], [400.0, 50.0, 100.0])
    batch.arenas[1].add_static_box([0.0, 3000.0, 100.0], [400.0, 50.0, 100.0])
    batch.arenas[0].remove_car(cars[2])
    batch.arenas[0].remove_static_box(box)
    batch.arenas[0].add_car(team=1, preset="dominus")
    for arena in batch.arenas:
        arena.reset_kickoff(seed=1)
    for car in (c for arena in batch.arenas for c in arena.cars):
        car.set_controls(CarControls(throttle=1.0, steer=0.3, boost=True))
    batch.step(90)
    clone = copy.deepcopy(batch)
    assert clone.pybullet_car_bodies() == batch.pybullet_car_bodies() and clone.client != batch.client
    for _ in range(3):
        batch.step(40)
        clone.step(40)
        for name, a, b in zip(batch.arrays()._fields, batch.arrays(), clone.arrays()):
            np.testing.assert_array_equal(a, b, err_msg=name)
    clone.close()
    batch.step(1)  # the original's PyBullet world is its own
    batch.close()


def test_the_aec_env_copies_too():
    aec = rocketdrl_ma.env("matches/1v1.yaml", kickoff_countdown_s=0.0)
    aec.reset(seed=3)
    rng = np.random.default_rng(0)
    for _ in range(30):
        aec.step(rng.uniform(-1, 1, 8).astype(np.float32))
    clone = copy.deepcopy(aec)
    for _ in range(60):
        assert clone.agent_selection == aec.agent_selection
        np.testing.assert_array_equal(clone.observe(aec.agent_selection), aec.observe(aec.agent_selection))
        action = rng.uniform(-1, 1, 8).astype(np.float32)
        aec.step(action)
        clone.step(action)
    aec.close()
    clone.close()


def test_a_closed_env_copies_as_a_closed_env_that_a_reset_brings_back():
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml")
    env.reset(seed=1)
    env.close()
    clone = pickle.loads(pickle.dumps(env))
    fresh = rocketdrl_ma.parallel_env("matches/1v1.yaml")
    obs_clone, _ = clone.reset(seed=6)
    obs_fresh, _ = fresh.reset(seed=6)
    np.testing.assert_array_equal(obs_clone["blue_0"], obs_fresh["blue_0"])
    assert_same_future(clone, fresh, np.random.default_rng(0), 20)
    clone.close()
    fresh.close()


@pytest.mark.slow
def test_torchrl_pettingzoo_wrapper_objects_in_a_multisync_collector():
    pytest.importorskip("torchrl")
    os.environ.setdefault("RL_WARNINGS", "0")
    from torchrl.collectors import MultiSyncCollector
    from torchrl.envs import PettingZooWrapper

    env = PettingZooWrapper(rocketdrl_ma.parallel_env("matches/1v1.yaml", info_format="numeric",
                                                      kickoff_countdown_s=0.0), return_state=True, use_mask=True)
    env.set_seed(0)
    env.rollout(3)
    collector = MultiSyncCollector([env, env], policy=None, frames_per_batch=20, total_frames=40)
    try:
        batches = [batch for batch in collector]
    finally:
        collector.shutdown()
    assert len(batches) == 2 and all(b.batch_size == (2, 10) for b in batches)
    for batch in batches:  # every worker's own world stepped: observations move within each worker's rollout
        obs = batch.get(("next", "blue", "observation"))
        assert (obs[:, 1:] != obs[:, :-1]).any(dim=-1).all()
    assert env.rollout(2).batch_size == (2,)
    env.close()
