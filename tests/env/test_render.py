"""Renderer (TinyRenderer, headless) and save_video."""
from __future__ import annotations

import numpy as np
import pytest

from rocketdrl_ma.env.render import Renderer, VideoWriter, rot_mat_to_quat, save_video
from rocketdrl_ma.physics import BallState, CarState, yaw_rot_mat
from rocketdrl_ma.physics.car_config import PRESETS
from rocketdrl_ma.rules.state import GameState, Obstacle

# On 2 xdist workers (`make test`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_render")


def make_state(ball=(0.0, 0.0, 93.15), tick=0, **kw) -> GameState:
    cars = {"blue_0": CarState(pos=[-300.0, -900.0, 17.0], rot_mat=yaw_rot_mat(np.pi / 2)),
            "orange_0": CarState(pos=[300.0, 900.0, 17.0], rot_mat=yaw_rot_mat(-np.pi / 2))}
    timers = np.zeros(34)
    timers[::4] = 3.0
    kw.setdefault("obstacles", (Obstacle(np.array([0.0, -2000.0, 100.0]), np.array([400.0, 50.0, 100.0])),))
    return GameState(tick=tick, tick_rate=120, cars=cars, ball=BallState(pos=list(ball)), pad_timers=timers,
                     last_controls={}, score=(1, 2), clock_s=123.4, **kw)


@pytest.fixture(scope="module")
def renderer():
    r = Renderer(160, 90)
    yield r
    r.close()


def test_default_size_frame_is_rgb_and_not_blank():
    with Renderer() as r:
        frame = r.render(make_state())
    assert frame.shape == (360, 640, 3) and frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 10


def test_ball_moves_in_the_picture(renderer):
    # The fixed top-down camera: the ball's pixels move from the centre to the ball's new place.
    with Renderer(320, 180, camera="top", scoreboard=False) as top:
        a = top.render(make_state(ball=(0.0, 0.0, 93.15)))
        b = top.render(make_state(ball=(2000.0, 3000.0, 93.15)))
    diff = np.any(a != b, axis=2)
    assert diff.sum() > 4
    rows, cols = np.nonzero(diff)
    centre = (np.abs(rows - 90) < 6) & (np.abs(cols - 160) < 6)
    assert centre.any() and (~centre).any()  # the ball left the centre and appeared elsewhere
    # The broadcast camera follows the ball: a different picture.
    renderer.reset_camera()
    c = renderer.render(make_state(ball=(0.0, 0.0, 93.15)))
    renderer.reset_camera()
    d = renderer.render(make_state(ball=(-2500.0, 3500.0, 600.0)))
    assert np.any(c != d)


def test_cars_and_barriers_show_up():
    with Renderer(160, 90, camera="top", scoreboard=False) as top:
        full = top.render(make_state())
        empty = make_state(obstacles=())
        empty.cars.clear()
        bare = top.render(empty)
        back = top.render(make_state())
    assert np.any(full != bare)
    np.testing.assert_array_equal(full, back)  # cars that left and came back are redrawn the same


def test_demoed_car_hidden_and_configs_used():
    with Renderer(160, 90, camera="top", scoreboard=False) as top:
        base = make_state()
        shown = top.render(base)
        base.cars["blue_0"].is_demoed = True
        hidden = top.render(base)
        assert np.any(shown != hidden)
        merc = make_state(car_configs={"blue_0": PRESETS["merc"], "orange_0": PRESETS["octane"]})
        assert top.render(merc).shape == (90, 160, 3)


def test_camera_smoothing_lags_then_reset_snaps():
    with Renderer(160, 90, scoreboard=False) as r:
        r.render(make_state(ball=(0.0, 0.0, 93.15), tick=0))
        lagged = r.render(make_state(ball=(0.0, 4000.0, 93.15), tick=8))
        r.reset_camera()
        snapped = r.render(make_state(ball=(0.0, 4000.0, 93.15), tick=8))
    assert np.any(lagged != snapped)


def test_bad_arguments():
    with pytest.raises(ValueError, match="camera"):
        Renderer(160, 90, camera="drone")
    with pytest.raises(ValueError, match="width"):
        Renderer(0, 90)


def test_rot_mat_to_quat_matches_pybullet():
    import pybullet as p
    rng = np.random.default_rng(0)
    for _ in range(50):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        m = np.array(p.getMatrixFromQuaternion(q.tolist())).reshape(3, 3)
        got = np.array(rot_mat_to_quat(m))
        assert min(np.abs(got - q).max(), np.abs(got + q).max()) < 1e-9


def _frames(n=6, h=90, w=160):
    frames = []
    for i in range(n):
        f = np.zeros((h, w, 3), dtype=np.uint8)
        f[:, : (i + 1) * w // n] = (40 * i, 255 - 40 * i, 128)
        frames.append(f)
    return frames


@pytest.mark.parametrize("ext", [".gif", ".mp4"])
def test_save_video_reads_back(tmp_path, ext):
    import imageio.v2 as iio
    path = tmp_path / f"clip{ext}"
    save_video(_frames(), str(path), fps=10)
    got = iio.mimread(str(path))
    assert len(got) == 6
    assert all(np.asarray(f).shape[:2] == (90, 160) for f in got)


def test_odd_sizes_mp4(tmp_path):
    import imageio.v2 as iio
    path = tmp_path / "odd.mp4"
    save_video(_frames(3, 45, 81), str(path), fps=5)
    assert len(iio.mimread(str(path))) == 3


def test_save_video_bad_input(tmp_path):
    with pytest.raises(ValueError, match=r"\.mp4.*\.gif"):
        save_video(_frames(), str(tmp_path / "clip.avi"), fps=10)
    with pytest.raises(ValueError, match="fps"):
        save_video(_frames(), str(tmp_path / "clip.gif"), fps=0)
    with pytest.raises(ValueError, match="frames"):
        save_video([], str(tmp_path / "clip.gif"), fps=10)
    with pytest.raises(ValueError, match=r"frames\[1\]"):
        save_video([_frames()[0], np.zeros((10, 10, 3), np.uint8)], str(tmp_path / "clip.gif"), fps=10)
    with pytest.raises(ValueError, match="closed"):
        w = VideoWriter(str(tmp_path / "c.gif"), 10)
        w.append(_frames()[0])
        w.close()
        w.append(_frames()[0])
