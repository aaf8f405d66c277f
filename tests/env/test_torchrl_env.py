"""The torchrl EnvBase over the vectorised env: torchrl's own spec check and real rollouts with partial resets."""
import os

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("torchrl")
os.environ.setdefault("RL_WARNINGS", "0")

from torchrl.envs.utils import check_env_specs  # noqa: E402

from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv  # noqa: E402
from rocketdrl_ma.env.torchrl_env import RocketDRLTorchEnv  # noqa: E402


def test_specs_and_a_rollout_across_episode_ends():
    env = RocketDRLTorchEnv("matches/2v2.yaml", n_games=3, kickoff_countdown_s=0.0, max_cycles=5)
    env.set_seed(3)
    td = env.rollout(12, break_when_any_done=False)
    assert td.batch_size == (3, 12)
    assert td.get(("agents", "observation")).shape == (3, 12, 4, 127)
    assert td.get(("next", "agents", "reward")).shape == (3, 12, 4, 1)
    assert td.get(("next", "state")).shape[:2] == (3, 12)
    done = td.get(("next", "done")).squeeze(-1)
    expected = torch.zeros(12, dtype=torch.bool)
    expected[[4, 9]] = True  # max_cycles 5: truncated every 5th step, then torchrl resets the arena
    assert (done == expected).all() and (td.get(("next", "truncated")).squeeze(-1) == expected).all()
    assert env.full_observation_spec.is_in(td[:, 7].exclude("next", "done", "terminated", "truncated"))
    # set_seed(3) on a fresh env: arena 1 starts the game a fresh lone env reset with seed 3 + 1 starts.
    lone = RocketDRLParallelEnv("matches/2v2.yaml", kickoff_countdown_s=0.0, max_cycles=5)
    lone_obs, _ = lone.reset(seed=4)
    np.testing.assert_allclose(td.get(("agents", "observation"))[1, 0].numpy(),
                               np.stack([lone_obs[a] for a in env.possible_agents]), atol=1e-6)
    lone.close()
    check_env_specs(env)
    env.close()


def test_discrete_lookup_actions_become_a_categorical_spec():
    env = RocketDRLTorchEnv("matches/1v1.yaml", n_games=2, kickoff_countdown_s=0.0, action="lookup")
    check_env_specs(env)
    td = env.rollout(4)
    actions = td.get(("agents", "action"))
    assert actions.shape == (2, 4, 2) and actions.dtype == torch.int64
    assert torch.isfinite(td.get(("next", "agents", "observation"))).all()
    env.close()
