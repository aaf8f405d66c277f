"""The centralised critic (``critic: central``, MAPPO): which rows it reads, the config's check, and real 2v2
self-play training with it in the trainer's process and through a rollout worker process, whose checkpoint
resumes and plays a league match."""
import json
import math

import numpy as np
import pytest
import torch

from rocketdrl_ma.cli import main
from rocketdrl_ma.league.config import validate_league_config
from rocketdrl_ma.league.play import play_local
from rocketdrl_ma.league.schedule import schedule
from rocketdrl_ma.policies.ppo import load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.checkpoint import load_model
from rocketdrl_ma.policies.ppo.critic import critic_input, team_order


def test_team_order_puts_the_car_first_then_its_team_mates():
    assert team_order(["learner"] * 3, "central").tolist() == [[0, 1, 2], [1, 0, 2], [2, 0, 1]]
    # a copy of a 2v2 match without self-play: both teams' cars are rows; each reads its own team only
    assert team_order(["blue", "blue", "orange", "orange"], "central").tolist() == [[0, 1], [1, 0], [2, 3], [3, 2]]
    assert team_order(["blue", "blue", "orange"], "local").tolist() == [[0], [1], [2]]
    with pytest.raises(ValueError, match="critic: 'central' needs teams of one size"):
        team_order(["blue", "orange", "orange"], "central")


def test_critic_input_joins_each_row_with_its_team_mates_at_the_same_decision():
    copies, per_copy, horizon, dim = 3, 2, 4, 5
    x = torch.arange(copies * per_copy * horizon * dim, dtype=torch.float32).reshape(copies * per_copy, horizon, dim)
    out = critic_input(x, torch.as_tensor(team_order(["learner"] * per_copy, "central")))
    assert out.shape == (copies * per_copy, horizon, per_copy * dim)
    for row in range(copies * per_copy):
        mate = row + 1 if row % 2 == 0 else row - 1
        for t in range(horizon):
            assert torch.equal(out[row, t], torch.cat([x[row, t], x[mate, t]]))
    local = critic_input(x, torch.as_tensor(team_order(["learner"] * per_copy, "local")))
    assert torch.equal(local, x)


def test_config_names_the_critic_and_its_allowed_values():
    cfg = load_train_config("policies/selfplay_2v2.yaml")
    assert cfg.critic == "local"
    assert load_train_config("policies/selfplay_2v2_mappo.yaml").critic == "central"
    assert validate_train_config({"env": "matches/1v1.yaml"}).critic == "local"
    with pytest.raises(ValueError, match=r"critic.*'global'.*central"):
        validate_train_config({**cfg.to_mapping(), "critic": "global"})
    # the MAPPO config is the 2v2 config with the central critic, nothing else
    plain, mappo = cfg.to_mapping(), load_train_config("policies/selfplay_2v2_mappo.yaml").to_mapping()
    assert {key for key in plain if plain[key] != mappo[key]} == {"critic"}


def tiny_central(n_workers: int) -> dict:
    """policies/selfplay_2v2_mappo.yaml cut to one iteration of 64 decisions of 2 env copies, 4 s matches."""
    cfg = load_train_config("policies/selfplay_2v2_mappo.yaml").to_mapping()
    steps = 64 * 2 * 2
    return {**cfg, "env_overrides": {**cfg["env_overrides"], "clock_s": 4.0}, "n_envs": 2, "n_workers": n_workers,
            "buffer_size": steps, "batch_size": steps // 2, "num_epoch": 2, "hidden_units": 32, "max_steps": steps,
            "summary_freq": steps, "checkpoint_interval": steps,
            "selfplay": {**cfg["selfplay"], "snapshot_interval": steps,
                         "imitate": {**cfg["selfplay"]["imitate"], "decisions": 40, "epochs": 2, "dagger_rounds": 1,
                                     "dagger_decisions": 20}}}


@pytest.mark.slow
@pytest.mark.parametrize("n_workers", [0, 1])
def test_central_critic_trains_resumes_and_its_checkpoint_plays(tmp_path, n_workers):
    cfg = tiny_central(n_workers)
    cfg_path = tmp_path / "mappo.yaml"
    cfg_path.write_text(json.dumps(cfg))
    run_dir = tmp_path / "run"
    assert main(["train", str(cfg_path), "--run-dir", str(run_dir), "--quiet"]) == 0
    model, meta = load_model(run_dir / "final.pt")
    assert meta["network"]["critic"] == "central" and meta["network"]["critic_inputs"] == 2
    # the value reads two model inputs (the car's and its team-mate's), the policy one
    assert model.value[0].in_features == 2 * model.input_dim
    assert model.policy[0].in_features == model.input_dim
    for key in ("loss_objective", "loss_critic", "loss_entropy"):
        assert math.isfinite(meta["metrics"][key]), (key, meta["metrics"])
    # the warm start before any update, and a snapshot, are checkpoints with the same central critic
    assert load_model(run_dir / "warm_start.pt")[1]["network"]["critic_inputs"] == 2
    snapshot_meta = load_model(next((run_dir / "snapshots").glob("step_*.pt")))[1]
    assert snapshot_meta["network"]["critic"] == "central"
    assert math.isfinite(snapshot_meta["metrics"]["train_seconds"])  # the rating curve's hours axis reads it

    # resume: one more iteration; with another critic it is a clear error naming the key
    resumed = run_dir / "resumed.pt"
    assert main(["train", str(cfg_path), "--run-dir", str(run_dir), "--quiet", "--resume", str(run_dir / "final.pt"),
                 "--max-steps", str(2 * cfg["max_steps"]), "--out", str(resumed)]) == 0
    assert load_model(resumed)[1]["agent_steps"] == 2 * cfg["max_steps"]
    local_path = tmp_path / "local.yaml"
    local_path.write_text(json.dumps({**cfg, "critic": "local"}))
    with pytest.raises(ValueError, match="critic: .* was trained with critic: central"):
        main(["train", str(local_path), "--run-dir", str(tmp_path / "other"), "--quiet",
              "--resume", str(run_dir / "final.pt"), "--max-steps", str(2 * cfg["max_steps"])])

    # the checkpoint plays a league match (only its actor acts), a team of it against two ball-chasers
    league = validate_league_config({
        "name": "mappo", "match": "matches/2v2.yaml", "results": str(tmp_path / "r.sqlite"),
        "report": str(tmp_path / "report"), "format": "per_pair", "matches_per_pair": 1, "seed": 5,
        "overrides": {"clock_s": 5.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
        "entrants": [{"name": "mappo", "policy": f"checkpoint:{resumed}"},
                     {"name": "ball_chaser", "policy": "scripted:ball_chaser"}]})
    result = play_local(league, schedule(league)[0])
    assert result.duration_s >= 5.0
    assert np.isfinite([result.score_blue, result.score_orange]).all()
