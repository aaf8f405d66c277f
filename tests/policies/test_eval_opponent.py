"""``rocketdrl-ma eval CHECKPOINT --opponent SPEC``: a two-team checkpoint (the penalty duel's keeper) played against
another policy on the real env; success is the checkpoint's team winning, and an opponent trained with other
sensors and actions (penalty_tuned: the seed's) plays as it learned."""
from pathlib import Path

import pytest
import torch

from rocketdrl_ma.cli import main
from rocketdrl_ma.policies.ppo import load_train_config, validate_train_config
from rocketdrl_ma.policies.ppo.checkpoint import checkpoint_meta, save_checkpoint
from rocketdrl_ma.policies.ppo.evaluate import evaluate, evaluate_against, play_against
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.policies.ppo.model import PPOModel
from rocketdrl_ma.policies.ppo.trainer import Probe

# On 2 xdist workers (`make test`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_eval_opponent")

CHECKPOINTS = Path(__file__).resolve().parents[2] / "policies" / "checkpoints"
SHORT = {"action": "lookup", "observation": "team_relative", "timeout_s": 3.0}


@pytest.fixture(scope="module")
def keeper(tmp_path_factory) -> Path:
    """An untrained keeper (orange, lookup actions, team-relative observation) saved as a checkpoint."""
    raw = load_train_config("policies/penalty_duel_keeper.yaml").to_mapping()
    cfg = validate_train_config({**raw, "env_overrides": SHORT, "hidden_units": 16,
                                 "selfplay": {**raw["selfplay"], "imitate": {}, "kickstart": {}}})
    probe = Probe.of(cfg)
    torch.manual_seed(0)
    model = PPOModel(probe.obs_dim, probe.action, cfg.hidden_units, cfg.num_layers, cfg.normalize,
                     features=cfg.features)
    meta = checkpoint_meta(cfg, model, probe.obs_dim, 0, {})
    return save_checkpoint(tmp_path_factory.mktemp("keeper") / "keeper.pt", model, meta)


def test_the_keeper_saves_every_shot_of_an_idle_shooter_and_the_side_decides_whose_success_counts(keeper):
    saves = evaluate_against(keeper, "scripted:idle", episodes=2, n_envs=2)  # its side: orange, from training
    assert (saves.episodes, saves.success_rate) == (2, 1.0)  # the timeout is a miss: the keeper's win
    assert saves.mean_return > 0.0  # the keeper's reward: the negated -0.01 per decision and the +10 of the miss
    assert saves.outcomes == {"timeout": 2}
    shots = evaluate_against(keeper, "scripted:idle", episodes=2, n_envs=2, side="blue")
    assert shots.success_rate == 0.0  # the same network shooting from blue, against an idle keeper: no goal


def test_an_opponent_trained_with_the_seeds_sensors_and_actions_plays_as_it_learned(keeper):
    # penalty_tuned (seed observation, seed actions, trained on Penalty alone) scores 99.5 % there; the duel env
    # takes its controls through the lossless continuous parser, so against a keeper that does not keep it scores.
    r = evaluate_against(keeper, f"checkpoint:{CHECKPOINTS / 'penalty_tuned.pt'}", episodes=4, n_envs=2)
    alone = evaluate(CHECKPOINTS / "penalty_tuned.pt", episodes=4, n_envs=2)
    assert alone.success_rate == 1.0
    assert r.episodes == 4 and r.success_rate < 1.0, "the untrained keeper saved every penalty_tuned shot"


def test_any_two_policies_play_and_the_side_decides_whose_win_counts():
    """Scripted bots on both sides: the scripted shooter scores past an idle keeper and an idle shooter never does."""
    shooter, idle = (lambda: load_policy("scripted:barrier_shooter")), (lambda: load_policy("scripted:idle"))
    scores = play_against("minigames/penalty_duel.yaml", SHORT, "blue", shooter, idle, episodes=4, n_envs=2)
    saves = play_against("minigames/penalty_duel.yaml", SHORT, "orange", idle, shooter, episodes=4, n_envs=2)
    assert scores.episodes == saves.episodes == 4
    assert scores.success_rate > 0.0 and saves.success_rate == 1.0 - scores.success_rate  # the same episodes
    assert play_against("minigames/penalty_duel.yaml", SHORT, "orange", idle, idle, episodes=2,
                        n_envs=2).success_rate == 1.0  # nobody shoots: every round times out, a miss


