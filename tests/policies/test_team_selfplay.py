"""Team self-play configs (policies/selfplay_2v2.yaml, selfplay_3v3.yaml): they validate, put the rotator in the pool,
warm-start and kickstart from it, and one real training iteration runs with tiny sizes, logging the team metrics."""
import json

import pytest

from rocketdrl_ma.cli import main
from rocketdrl_ma.policies.ppo import load_train_config
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.rules.team_metrics import TEAM_LOG_METRICS


def tiny(path: str, n_envs: int) -> dict:
    """The config cut down to one iteration of 128 decisions: 3 s matches (so some end and log team metrics), a small network, a
    short warm start."""
    cfg = load_train_config(path).to_mapping()
    per_iteration = 128 * n_envs * cfg_team_size(cfg)
    imitate = cfg["selfplay"].get("imitate")
    imitate = imitate and {**imitate, "decisions": 40, "epochs": 2, "dagger_rounds": 1, "dagger_decisions": 20}
    return {**cfg, "env_overrides": {**cfg["env_overrides"], "clock_s": 3.0}, "n_envs": n_envs, "n_workers": 0,
            "buffer_size": per_iteration, "batch_size": per_iteration // 2, "num_epoch": 1, "hidden_units": 32,
            "max_steps": per_iteration, "summary_freq": per_iteration, "checkpoint_interval": per_iteration,
            "selfplay": {**cfg["selfplay"], "snapshot_interval": per_iteration, "imitate": imitate}}


def cfg_team_size(cfg: dict) -> int:
    return int(cfg["env"].split("/")[-1][0])


@pytest.mark.parametrize("path, size", [("policies/selfplay_2v2.yaml", 2), ("policies/selfplay_3v3.yaml", 3)])
def test_team_selfplay_config_uses_the_rotator(path, size):
    cfg = load_train_config(path)
    assert cfg.env == f"matches/{size}v{size}.yaml"
    sp = cfg.selfplay
    assert "rotator" in sp.scripted and sp.weighting == "hard"
    assert sp.imitate.bot == "rotator" and sp.kickstart.bot == "rotator"


def test_the_scratch_config_starts_from_a_random_network_with_team_rewards():
    cfg = load_train_config("policies/selfplay_2v2_scratch.yaml")
    assert cfg.init_path is None and cfg.selfplay.imitate is None and cfg.selfplay.kickstart is None
    assert cfg.env_overrides["team_spirit"] > 0.0
    assert {"touch_speed", "touch_height", "face_ball", "ball_velocity_to_goal"} <= set(cfg.env_overrides["rewards"])


@pytest.mark.slow
@pytest.mark.parametrize("path, size", [("policies/selfplay_2v2.yaml", 2), ("policies/selfplay_3v3.yaml", 3),
                                        ("policies/selfplay_2v2_scratch.yaml", 2)])
def test_team_selfplay_trains_one_iteration(tmp_path, path, size):
    cfg = tiny(path, n_envs=2)
    cfg_path = tmp_path / "team.yaml"
    cfg_path.write_text(json.dumps(cfg))
    run_dir = tmp_path / "run"
    assert main(["train", str(cfg_path), "--run-dir", str(run_dir), "--quiet"]) == 0
    meta = json.loads((run_dir / "final.json").read_text())
    assert meta["agent_steps"] == cfg["max_steps"]
    assert meta["env"]["resolved"]["team_size"] == size
    policy = load_policy(f"checkpoint:{run_dir / 'final.pt'}")
    assert policy.meta["env"]["resolved"]["action"]["name"] == "lookup"
    tensorboard = pytest.importorskip("tensorboard.backend.event_processing.event_accumulator")
    events = tensorboard.EventAccumulator(str(run_dir))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert {f"team/{key}" for key in ("passes", "double_commits", "boost_collected", "last_back_max_share")} <= tags
    share = events.Scalars("team/last_back_max_share")[-1].value
    assert 1.0 / size - 1e-6 <= share <= 1.0
    assert set(TEAM_LOG_METRICS) >= {tag.split("/", 1)[1] for tag in tags if tag.startswith("team/")}
