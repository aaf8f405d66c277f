"""The penalty duel's two learners: a self-play learner on a fixed side, opponent slots filled from another run's
snapshots, and one alternation of ``rocketdrl-ma duel`` at tiny size on the real env and trainer."""
import json

import numpy as np
import pytest
import torch

from rocketdrl_ma.cli import main
from rocketdrl_ma.policies.ppo import TrainConfig, load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.checkpoint import load_model, read_meta
from rocketdrl_ma.policies.ppo.curves import read_scalars
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.policies.ppo.selfplay.games import SelfPlayGames
from rocketdrl_ma.policies.ppo.selfplay.imitation import collect
from rocketdrl_ma.policies.ppo.selfplay.pool import OpponentPool
from rocketdrl_ma.policies.scripted import make_scripted

OVERRIDES = {"action": "lookup", "observation": "team_relative", "timeout_s": 2.0}
TINY = {"env_overrides": OVERRIDES, "n_envs": 2, "buffer_size": 128, "batch_size": 64, "num_epoch": 1,
        "hidden_units": 32, "summary_freq": 128, "checkpoint_interval": 128, "keep_checkpoints": 1}


def _learner(name: str, **selfplay) -> TrainConfig:
    raw = load_train_config(f"policies/penalty_duel_{name}.yaml").to_mapping()
    return validate_train_config({**raw, **TINY, "selfplay": {**raw["selfplay"], "imitate": {}, "kickstart": {},
                                                              "snapshot_interval": 128, "pool_size": 2,
                                                              **selfplay}})


def test_a_fixed_side_learner_plays_that_team_in_every_episode():
    games = SelfPlayGames(_learner("keeper"), 2)
    rng = np.random.default_rng(0)
    try:
        obs = games.reset()
        episodes = 0
        for _ in range(150):  # 2 s episodes: several per copy
            assert games.learner_team == ["orange", "orange"]
            assert games.learners(0) == games.learners(1) == ["orange_0"]
            step, results, _ = games.step(rng.integers(0, 90, 2), rng.integers(0, 90, 2))
            obs = step.obs
            ended = step.terminated | step.truncated
            if ended.any():
                episodes += int(ended.sum())
                obs = games.reset_copies(ended, obs)
        assert episodes >= 4
    finally:
        games.close()


def test_the_warm_start_of_a_fixed_side_learner_records_only_its_team():
    obs, labels = collect("minigames/penalty_duel.yaml", OVERRIDES, "goalie", "barrier_shooter", 120, seed=3,
                          side="orange")
    from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
    env = RocketDRLParallelEnv("minigames/penalty_duel.yaml", **OVERRIDES)
    keeper, shooter = make_scripted("goalie"), make_scripted("barrier_shooter")
    seen = env.reset(seed=3)[0]
    for t in range(120):  # the same episodes again, the goalie always in orange
        assert np.array_equal(seen["orange_0"], obs[t])
        label = env.action_parser.encode(keeper.controls("orange_0", env.game_state))
        assert np.array_equal(label, labels[t])
        seen = env.step({"orange_0": label,
                         "blue_0": env.action_parser.encode(shooter.controls("blue_0", env.game_state))})[0]
        if not env.agents:
            seen = env.reset()[0]
    env.close()


def _learner_yamls(tmp_path) -> list[str]:
    """The two tiny learners as YAML files (the ``duel`` command reads files; JSON is YAML)."""
    configs = []
    for name in ("shooter", "keeper"):
        path = tmp_path / f"{name}.yaml"
        path.write_text(json.dumps({**_learner(name).to_mapping(), "env": "minigames/penalty_duel.yaml"}))
        configs.append(str(path))
    return configs


@pytest.mark.slow
def test_one_alternation_trains_each_learner_against_the_others_snapshots(tmp_path):
    """``rocketdrl-ma duel``: the shooter's phase meets only the scripted goalie (no keeper yet), the keeper's phase
    has the shooter's two snapshots in its slots, and a second call resumes both learners."""
    configs = _learner_yamls(tmp_path)
    root = tmp_path / "duel"
    args = ["duel", *configs, "--cycles", "1", "--phase-steps", "256", "--root", str(root), "--workers", "0",
            "--quiet"]
    assert main(args) == 0
    for name in ("shooter", "keeper"):
        assert read_meta(root / name / "final.pt")["agent_steps"] == 256
        assert sorted(p.name for p in (root / name / "snapshots").glob("step_*[0-9].pt")) == \
            ["step_128.pt", "step_256.pt"]
    # who each learner's pool held, from its TensorBoard log
    assert read_scalars(root / "shooter", "selfplay/pfsp_weight/scripted:goalie")
    assert not read_scalars(root / "shooter", "selfplay/pfsp_weight/keeper/snapshot:128", required=False)
    for step in (128, 256):
        assert read_scalars(root / "keeper", f"selfplay/pfsp_weight/shooter/snapshot:{step}")

    assert main(args) == 0  # the next cycle: both resumed, the shooter now meets the keeper's snapshots
    assert read_meta(root / "shooter" / "final.pt")["agent_steps"] == 512
    assert read_meta(root / "keeper" / "final.pt")["agent_steps"] == 512
    assert read_scalars(root / "shooter", "selfplay/pfsp_weight/keeper/snapshot:256")

    # the slots hold the other learner's weights, and a network of another shape is refused by name
    keeper = _learner("keeper", opponent_runs=[str(root / "shooter")])
    model, meta = load_model(root / "keeper" / "final.pt")
    pool = OpponentPool(keeper, tmp_path / "k2", meta["network"]["obs_dim"])
    pool.attach(model, 512)
    newest, _ = load_model(root / "shooter" / "snapshots" / "step_512.pt")
    slot = pool.slot_names.index("shooter/snapshot:512")
    assert all(torch.equal(a, b) for a, b in zip(pool.slot_models[slot].state_dict().values(),
                                                 newest.state_dict().values()))
    small = PPOModel(meta["network"]["obs_dim"], meta["network"]["action"], 16, 2, True,
                     features=meta["network"]["features"])
    with pytest.raises(ValueError, match="selfplay.opponent_runs: .* is not shaped like this learner's network"):
        OpponentPool(keeper, tmp_path / "k3", meta["network"]["obs_dim"]).attach(small, 512)


def test_a_stop_request_ends_the_duel_with_the_phase_it_arrives_in(tmp_path, monkeypatch, capsys):
    """Ctrl-C or SIGTERM in the shooter's phase: that phase writes its checkpoint and the keeper's never starts
    (before, the runner went on to the next learner, so only killing the process stopped a duel)."""
    from rocketdrl_ma.policies.ppo import trainer

    class StopAfterFirstIteration(trainer.StopRequest):
        """The signal, arriving during the first iteration: ``requested`` turns true after the loop's first check."""

        def __init__(self):
            super().__init__()
            self.checks = 0

        @property
        def requested(self):
            self.checks += 1
            return self.checks > 1

        @requested.setter
        def requested(self, value):
            pass

    monkeypatch.setattr(trainer, "StopRequest", StopAfterFirstIteration)
    configs = _learner_yamls(tmp_path)
    root = tmp_path / "duel"
    assert main(["duel", *configs, "--cycles", "2", "--phase-steps", "1024", "--root", str(root), "--workers", "0",
                 "--quiet"]) == 0
    assert read_meta(root / "shooter" / "final.pt")["agent_steps"] == 128  # one iteration (buffer_size 128)
    assert not (root / "keeper").exists()
    assert "(stopped: the duel ends here" in capsys.readouterr().out
