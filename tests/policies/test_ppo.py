"""PPO: config validation, a short real training run that writes a checkpoint the registry loads and plays,
resuming, and the update lowering the loss on a fixed toy batch."""
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import torch
from tensordict import TensorDict
from torchrl.envs.utils import ExplorationType, set_exploration_type

import rocketdrl_ma
from rocketdrl_ma.cli import main
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.ppo import load_model, train, validate_train_config
from rocketdrl_ma.policies.ppo.envs import EnvPool, episode_outcomes
from rocketdrl_ma.policies.ppo.evaluate import count_outcomes, evaluate
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.rules.rewards import BallToGoalDistance, CarToBallDistance
from rocketdrl_ma.policies.ppo import trainer
from rocketdrl_ma.policies.ppo.trainer import RunClock, make_loss, ppo_update
from rocketdrl_ma.policies.base import ObservingPolicy
from rocketdrl_ma.policies.registry import load_policy

# A 1v1 match cut short so episodes end within a few hundred decisions; both cars share the policy.
TINY = {
    "env": "matches/1v1.yaml",
    "env_overrides": {"kickoff_countdown_s": 0.0, "clock_s": 4.0, "overtime_limit_s": 4.0, "boost_pads": False,
                      "observation": "seed_sensors", "action": "seed",
                      "rewards": {"touch": 1.0, "player_velocity_to_ball": 0.1}},
    "n_envs": 2, "n_workers": 0, "buffer_size": 512, "batch_size": 128, "num_epoch": 2, "normalize": True,
    "hidden_units": 32, "max_steps": 2048, "summary_freq": 1024, "checkpoint_interval": 1024, "keep_checkpoints": 1,
}


def test_unknown_and_bad_keys_are_named():
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['batchsize'\].*allowed:.*'batch_size'"):
        validate_train_config({**TINY, "batchsize": 64})
    with pytest.raises(ValueError, match="learning_rate_schedule"):
        validate_train_config({**TINY, "learning_rate_schedule": "cosine"})
    with pytest.raises(ValueError, match="lambd"):
        validate_train_config({**TINY, "lambd": 1.5})
    with pytest.raises(ValueError, match="batch_size"):
        validate_train_config({**TINY, "batch_size": 4096})
    with pytest.raises(ValueError, match="clock"):  # the env config is validated up front too
        validate_train_config({**TINY, "env_overrides": {"clock": 3.0}})


@pytest.mark.slow
def test_short_training_run_writes_a_checkpoint_that_loads_acts_and_resumes(tmp_path, monkeypatch):
    cfg_path = tmp_path / "tiny.yaml"
    cfg_path.write_text(json.dumps(TINY))  # JSON is YAML
    out = tmp_path / "tiny.pt"
    assert main(["train", str(cfg_path), "--out", str(out), "--run-dir", str(tmp_path / "run"), "--quiet"]) == 0

    meta = json.loads((tmp_path / "tiny.json").read_text())
    assert meta["agent_steps"] == 2048
    assert meta["env"]["resolved"]["observation"] == {"name": "seed_sensors"}
    assert meta["network"]["action"] == {"kind": "box", "dim": 5}
    state = torch.load(out, weights_only=True)  # a plain state dict, no pickled code
    assert state["obs_norm.count"] >= 2048 and "policy.log_std" in state
    assert list((tmp_path / "run").glob("events.out.tfevents.*"))  # TensorBoard log
    assert main(["curves", f"tiny={tmp_path / 'run'}", "--out", str(tmp_path / "curve.png")]) == 0
    assert (tmp_path / "curve.png").read_bytes()[:4] == b"\x89PNG"
    assert [p.name for p in (tmp_path / "run" / "checkpoints").glob("step_*[0-9].pt")] == ["step_2048.pt"]

    policy = load_policy(f"checkpoint:{out}")
    assert isinstance(policy, ObservingPolicy)
    env = rocketdrl_ma.parallel_env(TINY["env"], **TINY["env_overrides"])
    env.reset(seed=3)
    state0 = env.rules.game_state()
    policy.reset(state0)
    controls = policy.controls("blue_0", state0)
    assert isinstance(controls, CarControls)
    for _ in range(5):  # the policy drives a real env through its own parser
        state = env.rules.game_state()
        env.step({a: env.action_parser.encode(policy.controls(a, state)) for a in env.agents})
    env.close()

    # resume: the step count continues, and the weights start from the checkpoint's
    model, _ = load_model(out)
    # the run's wall time so far (rating curves' hours) is carried on by the resumed session, not started again
    meta = json.loads((tmp_path / "tiny.json").read_text())
    meta["metrics"]["train_seconds"] = 7200.0
    (tmp_path / "tiny.json").write_text(json.dumps(meta))
    # this session's own time held at zero: what is checked is the carried-over 7200 s, not a measured duration
    monkeypatch.setattr(trainer, "RunClock", lambda seconds_before: RunClock(seconds_before, now=lambda: 0.0))
    resumed = train(validate_train_config({**TINY, "max_steps": 3072}), out=tmp_path / "more.pt",
                    run_dir=tmp_path / "run2", resume=out, progress=False)
    assert resumed.agent_steps == 3072
    assert [h[0] for h in resumed.history] == [3072]
    assert json.loads((tmp_path / "more.json").read_text())["agent_steps"] == 3072
    assert json.loads((tmp_path / "more.json").read_text())["metrics"]["train_seconds"] == 7200.0
    more, _ = load_model(tmp_path / "more.pt")
    assert torch.equal(more.obs_norm.count, model.obs_norm.count + 1024)

    assert main(["eval", str(out), "--episodes", "2", "--n-envs", "1"]) == 0


