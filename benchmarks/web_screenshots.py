"""The browser guide's screenshots (docs/web/*.png), taken from real runs in headless Chromium at 1280x720.

A `rocketdrl-ma serve` on loopback and `rocketdrl-ma web --play --league` beside it: a live 4v4 (broadcast and chase
cameras), a 4v4 replay top-down with its timeline, a 2v2 played from the keyboard against ball-chasers, the instant
replay of a live 2v2's goal, and the league page of a tiny league of scripted bots played for it. The pages are
opened with ``?sharp`` (the full pixel ratio even when the software renderer draws slowly).

Run from the repo root (after ``make web-deps`` and ``rocketdrl-ma warmup``):
``.venv/bin/python benchmarks/web_screenshots.py [--out docs/web]``.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "tests" / "web"))

from web_helpers import Procs, launch_chromium, write_replay  # noqa: E402

VIEWPORT = {"width": 1280, "height": 720}
LIVE_4V4 = ("create", "matches/4v4.yaml", "--id", "final", "--mode", "realtime", "--ready-timeout", "1", "--set",
            "clock_s=300")
#: 2v2 ball-chasers, seed 1: a goal 15.5 s into the 20 s clock
GOAL_2V2 = ("create", "matches/2v2.yaml", "--id", "goal", "--seed", "1", "--mode", "realtime", "--ready-timeout", "1",
            "--set", "clock_s=20", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=2")


def tiny_league(folder: Path) -> Path:
    """Three scripted bots, one short 1v1 per pair, played into a results store; the league config."""
    from rocketdrl_ma.league.config import load_league_config
    from rocketdrl_ma.league.runner import run_league

    config = {"name": "scripted", "match": "matches/1v1.yaml", "format": "per_pair", "matches_per_pair": 2,
              "seed": 0, "overrides": {"clock_s": 30.0, "kickoff_countdown_s": 0.0, "overtime_limit_s": 5.0},
              "results": str(folder / "results.sqlite"), "report": str(folder / "report"),
              "entrants": [{"name": n, "policy": f"scripted:{n}"} for n in ("ball_chaser", "flip_chaser", "goalie")]}
    path = folder / "league.yaml"
    path.write_text(yaml.safe_dump(config))
    run_league(load_league_config(path))
    return path


def open_page(browser, url: str):
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(url)
    page.wait_for_function("window.__view && window.__view.ready", timeout=30_000)
    return page


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs" / "web"))
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from playwright.sync_api import sync_playwright

    procs = Procs()
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        try:
            write_replay(tmp / "replays" / "final_4v4.npz", "matches/4v4.yaml", decisions=600, seed=1)
            league = tiny_league(tmp)
            _, endpoint = procs.serve(tmp, name="docs")
            _, url = procs.web("--connect", endpoint, "--server", "docs", "--play", "--replays", str(tmp / "replays"),
                               "--league", str(league))
            with sync_playwright() as playwright:
                browser = launch_chromium(playwright)
                procs.lobby(endpoint, "docs", *LIVE_4V4)
                page = open_page(browser, url + "?sharp#match=final")
                page.wait_for_function("window.__view.stats().frames > 200", timeout=300_000)
                page.keyboard.press("1")
                time.sleep(2)
                page.keyboard.press("l")  # an instant replay, if a goal just came, skipped
                time.sleep(0.5)
                page.screenshot(path=str(out / "live-broadcast.png"))
                page.keyboard.press("3")
                time.sleep(2)
                page.screenshot(path=str(out / "live-chase.png"))
                page.close()

                page = open_page(browser, url + "?sharp#replay=replays/final_4v4.npz")
                page.wait_for_function("window.__view.mode() === 'replay' && window.__view.roster() !== null")
                page.click("#play")
                page.eval_on_selector("#seek", "(el) => { el.value = Number(el.min) + 0.6 * (el.max - el.min); "
                                               "el.dispatchEvent(new Event('input')); }")
                page.keyboard.press("2")
                time.sleep(2)
                page.screenshot(path=str(out / "replay-topdown.png"))
                page.close()

                procs.lobby(endpoint, "docs", *GOAL_2V2)
                page = open_page(browser, url + "?sharp#match=goal")
                page.wait_for_function("window.__view.replaying()", timeout=120_000)
                time.sleep(2.5)
                page.screenshot(path=str(out / "live-instant-replay.png"))
                page.close()

                page = open_page(browser, url + "?sharp")
                page.wait_for_selector("#play-panel:not([hidden])", timeout=20_000)
                page.select_option("#play-config", "matches/2v2.yaml")
                page.select_option("#play-opponent", "scripted:ball_chaser")
                page.click("#play-create")
                page.wait_for_function("window.__view.seat() !== null && window.__view.stats().frames > 30",
                                       timeout=120_000)
                time.sleep(3)  # the kickoff countdown
                page.keyboard.down("KeyW")
                time.sleep(1.5)
                page.keyboard.down("ShiftLeft")
                time.sleep(0.6)
                page.screenshot(path=str(out / "play-chase.png"))
                page.keyboard.up("ShiftLeft")
                page.keyboard.up("KeyW")
                page.close()

                page = browser.new_page(viewport={"width": 1280, "height": 1000})
                page.goto(url + "league")
                page.wait_for_selector("#matches tr:nth-child(2)", timeout=30_000)
                page.screenshot(path=str(out / "league.png"), full_page=True)
                page.close()
                browser.close()
        finally:
            procs.stop_all()
    print(f"screenshots in {out}: " + ", ".join(sorted(p.name for p in out.glob("*.png"))))


if __name__ == "__main__":
    main()
