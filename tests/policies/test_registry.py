"""Policies by name: scripted bots load and play; bad specs name the allowed kinds."""
import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.registry import load_policy


def test_scripted_policy_plays_from_the_game_state():
    policy = load_policy("scripted:ball_chaser")
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", kickoff_countdown_s=0.0)
    env.reset(seed=0)
    policy.reset(env.rules.game_state())
    controls = policy.controls("blue_0", env.rules.game_state())
    assert isinstance(controls, CarControls) and controls.throttle == 1.0
    env.close()


@pytest.mark.parametrize("spec", ["ball_chaser", "scripted:nobody", "magic:x"])
def test_bad_specs_are_named(spec):
    with pytest.raises(ValueError, match="scripted|kind"):
        load_policy(spec)
