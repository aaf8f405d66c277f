"""Rollout workers on torchrl's collectors: determinism, faults, stopping, and the env they step."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import psutil
import pytest
import torch

from rocketdrl_ma.policies.ppo import TrainConfig, load_train_config, train, validate_train_config
from rocketdrl_ma.policies.ppo.checkpoint import load_model
from rocketdrl_ma.policies.ppo.critic import team_order
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.policies.ppo.rollout import RolloutEnv, worker_copies
from rocketdrl_ma.policies.ppo.rollout_policy import RolloutPolicy
from rocketdrl_ma.policies.ppo.trainer import Probe, worker_config
from rocketdrl_ma.policies.ppo.workers import Rollouts, WorkerPlan
from ray_cluster import LocalRayCluster

# policies/selfplay_1v1.yaml cut down: 3 s matches, a tiny network, a kickstart teacher so every key travels
SELFPLAY = {"env_overrides": {"clock_s": 3.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
            "n_envs": 4, "buffer_size": 256, "batch_size": 128, "num_epoch": 2, "hidden_units": 32,
            "max_steps": 768, "summary_freq": 512, "checkpoint_interval": 256, "keep_checkpoints": 1,
            "selfplay": {"snapshot_interval": 256, "pool_size": 2, "scripted": ["ball_chaser"], "self_play": 0.2,
                         "window": 20, "kickstart": {"bot": "goalie"}}}


def _selfplay_cfg(**extra) -> TrainConfig:
    return validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **SELFPLAY, **extra})


@pytest.mark.slow
def test_asynchronous_workers_train_on_each_workers_batch_and_record_the_policy_lag(tmp_path):
    """``async: true`` (torchrl's ``MultiAsyncCollector``): the learner updates on each worker's batch as it comes
    while the other worker goes on collecting with the weights it had, so some batches come from older weights."""
    cfg = _selfplay_cfg(max_steps=1024)
    plan = WorkerPlan(2, asynchronous=True)
    result = train(cfg, tmp_path / "final.pt", tmp_path, progress=False, workers=plan)
    assert result.agent_steps >= 1024
    wcfg = worker_config(cfg)
    layout = Rollouts(wcfg, None, plan, Probe.of(wcfg).rows_per_copy)
    per_batch = layout.rows_per_worker * layout.horizon  # one worker's batch fills the buffer
    assert per_batch == cfg.buffer_size
    assert len(result.policy_lags) == len(result.losses) == result.agent_steps // per_batch
    assert min(result.policy_lags) >= 0 and max(result.policy_lags) >= 1
    assert all(np.isfinite(v) for losses in result.losses for v in losses.values())
    _, meta = load_model(tmp_path / "final.pt")
    assert meta["agent_steps"] == result.agent_steps


def test_worker_copies_split_evenly_and_every_copy_keeps_its_seed():
    assert [worker_copies(32, n) for n in (1, 2, 3, 8)] == [32, 16, 11, 4]
    cfg = worker_config(_selfplay_cfg())
    whole, part = RolloutEnv(cfg, copies=4), RolloutEnv(cfg, copies=2, worker=1)
    try:
        a, b = whole.reset(), part.reset()
        # copy 2 of the run is copy 0 of worker 1: the same game from the same seed, on the same side
        assert torch.equal(a["observation"][2:4], b["observation"][0:2])
        assert whole.games.learner_team[2:] == part.games.learner_team
    finally:
        whole.close()
        part.close()


@pytest.mark.slow
def test_two_workers_give_the_same_losses_for_the_same_seed(tmp_path):
    """Synchronous collection is deterministic: same seed, same worker count, bit-identical losses."""
    cfg = _selfplay_cfg()
    runs = [train(cfg, tmp_path / f"r{k}" / "final.pt", tmp_path / f"r{k}", progress=False,
                  workers=WorkerPlan(2)).losses[:3] for k in range(2)]
    assert len(runs[0]) == 3 and runs[0] == runs[1]
    assert all(np.isfinite(v) for losses in runs[0] for v in losses.values())


@pytest.mark.slow
def test_overlapping_workers_collect_each_batch_with_the_weights_of_one_update_before(tmp_path):
    """``overlap`` (the default with worker processes): the workers collect the next batch while the learner
    updates, so after the first batch every batch is exactly one update old, and a seed still gives one run."""
    cfg = _selfplay_cfg(max_steps=1280)
    runs = [train(cfg, tmp_path / f"r{k}" / "final.pt", tmp_path / f"r{k}", progress=False, workers=WorkerPlan(2))
            for k in range(2)]
    assert runs[0].policy_lags == [0, 1, 1, 1, 1]
    assert runs[0].losses == runs[1].losses
    off = train(cfg, tmp_path / "off" / "final.pt", tmp_path / "off", progress=False,
                workers=WorkerPlan(2, overlap=False))
    assert off.policy_lags == [0] * 5
    assert off.losses[0] == runs[0].losses[0] and off.losses[1] != runs[0].losses[1]
    # the env's capacity readout is computed and logged (its figures belong to benchmarks/scaling.py)
    assert np.isfinite(runs[0].env_capacity_steps_per_s)
    tensorboard = pytest.importorskip("tensorboard.backend.event_processing.event_accumulator")
    events = tensorboard.EventAccumulator(str(tmp_path / "r0"))
    events.Reload()
    assert {"perf/env_share", "perf/env_capacity_steps_per_s", "perf/learner_share"} <= set(events.Tags()["scalars"])


class _FailingOnce:
    """A collector whose first batch fails with ``error``; a rebuilt one delivers."""

    def __init__(self, error: Exception | None):
        self.error, self.procs, self.stopped = error, [], False

    def update_policy_weights_(self) -> None:
        pass

    def shutdown(self) -> None:
        self.stopped = True

    def __iter__(self):
        if self.error is not None:
            raise self.error
        yield torch.zeros(4, 8)


def test_torchrls_close_race_counts_as_a_worker_fault_and_other_value_errors_propagate(monkeypatch):
    """torchrl, finding a dead worker, terminates the others and closes them 0.1 s later: on a loaded machine one is
    still exiting and multiprocessing raises ValueError. That is the fault it found (the killed-worker test below hit
    it under load): the workers are rebuilt. Any other ValueError is a bug and is raised."""
    race = ValueError("Cannot close a process while it is still running. You should first call join() or terminate().")
    for first_error, recovers in ((race, True), (ValueError("shape mismatch"), False)):
        built = iter([_FailingOnce(first_error), _FailingOnce(None)])
        rollouts = Rollouts(_selfplay_cfg(), policy=None, plan=WorkerPlan(n_workers=2), rows_per_copy=2)
        monkeypatch.setattr(rollouts, "_build", lambda: next(built))
        if recovers:
            assert rollouts.next_batch().shape == (4, 8) and rollouts.restarts == 1
        else:
            with pytest.raises(ValueError, match="shape mismatch"):
                rollouts.next_batch()
            assert rollouts.restarts == 0


def _start_training(tmp_path: Path, max_steps: int, workers: int = 2) -> tuple[subprocess.Popen, Path]:
    cfg_path = tmp_path / "cfg.yaml"
    cfg_path.write_text(json.dumps({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), **SELFPLAY,
                                    "max_steps": max_steps}))
    run_dir = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "rocketdrl_ma.cli", "train", str(cfg_path), "--run-dir",
                             str(run_dir), "--workers", str(workers), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    return proc, run_dir


def _rollout_workers(pid: int) -> list[psutil.Process]:
    """The trainer's worker processes (multiprocessing's spawned children, not its resource tracker)."""
    return [p for p in psutil.Process(pid).children(recursive=True)
            if any("spawn_main" in part for part in p.cmdline())]


def _wait_for(predicate, timeout_s: float, proc: subprocess.Popen) -> None:
    end = time.monotonic() + timeout_s
    while not predicate():
        assert proc.poll() is None, proc.communicate()[0]
        assert time.monotonic() < end, "timed out"
        time.sleep(0.2)


@pytest.mark.slow
def test_a_killed_worker_is_replaced_and_training_finishes_with_a_checkpoint_that_loads(tmp_path):
    proc, run_dir = _start_training(tmp_path, max_steps=4096)
    try:
        # after the first periodic checkpoint the workers are collecting
        _wait_for(lambda: (run_dir / "latest.pt").is_file() and len(_rollout_workers(proc.pid)) == 2, 240, proc)
        victim = _rollout_workers(proc.pid)[0]
        victim.send_signal(signal.SIGKILL)
        output, _ = proc.communicate(timeout=400)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, output
    assert "rollout workers failed" in output and "restarting them" in output
    model, meta = load_model(run_dir / "final.pt")
    assert meta["agent_steps"] >= 4096
    assert model.act_deterministic(np.zeros((1, meta["network"]["obs_dim"]), np.float32)).shape[0] == 1


@pytest.mark.slow
def test_a_worker_dead_between_batches_fails_the_weight_push_and_fresh_workers_collect_the_next_batch():
    """torchrl's shared-memory weight push waits for every worker's acknowledgement with no time limit: a worker
    killed while the learner updated (after its batch, before the push) hung the run for good. The push now raises
    ``WorkerLost`` and the workers are rebuilt."""
    cfg = worker_config(validate_train_config({**load_train_config("policies/penalty.yaml").to_mapping(),
                                               "n_envs": 2, "buffer_size": 64, "batch_size": 64, "hidden_units": 16}))
    probe = Probe.of(cfg)
    model = PPOModel(probe.obs_dim, probe.action, cfg.hidden_units, cfg.num_layers, cfg.normalize, cfg.init_std,
                     probe.idle, cfg.features, team_order(probe.row_teams, cfg.critic).shape[1])
    rollouts = Rollouts(cfg, RolloutPolicy(model, None, 0), WorkerPlan(n_workers=2), probe.rows_per_copy)
    try:
        assert rollouts.next_batch().numel() == 64
        first_workers = rollouts.worker_pids()
        os.kill(first_workers[0], signal.SIGKILL)
        deadline = time.monotonic() + 30
        while rollouts.workers_alive() == 2 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert rollouts.workers_alive() == 1
        push = threading.Thread(target=rollouts.update_weights, daemon=True)
        push.start()
        push.join(60)
        assert not push.is_alive(), "the weight push is still waiting for the dead worker"
        assert rollouts.restarts == 1
        assert rollouts.next_batch().numel() == 64
        assert rollouts.restarts == 1 and rollouts.workers_alive() == 2
        assert not set(rollouts.worker_pids()) & set(first_workers)
    finally:
        rollouts.close()


@pytest.mark.slow
def test_sigterm_saves_a_final_checkpoint_and_stops_every_worker(tmp_path):
    proc, run_dir = _start_training(tmp_path, max_steps=10_000_000)
    try:
        _wait_for(lambda: (run_dir / "latest.pt").is_file() and len(_rollout_workers(proc.pid)) == 2, 240, proc)
        family = [psutil.Process(proc.pid), *psutil.Process(proc.pid).children(recursive=True)]
        proc.send_signal(signal.SIGTERM)
        output, _ = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, output
    model, meta = load_model(run_dir / "final.pt")
    assert 0 < meta["agent_steps"] < 10_000_000
    deadline = time.monotonic() + 20
    while any(p.is_running() and p.status() != psutil.STATUS_ZOMBIE for p in family) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not [p.pid for p in family if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]


@pytest.mark.slow
@pytest.mark.xdist_group("ray")  # the tests that start a Ray cluster share an xdist worker (`make test`)
def test_training_on_a_two_node_ray_cluster_writes_a_checkpoint_that_eval_plays(tmp_path):
    from rocketdrl_ma.cli import main

    cluster = LocalRayCluster()
    try:
        cfg_path = tmp_path / "cfg.yaml"
        cfg_path.write_text(json.dumps({
            "env": "minigames/penalty.yaml", "n_envs": 2, "buffer_size": 256, "batch_size": 128, "num_epoch": 1,
            "hidden_units": 32, "max_steps": 1024, "summary_freq": 512, "checkpoint_interval": 1024,
            "curriculum": {"start": 0.0, "step": 0.1, "threshold": 0.9}}))
        run_dir = tmp_path / "run"
        result = train(validate_train_config(json.loads(cfg_path.read_text())), run_dir / "final.pt", run_dir,
                       progress=False, workers=WorkerPlan(2, ray=cluster.address))
        assert result.agent_steps == 1024
        assert result.policy_lags == [0] * len(result.policy_lags)  # every batch collected with the newest weights
        assert main(["eval", str(run_dir / "final.pt"), "--episodes", "2", "--n-envs", "1"]) == 0
    finally:
        cluster.stop()
    assert not cluster.processes()
