"""The vectorised env: a game of the batch plays the lone PettingZoo env's game; shapes, auto-reset, errors."""
import numpy as np
import pytest

from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.env.vector_env import VectorEnv

SEED = 7


def _lone_rows(env, values: dict, agents: list[str]) -> np.ndarray:
    return np.stack([values[agent] for agent in agents])


@pytest.mark.parametrize("config, overrides, n_games, game, n_steps", [
    # timeouts of 1 s: a dozen episodes end (terminated) and auto-reset inside the run
    ("minigames/penalty.yaml", {"timeout_s": 1.0}, 3, 2, 90),
    # a static barrier box in each arena of the batch, moved every round
    ("minigames/barrier.yaml", {"timeout_s": 1.0}, 2, 1, 60),
    # a 2v2 match cut at 25 decisions: truncation, auto-reset, four cars colliding
    ("matches/2v2.yaml", {"kickoff_countdown_s": 0.0, "max_cycles": 25, "info_format": "numeric"}, 3, 1, 60),
])
def test_a_game_of_the_batch_plays_the_lone_envs_game(config, overrides, n_games, game, n_steps):
    vec = VectorEnv(config, n_games=n_games, **overrides)
    lone = RocketDRLParallelEnv(config, **overrides)
    agents = vec.possible_agents
    obs, _ = vec.reset(seed=SEED)
    lone_obs, _ = lone.reset(seed=SEED + game)
    np.testing.assert_array_equal(obs[game], _lone_rows(lone, lone_obs, agents))
    rng = np.random.default_rng(0)
    space = vec.action_space
    episodes = 0
    for _ in range(n_steps):
        actions = rng.uniform(space.low, space.high, (n_games, len(agents)) + space.shape).astype(np.float32)
        obs, rewards, terminated, truncated, infos = vec.step(actions)
        lone_obs, lone_rew, lone_term, lone_trunc, lone_infos = lone.step(
            {agent: actions[game, j] for j, agent in enumerate(agents)})
        # Float rounding of positions far from the world's origin is the only difference the physics allows.
        np.testing.assert_allclose(vec.final_obs[game], _lone_rows(lone, lone_obs, agents), atol=1e-4)
        np.testing.assert_allclose(rewards[game], _lone_rows(lone, lone_rew, agents).astype(np.float32), atol=1e-6)
        assert terminated[game] == lone_term[agents[0]] and truncated[game] == lone_trunc[agents[0]]
        if overrides.get("info_format") == "numeric":
            for agent in agents:
                assert infos[game][agent].keys() == lone_infos[agent].keys()
                np.testing.assert_allclose(list(infos[game][agent].values()), list(lone_infos[agent].values()),
                                           atol=1e-4)
        if terminated[game] or truncated[game]:
            episodes += 1
            lone_obs, _ = lone.reset()
            np.testing.assert_allclose(obs[game], _lone_rows(lone, lone_obs, agents), atol=1e-4)
        else:
            np.testing.assert_array_equal(obs[game], vec.final_obs[game])
    assert episodes >= 2
    vec.close()
    lone.close()


def test_shapes_spaces_and_state():
    vec = VectorEnv("matches/2v2.yaml", n_games=4, kickoff_countdown_s=0.0)
    obs, infos = vec.reset(seed=0)
    assert obs.shape == (4, 4, 127) and obs.dtype == np.float32
    assert len(infos) == 4 and set(infos[0]) == {"blue_0", "blue_1", "orange_0", "orange_1"}
    assert vec.action_space.shape == (8,)
    obs, rewards, terminated, truncated, infos = vec.step(np.zeros((4, 4, 8), np.float32))
    assert rewards.shape == (4, 4) and terminated.shape == (4,) and truncated.dtype == bool
    assert all(vec.observation_space.contains(row) for row in obs.reshape(16, -1))
    assert vec.state().shape == (4,) + vec.games[0].state_space.shape
    vec.close()


def test_without_autoreset_an_ended_game_waits_for_its_reset():
    vec = VectorEnv("matches/1v1.yaml", n_games=2, autoreset=False, kickoff_countdown_s=0.0, max_cycles=2)
    vec.reset(seed=0)
    actions = np.zeros((2, 2, 8), np.float32)
    vec.step(actions)
    _, _, _, truncated, _ = vec.step(actions)
    assert truncated.all()
    with pytest.raises(ValueError, match="reset_games"):
        vec.step(actions)
    obs, infos = vec.reset_games(np.array([True, False]))
    assert infos[1] is None and set(infos[0]) == {"blue_0", "orange_0"}
    with pytest.raises(ValueError, match=r"games \[1\]"):
        vec.step(actions)
    vec.reset_games(np.array([False, True]))
    vec.step(actions)
    vec.close()


def test_bad_input_names_the_field():
    with pytest.raises(ValueError, match="n_games"):
        VectorEnv("matches/1v1.yaml", n_games=0)
    vec = VectorEnv("matches/1v1.yaml", n_games=2)
    with pytest.raises(ValueError, match="step: the games"):
        vec.step(np.zeros((2, 2, 8), np.float32))
    vec.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions: expected shape \(2, 2, 8\)"):
        vec.step(np.zeros((2, 8), np.float32))
    bad = np.zeros((2, 2, 8), np.float32)
    bad[1, 0, 0] = np.nan
    with pytest.raises(ValueError, match="blue_0"):
        vec.step(bad)
    with pytest.raises(ValueError, match="mask"):
        vec.reset_games(np.ones(3, bool))
    vec.close()


def test_a_used_vector_env_replays_a_new_ones_games_after_a_seeded_reset():
    """A seeded reset moves the batch onto a new PyBullet world: 400 decisions of four colliding cars in each of two
    arenas, after 300 of other games, come out as a new VectorEnv plays them."""
    overrides = {"kickoff_countdown_s": 0.0}
    used, new = VectorEnv("matches/2v2.yaml", n_games=2, **overrides), VectorEnv("matches/2v2.yaml", n_games=2,
                                                                                    **overrides)
    space = used.action_space
    rng = np.random.default_rng(4)

    def random_actions() -> np.ndarray:
        return rng.uniform(space.low, space.high, (2, used.n_agents) + space.shape).astype(np.float32)

    used.reset(seed=1)
    for _ in range(300):
        used.step(random_actions())
    obs = [used.reset(seed=SEED)[0], new.reset(seed=SEED)[0]]
    for step in range(400):
        np.testing.assert_array_equal(obs[0], obs[1], err_msg=f"decision {step}")
        actions = random_actions()
        obs = [used.step(actions)[0], new.step(actions)[0]]
    used.close()
    new.close()
