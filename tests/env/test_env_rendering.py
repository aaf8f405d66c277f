"""The env's rendering faces: rgb_array frames, save_video, replay files re-rendered, and `play --video`."""
import imageio.v3 as iio
import numpy as np

import rocketdrl_ma
from rocketdrl_ma.cli import main
from rocketdrl_ma.env.replay import load_replay, render_replay


def test_rgb_frames_video_and_replay_round_trip(tmp_path):
    env = rocketdrl_ma.parallel_env("matches/1v1.yaml", render_mode="rgb_array", kickoff_countdown_s=0.0,
                                    max_cycles=12)
    env.reset(seed=4)
    env.start_replay(tmp_path / "game.npz")
    frames = [env.render()]
    while env.agents:
        env.step({a: np.array([1, 0, 0, 0, 0, 0, 1, 0], np.float32) for a in env.agents})
        frames.append(env.render())
    assert all(f.dtype == np.uint8 and f.ndim == 3 and f.shape[2] == 3 for f in frames)
    assert not np.array_equal(frames[0], frames[-1])  # the cars moved
    env.save_video(tmp_path / "game.gif")
    assert iio.imread(tmp_path / "game.gif").shape[0] == len(frames)
    final = env.rules.game_state()
    env.close()

    replay = load_replay(tmp_path / "game.npz")
    assert len(replay) == 13  # the reset state and 12 decisions; the episode's end closed the file
    np.testing.assert_array_equal(replay.state(len(replay) - 1).cars["blue_0"].pos, final.cars["blue_0"].pos)
    render_replay(tmp_path / "game.npz", tmp_path / "replay.mp4")
    assert iio.imread(tmp_path / "replay.mp4").shape[0] == 13


def test_play_writes_a_video_and_prints_the_score(tmp_path, capsys):
    video = tmp_path / "match.mp4"
    config = tmp_path / "short.yaml"  # a tie at 0:00 goes to overtime: bound it too
    config.write_text("mode: match\nteam_size: 1\nclock_s: 4.0\novertime_limit_s: 2.0\n")
    assert main(["play", str(config), "--video", str(video), "--seed", "2"]) == 0
    out = capsys.readouterr().out
    assert "final: blue" in out and "winner" in out
    assert iio.imread(video).shape[0] > 10