def test_evaluation_takes_each_copys_first_episodes():
    """Not whichever episodes end first: a goal ends a minigame episode early, so that would favour successes."""
    checkpoint = Path(__file__).resolve().parents[2] / "policies" / "checkpoints" / "penalty_tuned.pt"
    model, meta = load_model(checkpoint)
    result = evaluate(checkpoint, episodes=3, seed=51, n_envs=2)  # copy 1 ends its second episode first
    expected = []
    for copy, quota in ((0, 2), (1, 1)):  # copy k of a pool seeded s plays what a lone copy seeded s + k plays
        pool = EnvPool(meta["env"]["config"], 1, 51 + copy, meta["env"]["overrides"])
        obs, finished = pool.reset(), []
        while len(finished) < quota:
            step = pool.step(model.act_deterministic(obs))
            obs, finished = step.obs, finished + step.episodes
        pool.close()
        expected += finished[:quota]
    assert result.episodes == 3
    assert result.mean_length == np.mean([e.length for e in expected])
    assert result.mean_return == pytest.approx(np.mean([e.agent_return for e in expected]))
    # one round an episode: one outcome each, the same ones the lone copies played
    assert result.outcomes == count_outcomes(e.outcomes for e in expected)
    assert sum(result.outcomes.values()) == 3 and set(result.outcomes) <= {"goal", "wide", "timeout", "retreat"}


def test_a_match_episode_ends_in_the_agents_teams_win_loss_or_draw_and_a_minigame_in_its_rounds():
    """The shapes ``Rules.summary()`` gives: a match's ``winner``, a minigame's ``results`` (reason, else outcome)."""
    assert episode_outcomes("orange_1", {"summary": {"winner": "orange"}}) == ("win",)
    assert episode_outcomes("blue_0", {"summary": {"winner": "orange"}}) == ("loss",)
    assert episode_outcomes("blue_0", {"summary": {"winner": None}}) == ("draw",)
    rounds = [{"outcome": "goal", "reason": None}, {"outcome": "miss", "reason": "wide"}]
    assert episode_outcomes("blue_0", {"summary": {"winner": None, "results": rounds}}) == ("goal", "wide")
    assert episode_outcomes("blue_0", {}) == ("unfinished",)
    assert count_outcomes([("goal", "wide"), ("wide",), ("timeout",)]) == {"wide": 2, "goal": 1, "timeout": 1}


def test_update_lowers_the_loss_on_a_toy_batch():
    """Fixed observations whose advantage says 'steer towards the sign of obs[0]' and value = obs[1]."""
    torch.manual_seed(0)
    cfg = validate_train_config({**TINY, "beta": 0.0, "learning_rate": 3e-3})
    model = PPOModel(4, {"kind": "box", "dim": 2}, 32, 2, normalize=False)
    obs = torch.randn(512, 4)
    actor, _ = model.td_modules()
    with torch.no_grad(), set_exploration_type(ExplorationType.RANDOM):
        td = actor(TensorDict({"observation": obs}, batch_size=[512]))
    advantage = (td["action"][:, 0] * obs[:, 0].sign()).unsqueeze(-1)
    batch = TensorDict({"observation": obs, "action": td["action"], "action_log_prob": td["action_log_prob"],
                        "advantage": advantage, "value_target": obs[:, 1:2]}, batch_size=[512])
    optimizer = torch.optim.Adam(model.parameters(), lr=cfg.learning_rate)
    epochs = ppo_update(model, make_loss(model, cfg), optimizer, batch, num_epoch=20, batch_size=128)
    assert epochs[-1]["loss_critic"] < 0.2 * epochs[0]["loss_critic"]
    assert epochs[-1]["loss_objective"] < epochs[0]["loss_objective"]
    # and the greedy policy learned the toy rule
    greedy = model.act_deterministic(obs.numpy())
    assert np.mean(np.sign(greedy[:, 0]) == np.sign(obs[:, 0].numpy())) > 0.9


