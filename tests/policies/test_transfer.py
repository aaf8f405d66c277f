"""``init_path``: a fresh run starts from a checkpoint, and a network trained on a smaller team game grows to a
bigger one, playing exactly as before on the cars it has slots for (policies/ppo/transfer.py); real envs, a real
training run."""
import json

import numpy as np
import pytest
import torch

import rocketdrl_ma
from rocketdrl_ma.cli import main
from rocketdrl_ma.policies.ppo import load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.checkpoint import load_model
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.policies.ppo.transfer import init_from_checkpoint, team_layout_size

ONE_V_ONE = "policies/checkpoints/selfplay_1v1_kickstart.pt"
TWO_V_TWO = "policies/checkpoints/selfplay_2v2_from_1v1.pt"
N_SELF_AND_BALL, N_CAR, N_TAIL = 29, 20, 38  # team_relative blocks: own car + ball, one car, pads + game


def _sub_game_view(obs: np.ndarray, old_k: int, new_k: int) -> np.ndarray:
    """The observation of a game with teams of ``old_k`` inside one with teams of ``new_k``: own car, ball, the first
    ``old_k - 1`` team-mate and first ``old_k`` opponent slots, pads and game."""
    mates, opponents = N_SELF_AND_BALL, N_SELF_AND_BALL + N_CAR * (new_k - 1)
    return np.concatenate([obs[..., :N_SELF_AND_BALL], obs[..., mates:mates + N_CAR * (old_k - 1)],
                           obs[..., opponents:opponents + N_CAR * old_k], obs[..., -N_TAIL:]], axis=-1)


def test_team_layout_sizes():
    assert [team_layout_size(n) for n in (87, 127, 167, 207)] == [1, 2, 3, 4]
    assert team_layout_size(107) is None and team_layout_size(22) is None


@pytest.mark.parametrize("checkpoint, old_k, team_size", [(ONE_V_ONE, 1, 2), (ONE_V_ONE, 1, 3), (TWO_V_TWO, 2, 3)])
def test_a_grown_network_plays_as_its_checkpoint_on_the_cars_it_had_slots_for(checkpoint, old_k, team_size):
    old, _ = load_model(checkpoint)
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml", team_size=team_size, action="lookup", kickoff_countdown_s=0.0)
    obs, _ = env.reset(seed=11)
    obs_dim = env.observation_space("blue_0").shape[0]
    grown = PPOModel(obs_dim, old.action, 256, 2, True, features="car_local")
    init_from_checkpoint(grown, obs_dim, checkpoint)
    rng = np.random.default_rng(0)
    seen = []
    for _ in range(60):  # random driving spreads the cars, so the other cars' inputs are far from zero
        seen += [obs[a] for a in env.agents]
        obs = env.step({a: int(rng.integers(90)) for a in env.agents})[0]
    env.close()
    batch = torch.as_tensor(np.stack(seen))
    view = torch.as_tensor(_sub_game_view(np.stack(seen), old_k, team_size))
    with torch.no_grad():
        assert torch.allclose(grown.policy(grown.obs_norm(batch)), old.policy(old.obs_norm(view)), atol=1e-4)
        assert torch.allclose(grown.value(grown.obs_norm(batch)), old.value(old.obs_norm(view)), atol=1e-4)
    assert np.array_equal(grown.act_deterministic(batch.numpy()), old.act_deterministic(view.numpy()))
    # the last team-mate slot is new: it starts at zero weight, an input PPO can learn to use
    first_layer = grown.policy[0].weight
    last_mate = N_SELF_AND_BALL + N_CAR * (team_size - 2)
    assert first_layer[:, last_mate:last_mate + N_CAR].abs().sum() == 0.0
    assert first_layer[:, :N_SELF_AND_BALL].abs().sum() > 0.0 and first_layer.requires_grad


def test_init_path_is_validated_and_a_network_only_grows_to_a_bigger_team_game(tmp_path):
    raw = load_train_config("policies/selfplay_2v2_from_1v1.yaml").to_mapping()
    with pytest.raises(ValueError, match=r"init_path: no such file 'nope.pt'"):
        validate_train_config({**raw, "init_path": "nope.pt"})
    with pytest.raises(ValueError, match="init_path: expected the path of a checkpoint"):
        validate_train_config({**raw, "init_path": 3})
    with pytest.raises(ValueError, match=r"init_path: a run starts from a checkpoint or from a warm start"):
        validate_train_config({**raw, "selfplay": {**raw["selfplay"], "imitate": {"bot": "rotator"}}})
    old, _ = load_model(TWO_V_TWO)
    small = PPOModel(87, old.action, 256, 2, True, features="car_local")
    with pytest.raises(ValueError, match=r"init_path: a network grows .* got 127 -> 87"):
        init_from_checkpoint(small, 87, TWO_V_TWO)
    continuous = PPOModel(127, {"kind": "box", "dim": 8}, 256, 2, True, features="car_local")
    with pytest.raises(ValueError, match=r"init_path: .* was trained with action"):
        init_from_checkpoint(continuous, 127, ONE_V_ONE)
    narrow = PPOModel(87, old.action, 64, 2, True, features="car_local")
    with pytest.raises(ValueError, match="init_path: .* does not fit this run's network"):
        init_from_checkpoint(narrow, 87, ONE_V_ONE)


def test_a_run_from_init_path_starts_at_the_grown_checkpoint_and_keeps_its_input_statistics(tmp_path):
    cfg_path = tmp_path / "grow.yaml"
    raw = load_train_config("policies/selfplay_2v2_from_1v1.yaml").to_mapping()
    cfg_path.write_text(json.dumps({
        **raw, "env_overrides": {**raw["env_overrides"], "clock_s": 3.0}, "n_envs": 2, "n_workers": 0,
        "buffer_size": 256, "batch_size": 128, "num_epoch": 1, "max_steps": 512, "summary_freq": 256,
        "checkpoint_interval": 512, "keep_checkpoints": 1,
        "selfplay": {**raw["selfplay"], "snapshot_interval": 256, "pool_size": 2, "scripted": ["ball_chaser"]}}))
    run_dir = tmp_path / "run"
    assert main(["train", str(cfg_path), "--run-dir", str(run_dir), "--quiet"]) == 0
    start = torch.load(run_dir / "warm_start.pt", weights_only=True)
    expected = PPOModel(127, {"kind": "discrete", "n": 90}, 256, 2, True, features="car_local")
    init_from_checkpoint(expected, 127, ONE_V_ONE)
    assert all(torch.equal(start[k], v) for k, v in expected.state_dict().items())
    final = torch.load(run_dir / "final.pt", weights_only=True)
    assert not torch.equal(final["policy.0.weight"], start["policy.0.weight"])  # PPO did update it
    for key in ("obs_norm.mean", "obs_norm.var", "obs_norm.count"):
        assert torch.equal(final[key], start[key])
    assert json.loads((run_dir / "final.json").read_text())["train"]["init_path"] == ONE_V_ONE
