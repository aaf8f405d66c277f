"""An evaluation plays every car of one checkpoint in one forward per decision, and its episodes are those the cars'
own forwards play: the same successes, returns, lengths and outcomes."""
from pathlib import Path

from rocketdrl_ma.policies.ppo.batched import seat, seat_factory
from rocketdrl_ma.policies.ppo.checkpoint import ModelPolicy, load_model
from rocketdrl_ma.policies.ppo.evaluate import play_against
from rocketdrl_ma.policies.registry import load_policy

CHECKPOINTS = Path(__file__).resolve().parents[2] / "policies" / "checkpoints"


def test_one_forward_for_every_car_plays_the_episodes_of_one_forward_per_car():
    model, meta = load_model(CHECKPOINTS / "penalty_duel_shooter.pt")
    resolved = meta["env"]["resolved"]
    template = ModelPolicy(model, resolved)
    game = ("minigames/penalty_duel.yaml", {**meta["env"]["overrides"], "timeout_s": 3.0}, "blue")
    keeper = f"checkpoint:{CHECKPOINTS / 'penalty_duel_keeper.pt'}"
    shared = play_against(*game, lambda: seat(template), seat_factory(keeper), episodes=6, n_envs=3)
    # a model of its own for every car: each car's forward is its own, batch-1, as before batching
    alone = play_against(*game, lambda: ModelPolicy(model, resolved), lambda: load_policy(keeper), episodes=6,
                         n_envs=3)
    assert shared == alone
    assert sum(alone.outcomes.values()) == 6 and len(alone.outcomes) > 1  # goals and misses: the check has teeth
