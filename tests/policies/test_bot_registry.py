"""Scripted bots register themselves by ``bot_name`` (``ScriptedBot.__init_subclass__``): every shipped bot is known
whichever module a fresh process imports first, a user's own bot class joins by being defined, and an unknown or
taken name is a clear error."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.policies.scripted import SCRIPTED_BOTS, ScriptedBot, make_scripted

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ["aerial_shooter", "ball_chaser", "barrier_shooter", "flip_chaser", "goalie", "idle", "rotator"]

# each a fresh interpreter whose first import of the package is a different module
FIRST_IMPORTS = {
    "scripted": "from rocketdrl_ma.policies.scripted import SCRIPTED_BOTS; print(sorted(SCRIPTED_BOTS))",
    "registry": "from rocketdrl_ma.policies.registry import load_policy\n"
                "print(load_policy('scripted:barrier_shooter').name)",
    "selfplay config": "from rocketdrl_ma.policies.ppo.selfplay.config import check_selfplay\n"
                       "print(check_selfplay({'scripted': ['barrier_shooter', 'rotator']}).scripted)",
    "training config": "from rocketdrl_ma.policies.ppo.config import load_train_config\n"
                       "print(load_train_config('policies/barrier_tuned.yaml').kickstart.bot)",
}


def _fresh(code: str, *args: str, cwd: Path = ROOT) -> str:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, *(["-c", code] if code else []), *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


@pytest.mark.parametrize("first", sorted(FIRST_IMPORTS))
def test_every_shipped_bot_is_registered_whatever_is_imported_first(first):
    out = _fresh(FIRST_IMPORTS[first])
    assert "barrier_shooter" in out


def test_a_league_with_a_minigame_bot_plays_in_a_fresh_process(tmp_path):
    (tmp_path / "bots.yaml").write_text(
        "name: bots\nmatch: matches/1v1.yaml\noverrides: {clock_s: 2.0, kickoff_countdown_s: 0.0, "
        "overtime_limit_s: 0.5}\nformat: per_pair\nmatches_per_pair: 1\nresults: results.sqlite\nreport: report\n"
        "entrants:\n  - {name: shooter, policy: 'scripted:barrier_shooter'}\n"
        "  - {name: chaser, policy: 'scripted:ball_chaser'}\n")
    out = _fresh("", "-m", "rocketdrl_ma.cli", "league", "bots.yaml", cwd=tmp_path)
    assert "league bots: 1 scheduled, 0 already stored, 1 played now" in out


def test_the_registry_holds_exactly_the_shipped_bots_by_their_names():
    assert sorted(SCRIPTED_BOTS) == SHIPPED
    for name, cls in SCRIPTED_BOTS.items():
        assert cls.bot_name == name and make_scripted(name).name == f"scripted:{name}"


def test_a_users_bot_joins_by_being_defined_and_names_are_checked():
    class Reverser(ScriptedBot):
        bot_name = "test_reverser"

        def controls(self, agent, state):
            return CarControls(throttle=-1.0)

    try:
        assert isinstance(load_policy("scripted:test_reverser"), Reverser)

        class Variant(Reverser):  # no bot_name of its own: a variant, not another bot
            pass

        assert SCRIPTED_BOTS["test_reverser"] is Reverser
        with pytest.raises(ValueError, match=r"^bot_name: 'test_reverser' is taken by .*Reverser"):
            type("Impostor", (ScriptedBot,), {"bot_name": "test_reverser", "controls": Reverser.controls})
        with pytest.raises(ValueError, match=r"^bot_name: expected 1-64 letters"):
            type("Spaced", (ScriptedBot,), {"bot_name": "a bot", "controls": Reverser.controls})
    finally:
        SCRIPTED_BOTS.pop("test_reverser", None)
    with pytest.raises(ValueError, match=r"^bot: unknown scripted bot 'test_reverser'; allowed: \['aerial_shooter', "
                                         r"'ball_chaser', 'barrier_shooter', "):
        make_scripted("test_reverser")