def test_bad_sides_and_games_without_an_opponent_are_refused(keeper, capsys):
    with pytest.raises(ValueError, match="side"):
        evaluate_against(keeper, "scripted:idle", episodes=1, side="green")
    with pytest.raises(ValueError, match="nobody for the opponent"):
        evaluate_against(CHECKPOINTS / "penalty_tuned.pt", "scripted:goalie", episodes=1)
    with pytest.raises(ValueError, match="policy"):
        evaluate_against(keeper, "goalie", episodes=1)


def test_the_eval_command_takes_an_opponent(keeper, capsys):
    assert main(["eval", str(keeper), "--opponent", "scripted:idle", "--episodes", "2", "--n-envs", "2"]) == 0
    out = capsys.readouterr().out
    assert "against scripted:idle: success 100.0% over 2 episodes" in out
    assert "outcomes: timeout 2" in out
    with pytest.raises(ValueError, match="--side"):
        main(["eval", str(keeper), "--side", "blue", "--episodes", "1"])


def test_the_eval_command_plays_a_scripted_bot_on_the_env_it_names(capsys):
    """A scripted teacher's own figure, on the episodes a checkpoint's evaluation plays: the aerial shooter scores the
    seed's Aerial (one team, no opponent) and an idle car never does."""
    aerial = ["--env", "minigames/aerial.yaml", "--episodes", "4", "--n-envs", "2"]
    assert main(["eval", "scripted:aerial_shooter", *aerial]) == 0
    out = capsys.readouterr().out
    assert out.startswith("scripted:aerial_shooter: success ") and "outcomes: goal" in out
    assert float(out.split("success ")[1].split("%")[0]) >= 50.0  # a floor for 4 episodes of a bot that scores most
    assert main(["eval", "scripted:idle", *aerial]) == 0
    assert "scripted:idle: success 0.0% over 4 episodes" in capsys.readouterr().out
    duel = ["--env", "minigames/penalty_duel.yaml", "--episodes", "2", "--n-envs", "2"]
    assert main(["eval", "scripted:idle", *duel, "--opponent", "scripted:idle", "--side", "orange"]) == 0
    assert "success 100.0% over 2 episodes" in capsys.readouterr().out  # nobody shoots: the keeper's rounds


def test_a_scripted_bot_needs_an_env_and_the_opponents_must_fit_it(keeper):
    with pytest.raises(ValueError, match="^--env: the env config a scripted bot plays"):
        main(["eval", "scripted:aerial_shooter", "--episodes", "1"])
    with pytest.raises(ValueError, match="^--env: "):
        main(["eval", str(keeper), "--env", "minigames/aerial.yaml", "--episodes", "1"])
    with pytest.raises(ValueError, match="^bot: unknown scripted bot 'nobot'"):
        main(["eval", "scripted:nobot", "--env", "minigames/aerial.yaml", "--episodes", "1"])
    with pytest.raises(ValueError, match="^opponent: .* has cars on the other team"):
        main(["eval", "scripted:idle", "--env", "minigames/penalty_duel.yaml", "--episodes", "1"])
    with pytest.raises(ValueError, match="^opponent: .* nobody for the opponent"):
        main(["eval", "scripted:idle", "--env", "minigames/aerial.yaml", "--opponent", "scripted:idle",
              "--episodes", "1"])
    with pytest.raises(ValueError, match="^side: .* has no orange cars"):
        main(["eval", "scripted:idle", "--env", "minigames/aerial.yaml", "--side", "orange", "--episodes", "1"])