def test_potential_shaping_follows_the_game_state():
    pool = EnvPool("minigames/penalty.yaml", n_envs=1, seed=0, shaping={"car_to_ball": 1.0, "ball_to_goal": 2.0})
    pool.reset()
    env = pool.envs[0]
    before = env.game_state
    step = pool.step(np.array([[1.0, 0.0, -1.0, 1.0, -1.0]]))  # full throttle and boost, towards the ball
    after = env.game_state
    phi = [CarToBallDistance().get("blue_0", s) + 2.0 * BallToGoalDistance().get("blue_0", s) for s in (before, after)]
    assert phi[0] == pytest.approx(-np.linalg.norm(before.ball.pos - before.cars["blue_0"].pos) / 1000.0
                                   - 2.0 * np.linalg.norm(before.ball.pos - [0.0, 5560.0, 321.3875]) / 1000.0)
    assert step.shaping[0] == pytest.approx(phi[1] - phi[0], rel=1e-5)
    assert phi[1] > phi[0]  # the car got closer to the ball
    pool.close()
    with pytest.raises(ValueError, match="shaping: unknown term 'closeness'"):
        validate_train_config({**TINY, "shaping": {"closeness": 1.0}})


def test_curriculum_sets_the_minigame_difficulty():
    with pytest.raises(ValueError, match=r"curriculum: unknown key\(s\) \['levels'\]"):
        validate_train_config({**TINY, "curriculum": {"levels": 3}})
    with pytest.raises(ValueError, match="curriculum.threshold"):
        validate_train_config({**TINY, "curriculum": {"threshold": 1.5}})
    pool = EnvPool("minigames/penalty.yaml", n_envs=2, seed=0)
    pool.set_difficulty(0.0)  # the easiest spawn: car and ball on the goal's axis
    pool.reset()
    for env in pool.envs:
        state = env.game_state
        assert state.ball.pos[0] == 0.0 and state.cars["blue_0"].pos[0] == 0.0
    pool.close()
    match = EnvPool(TINY["env"], n_envs=1, seed=0, overrides=TINY["env_overrides"])
    with pytest.raises(ValueError, match="curriculum: game mode 'match' has no difficulty"):
        match.set_difficulty(0.5)
    match.close()


@pytest.mark.slow
def test_curriculum_raises_difficulty_and_sigterm_stops_with_a_checkpoint(tmp_path):
    """Threshold 0: every 100 finished episodes the difficulty goes up a step. SIGTERM to a background run:
    it finishes the iteration, writes its final checkpoint and exits 0."""
    cfg = {**TINY, "env": "minigames/penalty.yaml", "env_overrides": {"timeout_s": 0.5}, "n_envs": 4,
           "max_steps": 10_000_000, "curriculum": {"start": 0.0, "step": 0.5, "threshold": 0.0}}
    cfg_path = tmp_path / "curriculum.yaml"
    cfg_path.write_text(json.dumps(cfg))
    out = tmp_path / "stopped.pt"
    proc = subprocess.Popen([sys.executable, "-m", "rocketdrl_ma.cli", "train", str(cfg_path), "--out", str(out),
                             "--run-dir", str(tmp_path / "run"), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        latest = tmp_path / "run" / "latest.json"  # the periodic checkpoint, every 1024 steps
        deadline = time.monotonic() + 600.0
        while proc.poll() is None and time.monotonic() < deadline:
            try:
                if json.loads(latest.read_text()).get("difficulty") == 1.0:
                    break
            except (FileNotFoundError, json.JSONDecodeError):  # not written yet, or being written
                pass
            time.sleep(0.5)
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 0, stderr[-2000:]
    meta = json.loads((tmp_path / "stopped.json").read_text())
    assert 1024 < meta["agent_steps"] < 10_000_000
    assert meta["difficulty"] == 1.0


def test_registry_does_not_import_torch_until_a_checkpoint_loads():
    code = "import sys, rocketdrl_ma.policies.registry, rocketdrl_ma.cli; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_a_runs_clock_adds_this_sessions_time_to_the_earlier_sessions():
    ticks = iter([100.0, 130.0, 145.5])  # the session starts at 100 on its clock
    clock = RunClock(7200.0, now=lambda: next(ticks))
    assert clock.seconds() == 7230.0
    assert clock.seconds() == 7245.5
    assert RunClock(now=lambda: 5.0).seconds() == 0.0
