"""The shipped minigame checkpoints still play their game: a few greedy episodes on seeds no training run used, at
difficulty 1, through the evaluation of docs/results.md's table (``rocketdrl-ma eval``, with ``--opponent`` for the
penalty duel's two learners)."""
from pathlib import Path

import pytest

from rocketdrl_ma.policies.ppo.checkpoint import load_model
from rocketdrl_ma.policies.ppo.evaluate import evaluate, evaluate_against

CHECKPOINTS = Path(__file__).resolve().parents[2] / "policies" / "checkpoints"


@pytest.mark.slow
@pytest.mark.parametrize("name", ["penalty_tuned", "barrier_tuned", "barrier_seed_actions", "aerial_taught",
                                  "aerial_tuned", "aerial_explore_10M"])
def test_a_shipped_minigame_checkpoint_scores(name):
    path = CHECKPOINTS / f"{name}.pt"
    _, meta = load_model(path)
    assert meta["env"]["resolved"]["difficulty"] == 1.0  # evaluation plays the full task
    result = evaluate(path, episodes=6, seed=90_210, n_envs=2)
    assert result.episodes == 6
    assert result.success_rate > 0.0, f"{name}: no goal in 6 greedy episodes"


@pytest.mark.slow
@pytest.mark.parametrize("name, opponent", [
    ("penalty_duel_shooter", "scripted:goalie"),
    ("penalty_duel_shooter", f"checkpoint:{CHECKPOINTS / 'penalty_duel_keeper.pt'}"),
    ("penalty_duel_keeper", f"checkpoint:{CHECKPOINTS / 'penalty_tuned.pt'}"),
], ids=lambda value: value.replace(str(CHECKPOINTS), "policies/checkpoints"))  # ids the same in any clone
def test_a_penalty_duel_checkpoint_wins_against_its_opponents(name, opponent):
    """The shooter scores, the keeper saves, at least once in 6 episodes, each on the side it trained on."""
    result = evaluate_against(CHECKPOINTS / f"{name}.pt", opponent, episodes=6, seed=90_210, n_envs=2)
    assert result.episodes == 6
    assert result.success_rate > 0.0, f"{name} against {opponent}: no win in 6 greedy episodes"
