"""The lean rollout loop plays the batch torchrl's collector plays; stacked opponents play as their own forwards."""
from __future__ import annotations

import tempfile

import numpy as np
import pytest
import torch
from torchrl.collectors import Collector

from rocketdrl_ma.policies.ppo import TrainConfig, load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.policies.ppo.rollout import RolloutEnv
from rocketdrl_ma.policies.ppo.rollout_policy import RolloutPolicy
from rocketdrl_ma.policies.ppo.selfplay.pool import OpponentPool
from rocketdrl_ma.policies.ppo.stacked import StackedPolicies
from rocketdrl_ma.policies.ppo.trainer import Probe, sync_controls, worker_config
from rocketdrl_ma.policies.ppo.worker_loop import LeanCollector

from test_workers import _selfplay_cfg


def _policy(cfg: TrainConfig) -> tuple[RolloutPolicy, TrainConfig]:
    wcfg = worker_config(cfg)
    probe = Probe.of(wcfg)
    torch.manual_seed(3)
    model = PPOModel(probe.obs_dim, probe.action, cfg.hidden_units, cfg.num_layers, cfg.normalize, cfg.init_std,
                     probe.idle, cfg.features)
    pool = None
    if cfg.selfplay:
        pool = OpponentPool(cfg, tempfile.mkdtemp(), probe.obs_dim)
        pool.attach(model, 1)
    policy = RolloutPolicy(model, pool.slot_models if pool else None, pool.n_opponents if pool else 0)
    sync_controls(policy, None, cfg.teacher_kickstart is not None, pool)
    return policy, wcfg


def _assert_same(torchrl_batch, lean_batch) -> None:
    for key in lean_batch.keys(True, True):
        if key == ("next", "env_cpu_s"):  # a CPU clock
            continue
        torch.testing.assert_close(lean_batch.get(key), torchrl_batch.get(key), rtol=0, atol=0, equal_nan=True,
                                   msg=lambda m: f"{key}: {m}")


@pytest.mark.parametrize("config", ["selfplay", "penalty"])
def test_the_lean_loop_collects_the_batch_torchrls_collector_collects_for_one_seed(config):
    """Two batches of 150 decisions, with episode ends and resets between them (3 s self-play matches with
    scripted, self and kickstart keys; Penalty rounds): every key the learner reads is bit for bit torchrl's."""
    if config == "selfplay":
        cfg = _selfplay_cfg()
    else:
        cfg = validate_train_config({**load_train_config("policies/penalty_tuned.yaml").to_mapping(), "n_envs": 2,
                                     "hidden_units": 16})
    policy, wcfg = _policy(cfg)
    horizon = 150
    torch.manual_seed(11)
    env = RolloutEnv(wcfg, cfg.n_envs)
    collector = Collector(env, policy, frames_per_batch=env.rows * horizon, total_frames=-1,
                          auto_register_policy_transforms=False)
    after_start = torch.get_rng_state()  # torchrl's collector draws from torch's generator as it starts
    batches = iter(collector)
    expected = [next(batches), next(batches)]
    collector.shutdown()
    torch.set_rng_state(after_start)
    lean = LeanCollector(wcfg, policy, 0, cfg.n_envs, horizon)
    try:
        got = [next(lean), next(lean)]
    finally:
        lean.shutdown()
    assert bool(torch.cat([b["next", "done"] for b in got]).any())  # episodes ended and copies were reset
    for torchrl_batch, lean_batch in zip(expected, got):
        assert lean_batch.shape == torchrl_batch.shape == (env.rows, horizon)
        _assert_same(torchrl_batch, lean_batch)


def _models(action: dict, n: int, obs_dim: int, features: str) -> list[PPOModel]:
    torch.manual_seed(5)
    models = []
    for _ in range(n):
        model = PPOModel(obs_dim, action, 64, 2, True, 0.5, None, features)
        with torch.no_grad():
            for p in model.policy.parameters():
                p.add_(torch.randn_like(p) * 0.3)
            model.obs_norm.mean.normal_()
            model.obs_norm.var.uniform_(0.5, 2.0)
        models.append(model)
    return models


