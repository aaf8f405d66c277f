"""The viewer's fixes, each in a real headless Chromium: a killed match server shows its match lost; a replay
recorded by `rocketdrl-ma watch --replay` keeps its goal in the feed, at the match clock's time; the chase
camera keeps its car in view under a high ball; a training run's later episodes show their own iteration;
a match with no state yet says why."""
from __future__ import annotations

import math
import os
import signal
import subprocess
from collections import Counter

import numpy as np
import pytest

from rocketdrl_ma.env.replay import ReplayWriter, load_replay
from web_helpers import REPO, Procs, cli, launch_chromium, write_replay

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("test_page")]
VIEWPORT = {"width": 1280, "height": 720}
#: 2v2 ball-chasers, seed 1: a goal 15.5 s into the 20 s clock
GOAL_MATCH = ("create", "matches/2v2.yaml", "--seed", "1", "--mode", "realtime", "--ready-timeout", "8",
              "--set", "clock_s=20", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=2")
LONG_MATCH = ("create", "matches/1v1.yaml", "--mode", "realtime", "--ready-timeout", "1", "--set", "clock_s=120")


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    """A match server, a page server following it and listing a replay folder, one Chromium."""
    from playwright.sync_api import sync_playwright

    tmp = tmp_path_factory.mktemp("fixes")
    (tmp / "replays").mkdir()
    procs = Procs()
    try:
        _, endpoint = procs.serve(tmp, name="fixes")
        _, url = procs.web("--connect", endpoint, "--server", "fixes", "--replays", str(tmp / "replays"))
        with sync_playwright() as playwright:
            browser = launch_chromium(playwright)
            yield {"url": url, "procs": procs, "endpoint": endpoint, "browser": browser, "tmp": tmp}
            browser.close()
    finally:
        procs.stop_all()


@pytest.fixture
def own_server(stack, tmp_path):
    """A match server of this test alone (it is stopped or killed) and a page server following it."""
    procs = Procs()
    try:
        server, endpoint = procs.serve(tmp_path, name="own")
        _, url = procs.web("--connect", endpoint, "--server", "own", "--replays", str(tmp_path))
        yield {"server": server, "endpoint": endpoint, "url": url, "procs": procs}
    finally:
        procs.stop_all()


def open_page(browser, url: str, fragment: str):
    page = browser.new_page(viewport=VIEWPORT)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url + fragment)
    page.wait_for_function("window.__view && window.__view.ready", timeout=30_000)
    return page, errors


def hud_clock(clock_s: float, overtime: bool) -> str:
    """The scoreboard's clock as the page writes it: whole seconds left (rounded up), or "+" and the seconds
    of overtime played."""
    s = max(0, math.floor(clock_s) if overtime else math.ceil(clock_s))
    return f"{'+' if overtime else ''}{s // 60}:{s % 60:02d}"


def test_a_killed_server_shows_its_match_lost(stack, own_server):
    procs, endpoint = own_server["procs"], own_server["endpoint"]
    procs.lobby(endpoint, "own", *LONG_MATCH, "--id", "doomed")
    page, errors = open_page(stack["browser"], own_server["url"], "#match=doomed")
    page.wait_for_function("window.__view.stats().frames > 5", timeout=60_000)
    assert page.inner_text("#title").endswith("running")
    os.kill(own_server["server"].pid, signal.SIGKILL)
    own_server["server"].wait(10)
    page.wait_for_function("document.getElementById('title').textContent.endsWith('lost')", timeout=20_000)
    assert "stopped answering" in page.inner_text("#notice")
    page.close()
    assert errors == []


