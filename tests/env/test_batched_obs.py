"""VectorEnv's batched team-relative observations equal the reference builder's (one agent, one state), bit for bit."""
import numpy as np
import pytest

from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.policies.scripted import BallChaser


@pytest.mark.parametrize("config, overrides", [
    # short clock, overtime and kickoff countdowns: kickoff_pending, the clock, episode ends
    ("matches/1v1.yaml", {"clock_s": 6.0, "overtime_limit_s": 2.0, "kickoff_countdown_s": 0.5}),
    # teammates and four cars bumping
    ("matches/2v2.yaml", {"kickoff_countdown_s": 0.0, "max_cycles": 60}),
])
def test_batched_observations_equal_the_reference_builder(config, overrides):
    vec = VectorEnv(config, n_games=3, autoreset=False, **overrides)
    assert vec._batched_obs is not None
    agents = vec.possible_agents
    vec.reset(seed=3)
    rng = np.random.default_rng(0)
    chaser = BallChaser()
    seen = {"kickoff_pending": 0, "ended": 0}
    for step in range(200):
        actions = rng.uniform(-1.0, 1.0, (vec.n_games, len(agents), 8)).astype(np.float32)
        if step % 4:  # mostly ball chasing, so that touches and bumps happen
            for k, game in enumerate(vec.games):
                for j, agent in enumerate(agents):
                    actions[k, j] = game.action_parser.encode(chaser.controls(agent, game.game_state))
        obs, _, terminated, truncated, _ = vec.step(actions)
        for k, game in enumerate(vec.games):
            state = game.game_state
            reference = np.stack([game.obs_builder.build(agent, state) for agent in agents])
            np.testing.assert_array_equal(obs[k], reference)
            seen["kickoff_pending"] += state.kickoff_pending
        done = terminated | truncated
        seen["ended"] += int(done.sum())
        if done.any():
            vec.reset_games(done)
    assert seen["ended"] > 0
    if config == "matches/1v1.yaml":
        assert seen["kickoff_pending"] > 0
    # A score difference (goals are rare in 200 decisions): each game's state carries its own score.
    for k, game in enumerate(vec.games):
        game.rules.score = [k, 2]
        game._state = game.rules.game_state()
    batched = vec._all_observations()
    for k, game in enumerate(vec.games):
        reference = np.stack([game.obs_builder.build(agent, game.game_state) for agent in agents])
        np.testing.assert_array_equal(batched[k], reference)
    vec.close()