#: stacked outputs against each network's own forward (batched kernels sum in another order): relative and absolute
TOLERANCE = 1e-5


@pytest.mark.parametrize("kind", ["discrete", "box"])
def test_stacked_policies_give_every_row_its_own_networks_output(kind):
    obs_dim = 87  # the 1v1 team_relative observation (car_local features need it)
    action = {"kind": "discrete", "n": 90} if kind == "discrete" else {"kind": "box", "dim": 8}
    models = _models(action, 3, obs_dim, "car_local")
    rng = np.random.default_rng(0)
    obs = torch.as_tensor(rng.normal(size=(40, obs_dim)), dtype=torch.float32)
    which = torch.as_tensor(rng.integers(0, 3, 40))
    which[:3] = 2  # one network with more rows than the others: the padding is exercised
    stacked = StackedPolicies(models)(obs, which)
    for k, model in enumerate(models):
        rows = which == k
        own = model.policy(model.obs_norm(obs[rows]))
        if kind == "box":
            torch.testing.assert_close(stacked[0][rows], own[0], rtol=TOLERANCE, atol=TOLERANCE)
            assert torch.equal(stacked[1][rows], own[1])
        else:
            torch.testing.assert_close(stacked[rows], own, rtol=TOLERANCE, atol=TOLERANCE)
            # greedy choices agree wherever the best logit leads the second by more than twice the tolerance
            top = own.topk(2, dim=-1).values
            clear = (top[:, 0] - top[:, 1]) > 2 * TOLERANCE * (1.0 + top[:, 0].abs())
            assert torch.equal(stacked[rows].argmax(-1)[clear], own.argmax(-1)[clear]) and bool(clear.any())


def test_the_rollout_policy_plays_each_opponent_row_with_its_own_network():
    """The learner (index 0), a scripted bot (1) and two snapshot slots (2, 3): each network made to prefer one
    action by far, so a sample shows which network played the row; the scripted bot's rows are left to the env."""
    action = {"kind": "discrete", "n": 90}
    learner, *slots = _models(action, 3, 87, "car_local")
    for model, preferred in zip((learner, *slots), (7, 21, 42)):
        with torch.no_grad():
            model.policy[-1].bias[preferred] += 1e4
    policy = RolloutPolicy(learner, torch.nn.ModuleList(slots), n_opponents=4)
    rows = 12
    opponent = torch.as_tensor([0, 1, 2, 3] * 3)
    out = policy.act(torch.zeros(rows, 87), torch.randn(rows, 87), opponent, torch.zeros(rows, dtype=torch.bool),
                     torch.zeros(rows))
    expected = torch.as_tensor([7, 0, 21, 42] * 3)
    assert torch.equal(out["opponent_action"], expected) and torch.equal(out["opponent_id"], opponent)


@pytest.mark.parametrize("kind", ["discrete", "box"])
def test_the_rollout_policy_samples_what_torch_distributions_sample_from_one_generator_state(kind):
    action = {"kind": "discrete", "n": 90} if kind == "discrete" else {"kind": "box", "dim": 8}
    (model,) = _models(action, 1, 87, "car_local")
    policy = RolloutPolicy(model)
    x = model.obs_norm(torch.randn(64, 87))
    torch.manual_seed(2)
    got_action, got_log_prob = policy.sample(x)
    torch.manual_seed(2)
    if kind == "box":
        loc, scale = model.policy(x)
        dist = torch.distributions.Independent(torch.distributions.Normal(loc, scale), 1)
    else:
        dist = torch.distributions.Categorical(logits=model.policy(x))
    expected = dist.sample()
    assert torch.equal(got_action, expected) and torch.equal(got_log_prob, dist.log_prob(expected))
