"""A scripted teacher for a single-team minigame: the top-level ``imitate`` (clone + DAgger) and ``kickstart``
(a fading distillation term) keys, on a real Barrier env and a real PPO run through ``rocketdrl-ma train``."""
import json

import numpy as np
import pytest
import torch

from tensordict import TensorDict

from rocketdrl_ma.cli import main
from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
from rocketdrl_ma.policies.ppo import load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.envs import EnvPool
from rocketdrl_ma.policies.ppo.rollout import RolloutEnv
from rocketdrl_ma.policies.ppo.trainer import worker_config
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.policies.scripted import make_scripted
from rocketdrl_ma.policies.ppo.selfplay.imitation import collect

OVERRIDES = {"action": "drive", "observation": "barrier_sensors+team_relative", "rewards": {"miss": 0.0}}
TINY = {"env_overrides": OVERRIDES, "n_envs": 2, "buffer_size": 256, "batch_size": 128, "num_epoch": 1,
        "hidden_units": 32, "max_steps": 512, "summary_freq": 256, "checkpoint_interval": 512,
        "keep_checkpoints": 1, "curriculum": {}}


def test_a_single_team_game_records_the_bot_for_every_decision():
    """No sides to alternate: every decision of every episode is the bot's, labelled with its own action."""
    obs, labels = collect("minigames/barrier.yaml", OVERRIDES, "barrier_shooter", "ball_chaser", 300, seed=4)
    env = RocketDRLParallelEnv("minigames/barrier.yaml", **OVERRIDES)
    bot = make_scripted("barrier_shooter")
    assert obs.shape == (300, env.observation_space("blue_0").shape[0]) and labels.shape == (300, 5)
    seen = env.reset(seed=4)[0]
    for t in range(300):  # the same episodes again
        assert np.array_equal(seen["blue_0"], obs[t])
        label = env.action_parser.encode(bot.controls("blue_0", env.game_state))
        assert np.array_equal(label, labels[t])
        seen = env.step({"blue_0": label})[0]
        if not env.agents:
            seen = env.reset()[0]
    env.close()


def test_top_level_teacher_keys_are_validated():
    base = load_train_config("policies/barrier_tuned.yaml").to_mapping()
    with pytest.raises(ValueError, match=r"imitate.bot: 'chipper' is not one of"):
        validate_train_config({**base, "imitate": {"bot": "chipper"}})
    with pytest.raises(ValueError, match=r"kickstart: unknown key\(s\) \['teacher'\]"):
        validate_train_config({**base, "kickstart": {"teacher": "barrier_shooter"}})
    with pytest.raises(ValueError, match="kickstart.weight"):
        validate_train_config({**base, "kickstart": {"bot": "barrier_shooter", "weight": -1}})
    with pytest.raises(ValueError, match="imitate: with selfplay, the teacher goes under selfplay.imitate"):
        validate_train_config({**load_train_config("policies/selfplay_1v1.yaml").to_mapping(), "imitate": {"bot": "goalie"}})


def test_a_trained_checkpoint_teaches_through_its_own_sensors_and_actions():
    """``imitate.bot: checkpoint:PATH``: penalty_tuned (the seed's sensors and actions, trained on Penalty alone)
    labels the penalty duel's shooter states (team-relative observation, lookup rows) with its own greedy controls."""
    spec = "checkpoint:policies/checkpoints/penalty_tuned.pt"
    overrides = {"action": "lookup", "observation": "team_relative"}
    obs, labels = collect("minigames/penalty_duel.yaml", overrides, spec, "goalie", 120, seed=2, side="blue")
    env = RocketDRLParallelEnv("minigames/penalty_duel.yaml", **overrides)
    teacher, keeper = load_policy(spec), make_scripted("goalie")
    seen = env.reset(seed=2)[0]
    for t in range(120):  # the same decisions again, the teacher asked through its own builder and parser
        assert np.array_equal(seen["blue_0"], obs[t])
        label = env.action_parser.encode(teacher.controls("blue_0", env.game_state))
        assert label == labels[t]
        seen = env.step({"blue_0": label,
                         "orange_0": env.action_parser.encode(keeper.controls("orange_0", env.game_state))})[0]
        if not env.agents:
            seen = env.reset()[0]
    env.close()
    assert len(set(labels.tolist())) > 1  # it steers, boosts and shoots: not one row throughout
    cfg = load_train_config("policies/penalty_duel_shooter.yaml").to_mapping()
    assert validate_train_config({**cfg, "selfplay": {**cfg["selfplay"], "kickstart": {"bot": spec}}})
    with pytest.raises(ValueError, match=r"selfplay.kickstart.bot: no such file 'nowhere.pt'"):
        validate_train_config({**cfg, "selfplay": {**cfg["selfplay"], "kickstart": {"bot": "checkpoint:nowhere.pt"}}})
    with pytest.raises(ValueError, match=r"selfplay.imitate.opponent: 'scripted:keeper' is not one of"):
        validate_train_config({**cfg, "selfplay": {**cfg["selfplay"], "imitate": {"opponent": "scripted:keeper"}}})


