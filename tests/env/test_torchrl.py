"""torchrl's PettingZooWrapper drives the env: a rollout runs and the teams become groups."""
import os

import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("torchrl")

os.environ.setdefault("RL_WARNINGS", "0")


def test_pettingzoo_wrapper_rollout_groups_teams():
    from torchrl.envs import PettingZooWrapper

    import rocketdrl_ma

    env = PettingZooWrapper(rocketdrl_ma.parallel_env("matches/2v2.yaml", kickoff_countdown_s=0.0, max_cycles=50,
                                                     info_format="numeric"),
                            return_state=True, use_mask=True)
    assert set(env.group_map) == {"blue", "orange"}
    assert env.group_map["blue"] == ["blue_0", "blue_1"]
    td = env.rollout(20)
    assert td.batch_size[0] == 20
    obs = td.get(("blue", "observation"))
    assert obs.shape[:2] == (20, 2) and torch.isfinite(obs).all()
    assert td.get(("next", "orange", "reward")).shape == (20, 2, 1)
    assert td.get("state").shape[0] == 20
    assert td.get(("next", "blue", "info", "score_blue")).shape == (20, 2)
    env.close()
