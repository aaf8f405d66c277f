"""Spectating a live match in a real headless Chromium: pausing and rewinding it while it goes on, back to live; after a
goal, an instant replay of its last seconds, then live again, with the goal marked on the live timeline."""
from __future__ import annotations

import pytest

from web_helpers import Procs, launch_chromium

pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("test_page")]
VIEWPORT = {"width": 1280, "height": 720}
#: 2v2 ball-chasers, seed 1: a goal 15.5 s into the 20 s clock
GOAL_MATCH = ("create", "matches/2v2.yaml", "--id", "goal", "--seed", "1", "--mode", "realtime", "--ready-timeout",
              "3", "--set", "clock_s=20", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=2")
LONG_MATCH = ("create", "matches/1v1.yaml", "--id", "long", "--mode", "realtime", "--ready-timeout", "1", "--set",
              "clock_s=120")


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    from playwright.sync_api import sync_playwright

    tmp = tmp_path_factory.mktemp("spectate")
    procs = Procs()
    try:
        _, endpoint = procs.serve(tmp, name="spectate")
        _, url = procs.web("--connect", endpoint, "--server", "spectate", "--replays", str(tmp))
        with sync_playwright() as playwright:
            browser = launch_chromium(playwright)
            yield {"url": url, "procs": procs, "endpoint": endpoint, "browser": browser}
            browser.close()
    finally:
        procs.stop_all()


def open_match(stack, match: str):
    page = stack["browser"].new_page(viewport=VIEWPORT)
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(f"{stack['url']}#match={match}")
    page.wait_for_function("window.__view && window.__view.ready", timeout=30_000)
    return page, errors


def test_a_live_match_is_paused_rewound_and_followed_again(stack):
    stack["procs"].lobby(stack["endpoint"], "spectate", *LONG_MATCH)
    page, errors = open_match(stack, "long")
    page.wait_for_function("window.__view.stats().frames > 150", timeout=120_000)  # 5 s at 30 states a second
    assert page.is_visible("#timeline") and page.evaluate("window.__view.following()")
    page.click("#play")  # pause: the view holds while the match goes on
    assert not page.evaluate("window.__view.following()")
    held = page.evaluate("window.__view.tick()")
    rewound = round(held) - 240
    page.wait_for_timeout(1000)
    assert page.evaluate("window.__view.tick()") == held
    assert page.evaluate("window.__view.lastTick()") > held + 60  # the states kept arriving
    assert page.is_visible("#go-live")
    # rewound 2 s of game time (the live buffer's ticks), stepped one state back
    page.eval_on_selector("#seek", "(el, t) => { el.value = t; el.dispatchEvent(new Event('input')); }", rewound)
    page.wait_for_function(f"window.__view.tick() === {rewound}")
    page.click("#step-back")
    assert page.evaluate("window.__view.tick()") < rewound
    assert page.inner_text("#time").startswith("-")
    page.click("#go-live")
    page.wait_for_function("window.__view.following()", timeout=5_000)
    assert page.evaluate("window.__view.tick()") > held
    page.wait_for_function("document.getElementById('time').textContent === 'live'", timeout=5_000)
    assert page.is_hidden("#go-live")
    page.close()
    assert errors == []


def test_a_goal_is_replayed_then_the_view_goes_live_with_the_goal_marked(stack):
    stack["procs"].lobby(stack["endpoint"], "spectate", *GOAL_MATCH)
    page, errors = open_match(stack, "goal")
    page.wait_for_function("window.__view.stats().frames > 5", timeout=120_000)
    page.wait_for_function("(window.__view.banner() || '').startsWith('GOAL')", timeout=60_000)
    goal_tick = page.evaluate("window.__view.tick()")  # the banner shows from the goal's tick on
    page.wait_for_function("window.__view.replaying()", timeout=10_000)
    assert page.evaluate("window.__view.banner()").startswith("REPLAY")
    assert page.evaluate("window.__view.tick()") < goal_tick  # the seconds before the goal, again
    assert not page.evaluate("window.__view.following()")
    page.wait_for_function("!window.__view.replaying() && window.__view.following()", timeout=15_000)
    assert page.evaluate("window.__view.tick()") > goal_tick
    assert page.locator("#goal-marks span").count() == 1
    page.close()
    assert errors == []