def test_the_pool_labels_every_row_with_the_teachers_action():
    pool = EnvPool("minigames/barrier.yaml", 3, 0, OVERRIDES, teacher="barrier_shooter")
    bot = make_scripted("barrier_shooter")
    pool.reset()
    rng = np.random.default_rng(0)
    for _ in range(20):
        labels = pool.teacher_actions()
        assert labels.shape == (3, 5)
        for i, env in enumerate(pool.envs):
            assert np.array_equal(labels[i], env.action_parser.encode(bot.controls("blue_0", env.game_state)))
        pool.step(rng.uniform(-1.0, 1.0, (3, 5)).astype(np.float32))
    pool.close()


def test_the_rollout_env_ships_the_teachers_label_of_every_state_it_returns():
    """The worker-side env of the plain (single-team) path: with a top-level ``kickstart`` it asks one teacher per
    copy, on the state each row is about to act in, and only while the learner wants labels (``ctl_kickstart``).
    Played by torchrl's own rollout loop, with its partial resets of the copies whose episode ended."""
    cfg = worker_config(validate_train_config({**load_train_config("policies/barrier_tuned.yaml").to_mapping(), **TINY,
                                               "env_overrides": {**OVERRIDES, "timeout_s": 2.0},
                                               "kickstart": {"bot": "barrier_shooter"}}))
    env = RolloutEnv(cfg, copies=3, worker=1)
    bot = make_scripted("barrier_shooter")
    rng = np.random.default_rng(1)
    asked = {"wanted": True, "checked": 0}

    def policy(td: TensorDict) -> TensorDict:
        labels = np.asarray([lane.action_parser.encode(bot.controls("blue_0", lane.game_state))
                             for lane in env.games.envs])
        expected = torch.as_tensor(labels) if asked["wanted"] else torch.zeros(3, 5)
        assert torch.equal(td["teacher_action"], expected)
        asked["checked"] += 1
        asked["wanted"] = asked["checked"] < 150  # then the learner's kickstart weight has faded to zero
        td["action"] = torch.as_tensor(rng.uniform(-1.0, 1.0, (3, 5)), dtype=torch.float32)
        td["ctl_kickstart"] = torch.full((3,), float(asked["wanted"]))
        return td

    try:
        assert "teacher_action" in env.full_observation_spec.keys()
        trajectory = env.rollout(200, policy, break_when_any_done=False)
        assert asked["checked"] == 200 and bool(trajectory["next", "done"].any())  # resets happened on the way
    finally:
        env.close()


@pytest.mark.parametrize("workers", [0, 1])
def test_a_minigame_run_starts_from_the_clone_and_distils_the_teacher(tmp_path, workers):
    """``rocketdrl-ma train`` with top-level imitate and kickstart, in the trainer's process and with a rollout
    worker: the warm start fits the normaliser once, on the bot's 400 states (PPO's own states do not move it),
    the workers act with the clone and label their states, and the checkpoint reports the teacher term."""
    cfg_path = tmp_path / "barrier.yaml"
    cfg_path.write_text(json.dumps({**load_train_config("policies/barrier_tuned.yaml").to_mapping(), **TINY,
                                    "imitate": {"bot": "barrier_shooter", "decisions": 400, "epochs": 5},
                                    "kickstart": {"bot": "barrier_shooter", "weight": 1.0, "decay_steps": 1024}}))
    assert main(["train", str(cfg_path), "--run-dir", str(tmp_path / "run"), "--workers", str(workers),
                 "--quiet"]) == 0
    state = torch.load(tmp_path / "run" / "final.pt", weights_only=True)
    assert abs(float(state["obs_norm.count"]) - 400.0) < 1e-3
    meta = json.loads((tmp_path / "run" / "final.json").read_text())
    assert meta["metrics"]["teacher_weight"] == pytest.approx(0.75)  # the last update: 256 of 1024 decay steps done
    assert 0.0 <= meta["metrics"]["teacher_disagreement"]
