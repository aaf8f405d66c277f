"""`rocketdrl-ma play` with a checkpoint team on one side, as `make demo` runs it: the score live, a replay that
loads, and the command that opens it in the browser."""
from __future__ import annotations

import shlex
from pathlib import Path

from rocketdrl_ma.cli import main
from rocketdrl_ma.env.replay import load_replay

REPO = Path(__file__).resolve().parents[2]


def demo_play_argv() -> list[str]:
    """The arguments of the Makefile's `demo` play command (after ``rocketdrl_ma.cli``)."""
    recipe = (REPO / "Makefile").read_text().split("\ndemo:", 1)[1].split("\n\n", 1)[0].replace("\\\n", " ")
    [command] = [line for line in recipe.splitlines() if "rocketdrl_ma.cli play" in line]
    words = shlex.split(command)
    return words[words.index("rocketdrl_ma.cli") + 1:]


def with_option(argv: list[str], option: str, value: str) -> list[str]:
    i = argv.index(option)
    return argv[:i + 1] + [value] + argv[i + 2:]


def test_the_demo_plays_a_checkpoint_team_and_writes_a_replay_that_loads(tmp_path, capsys):
    argv = demo_play_argv()
    assert argv[0] == "play" and argv[argv.index("--blue") + 1].startswith("checkpoint:")
    replay_path = tmp_path / "demo" / "2v2.npz"  # a folder that does not exist yet
    argv = with_option(with_option(argv, "--clock", "4"), "--replay", str(replay_path))
    assert main(argv + ["--set", "overtime_limit_s=2", "--set", "kickoff_countdown_s=0.5"]) == 0
    out = capsys.readouterr().out
    assert "final: blue" in out
    assert f"rocketdrl-ma web --no-zenoh --replay {replay_path}" in out
    replay = load_replay(replay_path)
    assert list(replay.state(0).cars) == ["blue_0", "blue_1", "orange_0", "orange_1"]
    assert len(replay) > 4 * 15  # the reset state and at least 4 s of decisions (15 a second)
    final = replay.state(len(replay) - 1)
    score = out.split("final: blue ", 1)[1].split(" orange", 1)[0]  # "B - O"
    assert f"{final.score[0]} - {final.score[1]}" == score


def test_play_takes_a_bot_name_or_a_policy_spec_and_refuses_others(capsys):
    assert main(["play", "matches/1v1.yaml", "--blue", "scripted:rotator", "--orange", "goalie", "--clock", "1",
                 "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=1"]) == 0
    assert main(["play", "matches/1v1.yaml", "--blue", "nobody:x", "--clock", "1"]) == 2
    assert "policy: 'nobody:x'" in capsys.readouterr().err
    assert main(["play", "matches/1v1.yaml", "--set", "clock_s"]) == 2
    assert "--set: expected KEY=VALUE" in capsys.readouterr().err