def test_a_match_without_a_state_yet_says_why_until_its_first_state(stack):
    """A match waiting for its bots publishes nothing, as a server compiling its kernels does: after 2 s the page
    says why, and the first state takes the hint away."""
    procs, endpoint = stack["procs"], stack["endpoint"]
    procs.lobby(endpoint, "fixes", "create", "matches/1v1.yaml", "--mode", "realtime", "--ready-timeout", "12",
                "--id", "quiet")
    page, errors = open_page(stack["browser"], stack["url"], "#match=quiet")
    page.wait_for_selector("#notice:not([hidden])", timeout=9_000)
    assert "compiles its physics kernels" in page.inner_text("#notice")
    assert page.evaluate("window.__view.stats().frames") == 0
    page.wait_for_function("window.__view.stats().frames > 0", timeout=60_000)
    page.wait_for_selector("#notice", state="hidden", timeout=5_000)
    # the match opens with its 3 s kickoff countdown, counted down on the banner
    page.wait_for_function("/^KICKOFF [123]$/.test(window.__view.banner() || '')", timeout=5_000)
    page.close()
    assert errors == []
    from rocketdrl_ma.web.bridge import first_state_hint
    assert "no state yet" in first_state_hint("match", {"status": "running"})


@pytest.fixture(scope="module")
def watched_replay(stack):
    """A real-time match with a goal, recorded by `rocketdrl-ma watch --replay` as a user does; the replay and
    the server's count of the match's events by kind."""
    procs, endpoint = stack["procs"], stack["endpoint"]
    path = stack["tmp"] / "replays" / "watched.npz"
    # the match waits 8 s for its (absent) bots: the watcher listens from its first decision
    procs.lobby(endpoint, "fixes", *GOAL_MATCH, "--id", "watched")
    done = subprocess.run(cli("watch", "watched", "--replay", str(path), "--no-live", "--timeout", "90",
                              "--connect", endpoint, "--server", "fixes"),
                          cwd=REPO, capture_output=True, text=True, timeout=150)
    assert done.returncode == 0, done.stdout + done.stderr
    return path, procs.inspect(endpoint, "fixes", "watched")["events"]


def open_replay_at_end(stack, name: str):
    page, errors = open_page(stack["browser"], stack["url"], f"#replay={name}")
    page.wait_for_function("window.__view.mode() === 'replay' && window.__view.roster() !== null", timeout=30_000)
    page.click("#play")  # pause
    page.eval_on_selector("#seek", "(el) => { el.value = el.max; el.dispatchEvent(new Event('input')); }")
    page.wait_for_function("window.__view.tick() === Number(document.getElementById('seek').max)")
    return page, errors


def test_a_watched_real_time_match_keeps_its_events_in_the_replay_and_its_feed(stack, watched_replay):
    path, server_counts = watched_replay
    replay = load_replay(path)
    events = [e for k in range(len(replay)) for e in replay.state(k).events]
    assert Counter(e.kind.value for e in events) == server_counts  # every event the server counted, once
    goals = [e for e in events if e.kind == "goal"]
    assert goals, f"the set-up should score: {server_counts}"
    page, errors = open_replay_at_end(stack, "replays/watched.npz")
    page.wait_for_function("document.getElementById('feed').textContent.includes('GOAL')", timeout=10_000)
    assert f"GOAL {goals[0].team}" in page.inner_text("#feed")
    # the spectator's extras: a mark per goal on the timeline, the goal's banner just after it, a name per car
    assert page.locator("#goal-marks span").count() == len(goals)
    after = int(next(t for t in replay.ticks if t >= goals[0].tick))
    page.eval_on_selector("#seek", "(el, t) => { el.value = t; el.dispatchEvent(new Event('input')); }", after)
    page.wait_for_function(f"window.__view.tick() === {after}")
    page.wait_for_function(f"(window.__view.banner() || '').startsWith('GOAL {goals[0].team.upper()}')", timeout=5_000)
    assert page.locator("#tags div").count() == len(page.evaluate("window.__view.roster().agents"))
    page.close()
    assert errors == []


def test_feed_times_are_the_match_clock_at_the_event(stack, watched_replay):
    replay = load_replay(watched_replay[0])
    at_goal = next(replay.state(k) for k in range(len(replay))
                   if any(e.kind == "goal" for e in replay.state(k).events))
    page, errors = open_replay_at_end(stack, "replays/watched.npz")
    line = page.wait_for_selector("#feed li:has-text('GOAL')", timeout=10_000).inner_text()
    assert line.split()[0] == hud_clock(at_goal.clock_s, at_goal.is_overtime), (line, at_goal.clock_s, at_goal.tick)
    page.close()
    assert errors == []


