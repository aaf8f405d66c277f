"""Policies by name: scripted bots load and play; bad specs name the allowed kinds."""
import subprocess
import sys
from pathlib import Path

import pytest

import rocketdrl_ma
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.registry import load_policy

REPO = Path(__file__).resolve().parents[2]


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


def test_playing_a_checkpoint_loads_neither_torchrl_nor_tensordict():
    """A league worker or a bot that plays a checkpoint imports torch only: torchrl and tensordict (with torch's
    compiler, which tensordict imports) took about 3 s of every such process's start."""
    script = """
import sys
import rocketdrl_ma
from rocketdrl_ma.policies.registry import load_policy
policy = load_policy("checkpoint:policies/checkpoints/selfplay_2v2_from_1v1.pt")
env = rocketdrl_ma.parallel_env("matches/2v2.yaml")
env.reset(seed=0)
policy.reset(env.game_state)
print(policy.controls("blue_0", env.game_state))
print(sorted({m.split(".")[0] for m in sys.modules} & {"torchrl", "tensordict"}))
"""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=REPO)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[-2].startswith("CarControls(") and out.stdout.splitlines()[-1] == "[]", out.stdout
