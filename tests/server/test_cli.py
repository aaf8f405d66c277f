"""The commands end to end, each its own process: ``rocketdrl-ma serve``, ``lobby create``, ``watch`` (live
scoreboard, replay and video), and two ``bot`` processes: a scripted bot and a checkpoint written by a short
real PPO run, playing through the Bot SDK. The match's result lands in the server's results store."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from server_helpers import cli

from rocketdrl_ma.env.actions import ContinuousActions
from rocketdrl_ma.env.replay import load_replay
from rocketdrl_ma.policies.registry import load_policy
from rocketdrl_ma.results import ResultsStore

# On 2 xdist workers (`make test XDIST=...`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_cli")

GAME = ["--set", "clock_s=4", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=1"]


@pytest.fixture(scope="module")
def checkpoint(tmp_path_factory) -> str:
    """A tiny PPO checkpoint (seed sensors, seed actions) from a real 128-step training run."""
    from rocketdrl_ma.policies.ppo import train, validate_train_config
    out = tmp_path_factory.mktemp("ckpt")
    cfg = validate_train_config({
        "env": "matches/1v1.yaml", "env_overrides": {"kickoff_countdown_s": 0.0, "clock_s": 4.0,
                                                     "observation": "general_sensors", "action": "drive"},
        "n_envs": 1, "buffer_size": 128, "batch_size": 64, "num_epoch": 1, "hidden_units": 16, "max_steps": 128,
        "summary_freq": 128, "checkpoint_interval": 128, "keep_checkpoints": 1, "device": "cpu"})
    train(cfg, out=out / "tiny.pt", run_dir=out / "run", progress=False)
    return str(out / "tiny.pt")


@pytest.mark.slow
def test_serve_lobby_watch_and_bots_as_commands(procs, tmp_path, checkpoint):
    served = procs.serve(tmp_path, name="cli")
    server, client = served.proc, served.client_args()
    key_line = server.line("server key ed25519:")
    assert (served.key_dir / "server.pub").read_text().strip() in key_line
    create = procs.start(cli("lobby", "create", "matches/1v1.yaml", "--id", "M", "--ready-timeout", "120", *GAME,
                             *client))
    assert create.wait(60) == 0, create.output()
    assert create.line("created match M (lockstep, slots ['blue_0', 'orange_0'])")
    # server/local.yaml: a slot needs its ticket; they are in a private file, printed only when asked
    assert not any(line.startswith("ticket ") for line in create.lines)
    tickets_file = Path(create.line("tickets in ").split()[2])
    assert tickets_file == served.key_dir / "tickets" / "M.txt" and tickets_file.stat().st_mode & 0o077 == 0
    tickets = dict(line.split() for line in tickets_file.read_text().splitlines())
    assert set(tickets) == {"blue_0", "orange_0"}
    video, replay = tmp_path / "match.mp4", tmp_path / "match.npz"
    watch = procs.start(cli("watch", "M", "--video", str(video), "--replay", str(replay), "--timeout", "300",
                            *client))
    watch.line("watching match M", 60)
    blue = procs.start(cli("bot", "--policy", "scripted:ball_chaser", "--match", "M", "--slot", "blue_0",
                           "--ticket", str(tickets_file), *client))
    orange = procs.start(cli("bot", "--policy", f"checkpoint:{checkpoint}", "--name", "tiny-ppo", "--match", "M",
                             "--ticket", tickets["orange_0"], *client))  # the slot its ticket opens: orange_0
    rejoin_file = Path(orange.line("joined match M as orange_0").split("--rejoin ")[1])
    assert rejoin_file.stat().st_mode & 0o077 == 0 and rejoin_file.read_text().startswith("orange_0:")
    for bot in (blue, orange):
        assert bot.wait(120) == 0, bot.output()
        assert bot.line("match M finished: blue ")
    assert watch.wait(300) == 0, watch.output()
    final = watch.line("match M finished: score ")
    assert "│ orange_0" in watch.output() and "tiny-ppo" in watch.output()  # the rich scoreboard's rows

    [result] = ResultsStore(tmp_path / "results.sqlite").results()
    assert f"result {result.match_key}" in final
    assert result.entrants == {"blue_0": "scripted:ball_chaser", "orange_0": "tiny-ppo"}
    assert result.details["mode"] == "lockstep" and result.config["clock_s"] == 4.0
    bots = result.details["bots"]
    decisions = result.details["timing"]["decisions"]
    assert all(b["received"] + b["missed"] + b["disconnected"] == decisions for b in bots.values())

    # The checkpoint really drove orange: each published state's orange controls are what the trained
    # policy computes from the state published one decision earlier (unless that decision was missed).
    states = list(load_replay(str(replay)))
    assert len(states) >= 10
    policy, wire = load_policy(f"checkpoint:{checkpoint}"), ContinuousActions()
    policy.reset(states[0])
    pairs = [(a, b) for a, b in zip(states, states[1:]) if b.tick - a.tick == 8]
    same = [np.allclose(b.last_controls["orange_0"].as_array(),
                        wire.parse("orange_0", wire.encode(policy.controls("orange_0", a))).as_array(), atol=1e-6)
            for a, b in pairs]
    assert len(pairs) >= 10 and sum(same) >= 0.8 * len(pairs), (len(pairs), sum(same))
    assert len({tuple(b.last_controls["orange_0"].as_array()) for _, b in pairs}) > 1  # it reacts to the game
    assert video.stat().st_size > 0

    server.popen.terminate()  # SIGTERM: a clean shutdown
    assert server.wait(30) == 0, server.output()