def test_the_chase_camera_keeps_its_car_under_a_high_ball_and_the_orbit_camera_follows_the_mouse(stack):
    """A replay whose ball hangs 1.3-2 km over the chased car: the car stays on screen at every state. Then the
    orbit camera, turned by a drag and zoomed by the wheel."""
    source = load_replay(write_replay(stack["tmp"] / "ground.npz", "matches/1v1.yaml", decisions=40))
    path = stack["tmp"] / "replays" / "high_ball.npz"
    writer = ReplayWriter(str(path), meta=dict(source.meta))
    chased = "blue_0"
    for k in range(len(source)):
        state = source.state(k)
        car = state.cars[chased].pos
        angle = 0.3 * k
        state.ball.pos = np.array([car[0] + 250 * math.cos(angle), car[1] + 250 * math.sin(angle),
                                   1300 + 18 * k], dtype=float)
        writer.add(state)
    writer.close()
    page, errors = open_page(stack["browser"], stack["url"], "#replay=replays/high_ball.npz")
    page.wait_for_function("window.__view.mode() === 'replay' && window.__view.roster() !== null", timeout=30_000)
    page.click("#play")  # pause
    index = page.evaluate("window.__view.roster().agents").index(chased)
    page.click(f"#cameras button[data-mode='chase:{index}']")
    replay = load_replay(path)
    for k in range(0, len(replay), 4):
        tick = int(replay.ticks[k])
        page.eval_on_selector("#seek", "(el, t) => { el.value = t; el.dispatchEvent(new Event('input')); }", tick)
        page.wait_for_function(f"window.__view.tick() === {tick}")
        page.wait_for_timeout(1200)  # the camera eases to its place
        car = page.evaluate("window.__view.carPositions()")[index]
        x, y = page.evaluate("(p) => window.__view.project(p)", car)
        width, height = page.evaluate("[document.getElementById('view').clientWidth, "
                                      "document.getElementById('view').clientHeight]")
        assert 0 <= x <= width and 0 <= y <= height, f"state {k}: car {car} drawn at {(x, y)}, off screen"
    # the orbit camera: a drag on the view turns it round the ball, the wheel zooms it
    page.mouse.move(640, 360)
    page.mouse.down()
    page.mouse.move(760, 330, steps=4)
    page.mouse.up()
    assert page.evaluate("window.__view.camera()") == "orbit"
    page.wait_for_timeout(1500)  # eased into place
    ball = np.array(page.evaluate("window.__view.ballPosition()"))
    turned = np.array(page.evaluate("window.__view.cameraPosition()"))
    page.mouse.wheel(0, 300)
    page.wait_for_timeout(1500)
    zoomed = np.array(page.evaluate("window.__view.cameraPosition()"))
    scene_ball = ball * [-1, 1, 1]  # the scene is the game mirrored in x
    assert np.linalg.norm(zoomed - scene_ball) > np.linalg.norm(turned - scene_ball) + 200
    page.close()
    assert errors == []


def test_a_training_runs_later_episode_shows_its_own_iteration(stack, tmp_path):
    from rocketdrl_ma.policies.registry import load_policy
    from rocketdrl_ma.web.training import TrainingBroadcast

    broadcast = TrainingBroadcast("matches/1v1.yaml", "iter-run", every=5, server="fixes",
                                  env_overrides={"clock_s": 1.5, "kickoff_countdown_s": 0.0, "overtime_limit_s": 0.5},
                                  connect=[stack["endpoint"]], replay_dir=tmp_path, speed=3.0)
    try:
        page, errors = open_page(stack["browser"], stack["url"], "#train=iter-run")
        page.wait_for_function("window.__view.mode() === 'train'")
        page.wait_for_timeout(500)  # the page server's subscription reaches the training peer
        for iteration in (5, 10):
            assert broadcast.publish(iteration, load_policy("scripted:ball_chaser"))
            page.wait_for_function(f"document.getElementById('title').textContent.includes('iteration {iteration}')",
                                   timeout=30_000)
            page.wait_for_function(
                f"document.getElementById('boost-blue').textContent.includes('@ iteration {iteration}')",
                timeout=10_000)
            broadcast.wait(30.0)
        assert "@ iteration 5" not in page.inner_text("#boost-blue")
        page.close()
    finally:
        broadcast.close()
    assert errors == []
