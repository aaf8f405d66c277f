"""The page in a real headless Chromium (Debian's, WebGL through SwiftShader), one browser for the module:
a live match from a real `rocketdrl-ma serve` whose HUD score equals the server's scoreboard after a goal,
a replay that seeks and steps to the states the file holds, and both team colours on the cars."""
from __future__ import annotations

import io
import time

import numpy as np
import pytest
from PIL import Image

from rocketdrl_ma.env.replay import load_replay
from web_helpers import PageSocket, Procs, launch_chromium, wait_for, write_replay

# On 2 xdist workers (`make test XDIST=...`) this module's tests share one, so its module fixtures are made once
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("test_page")]
VIEWPORT = {"width": 1280, "height": 720}
#: 2v2 ball-chasers, seed 1: an own goal about 15.5 s into the 20 s clock
GOAL_MATCH = ("create", "matches/2v2.yaml", "--id", "goal", "--seed", "1", "--mode", "realtime", "--ready-timeout", "3",
              "--set", "clock_s=20", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=2")


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    """A match server, a replay, a page server following both, and one Chromium."""
    from playwright.sync_api import sync_playwright

    tmp = tmp_path_factory.mktemp("page")
    replay = write_replay(tmp / "replays" / "chasers.npz", "matches/2v2.yaml", decisions=90)
    procs = Procs()
    try:
        _, endpoint = procs.serve(tmp)
        _, url = procs.web("--connect", endpoint, "--server", "web", "--replays", str(tmp / "replays"))
        with sync_playwright() as playwright:
            browser = launch_chromium(playwright)
            yield {"url": url, "procs": procs, "endpoint": endpoint, "browser": browser, "replay": replay}
            browser.close()
    finally:
        procs.stop_all()


def open_page(stack, fragment: str):
    """A page at ``url#fragment`` whose console errors and page errors are collected."""
    page = stack["browser"].new_page(viewport=VIEWPORT)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(stack["url"] + fragment)
    page.wait_for_function("window.__view && window.__view.ready", timeout=30_000)
    return page, errors


def test_webgl_works_in_this_chromium(stack):
    page = stack["browser"].new_page()
    version = page.evaluate("document.createElement('canvas').getContext('webgl2') !== null")
    page.close()
    assert version, "no WebGL 2 in headless chromium"


def test_live_match_hud_score_equals_the_server_scoreboard_after_a_goal(stack):
    procs, endpoint = stack["procs"], stack["endpoint"]
    procs.lobby(endpoint, "web", *GOAL_MATCH)
    page, errors = open_page(stack, "#match=goal")
    page.wait_for_function("window.__view.roster() !== null", timeout=30_000)
    lobby = PageSocket(stack["url"])  # the server's lobby list, through the page server
    listed = wait_for(lambda: (lambda m: m if m["status"] == "finished" else None)(lobby.matches()["goal"]), 60.0,
                      "the match to finish", interval_s=0.3)
    lobby.close()
    expected = [listed["score"]["blue"], listed["score"]["orange"]]
    assert sum(expected) >= 1, f"the set-up should have a goal: {listed}"
    page.wait_for_function(f"JSON.stringify(window.__view.hudScore()) === '{expected}'.replace(/ /g, '')",
                           timeout=15_000)
    assert page.evaluate("window.__view.hudScore()") == expected == page.evaluate("window.__view.score()")
    feed = page.inner_text("#feed")
    info = procs.inspect(endpoint, "web", "goal")
    assert [info["scoreboard"]["score"]["blue"], info["scoreboard"]["score"]["orange"]] == expected
    scorers = [agent for agent, stats in info["summary"]["stats"].items() if stats.get("goals")]
    scoring_teams = [team for team, goals in zip(("blue", "orange"), expected) if goals]
    assert all(f"GOAL {team}" in feed for team in scoring_teams), feed
    # the feed names who scored; an own goal credits nobody's goals and is marked as one
    assert any(agent in feed for agent in scorers) if scorers else "(own goal)" in feed, feed
    assert page.inner_text("#title").endswith("finished")
    page.wait_for_selector("#final-stats:not([hidden])", timeout=10_000)  # the end-of-match table
    assert all(agent in page.inner_text("#final-stats") for agent in scorers)
    stats = page.evaluate("window.__view.stats()")
    print(f"\nlive 2v2 in headless chromium (SwiftShader): {stats['fps']:.1f} fps, states received "
          f"{stats['frames']}, largest {stats['bytesMax']} bytes, page loop {stats['loopMs']:.2f} ms/frame")
    page.close()
    assert errors == []


def test_replay_seeks_and_steps_to_the_replays_states_and_shows_both_team_colours(stack):
    replay = load_replay(stack["replay"])
    page, errors = open_page(stack, "#replay=replays/chasers.npz")
    page.wait_for_function("window.__view.mode() === 'replay' && window.__view.roster() !== null", timeout=30_000)
    assert not page.is_hidden("#timeline")
    page.click("#play")  # pause

    def seek(index_or_tick: int, is_tick: bool = False) -> None:
        """Drag the timeline's slider (as a user does: it pauses) to a state, or a tick."""
        tick = index_or_tick if is_tick else int(replay.ticks[index_or_tick])
        page.eval_on_selector("#seek", "(el, t) => { el.value = t; el.dispatchEvent(new Event('input')); }", tick)
        page.wait_for_function(f"window.__view.tick() === {tick}")

    i = 40
    seek(i)
    assert page.evaluate("window.__view.frameIndex()") == i
    ball = np.array(page.evaluate("window.__view.ballPosition()"))
    assert np.allclose(ball, replay.state(i).ball.pos, atol=0.05), (ball, replay.state(i).ball.pos)
    page.click("#step-forward")
    page.wait_for_function(f"window.__view.frameIndex() === {i + 1}")
    assert np.allclose(page.evaluate("window.__view.ballPosition()"), replay.state(i + 1).ball.pos, atol=0.05)
    page.keyboard.press("ArrowLeft")
    page.keyboard.press("ArrowLeft")
    page.wait_for_function(f"window.__view.frameIndex() === {i - 1}")
    assert np.allclose(page.evaluate("window.__view.ballPosition()"), replay.state(i - 1).ball.pos, atol=0.05)
    # between two recorded states the view interpolates: halfway in ticks, halfway in space
    a, b = replay.state(i + 1), replay.state(i + 2)
    seek((a.tick + b.tick) // 2, is_tick=True)
    assert np.allclose(page.evaluate("window.__view.ballPosition()"), (a.ball.pos + b.ball.pos) / 2, atol=0.05)
    cars = page.evaluate("window.__view.carPositions()")
    shown = [(agent, car) for agent, car in zip(page.evaluate("window.__view.roster().agents"), cars) if car]
    assert len(shown) >= 2  # the demolished ones are not drawn
    for agent, car in shown:
        assert np.allclose(car, (a.cars[agent].pos + b.cars[agent].pos) / 2, atol=0.05)
    page.select_option("#speed", "4")
    page.click("#play")
    page.wait_for_function(f"window.__view.frameIndex() > {i + 5}", timeout=20_000)
    seek(i)  # pauses there

    # Both team colours, on the cars themselves: the top-down view with the HUD hidden, pixels around each car,
    # at a state where no car hides under the ball or another car.
    def apart(state) -> bool:
        points = [c.pos[:2] for c in state.cars.values() if not c.is_demoed] + [state.ball.pos[:2]]
        return len(points) == len(state.cars) + 1 and min(
            np.linalg.norm(p - q) for k, p in enumerate(points) for q in points[k + 1:]) > 400.0
    seek(next(k for k in range(len(replay)) if apart(replay.state(k))))
    page.keyboard.press("2")
    page.keyboard.press("h")
    time.sleep(0.5)  # a few frames at the new camera
    cars = page.evaluate("window.__view.carPositions()")
    teams = page.evaluate("window.__view.roster().teams")
    spots = [page.evaluate("(p) => window.__view.project(p)", car) for car in cars if car is not None]
    teams = [team for car, team in zip(cars, teams) if car is not None]
    assert set(teams) == {0, 1}
    shot = page.locator("#view").screenshot(path=str(stack["replay"].with_name("topdown.png")))
    pixels = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB")).astype(int)
    r, g, b = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    team_masks = [(b > 150) & (b > r + 60) & (b > g + 20), (r > 170) & (r > g + 50) & (g > 60) & (b < 110)]
    assert all(mask.sum() > 0 for mask in team_masks)
    for (x, y), team in zip(spots, teams):
        x, y = int(round(x)), int(round(y))
        window = team_masks[team][max(0, y - 10):y + 11, max(0, x - 10):x + 11]
        assert window.sum() >= 4, f"car of team {team} at pixel {(x, y)}: {window.sum()} pixels of its colour"
    page.close()
    assert errors == []


def test_a_training_run_is_listed_and_shown_with_its_iteration(stack, tmp_path):
    from rocketdrl_ma.policies.registry import load_policy
    from rocketdrl_ma.web.training import TrainingBroadcast

    broadcast = TrainingBroadcast("matches/1v1.yaml", "page-run", every=5, server="web",
                                  env_overrides={"clock_s": 3.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 1.0},
                                  connect=[stack["endpoint"]], replay_dir=tmp_path, speed=2.0)
    try:
        page, errors = open_page(stack, "")
        page.wait_for_selector("#list-training li:has-text('page-run')", timeout=20_000)  # the list refreshes every 3 s
        page.click("#list-training li:has-text('page-run')")
        page.wait_for_function("window.__view.mode() === 'train'")
        time.sleep(0.5)  # the page server's subscription reaches the training peer through the match server
        assert broadcast.publish(5, load_policy("scripted:ball_chaser"))
        page.wait_for_function("document.getElementById('title').textContent.includes('iteration 5')",
                               timeout=30_000)
        page.wait_for_function("window.__view.stats().frames > 10 && window.__view.roster().agents.length === 2",
                               timeout=30_000)
        assert page.evaluate("window.__view.ballPosition()") is not None
        broadcast.wait(30.0)
        page.wait_for_function("document.getElementById('title').textContent.includes('finished')", timeout=30_000)
        page.close()
    finally:
        broadcast.close()
    assert errors == []
