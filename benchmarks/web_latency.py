"""Playing in the browser: key press to the car's response drawn, and the frame rate of a live 4v4.

A real `rocketdrl-ma serve` and `rocketdrl-ma web --play` on loopback; Debian's chromium (WebGL through
SwiftShader when there is no GPU) at 1280x720 creates a real-time 4v4 against scripted ball-chasers and plays
blue_0. Each sample: with the car on its wheels, Playwright presses the jump key; the page notes the key
event's time and, at every animation frame, whether the car it draws has left the ground (5 uu above where
it stood). The latency is the time from the key event to the first frame that draws the car off the ground (read
just after the page's own frame callback has issued the drawing):
the page's websocket, the page server's seat, Zenoh, the server's next 120 Hz tick, the physics' first ticks of
the jump, the next state the real-time match publishes (60 a second), Zenoh, the page server (which sends a
player's page each state as it arrives, up to 60 a second), the websocket and the page's next frame (a player's
own match is drawn at its newest state, with no jitter buffer). Between samples the car lands and settles. fps:
the page's frames per second over the 2 s before each sample, the 4v4 live the whole time. The machine's load
average is printed before and after: figures taken beside other jobs are "loaded" figures.

Run from the repo root (after ``make web-deps``; ``rocketdrl-ma warmup`` first, or the first match compiles
its kernels): ``nice -n 10 .venv/bin/python benchmarks/web_latency.py`` (``--samples N``, default 60).
"""
from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "tests" / "web"))

from web_helpers import CHROMIUM_ARGS, Procs  # noqa: E402

VIEWPORT = {"width": 1280, "height": 720}
FLAG_ON_GROUND = 8
RISE_UU = 5.0
#: the page-side half of a sample: remember when the key went down, then find the first frame drawing the car up
WATCH_RESPONSE = """([index, riseUu]) => new Promise((resolve) => {
  const standZ = window.__view.carStates()[index][2];
  let pressedAt = null, arrivedAt = null;
  const onKey = (e) => { if (e.code === "Space" && pressedAt === null) pressedAt = e.timeStamp; };
  window.addEventListener("keydown", onKey);
  const giveUp = performance.now() + 3000;
  const check = () => {
    const drawnAt = performance.now(); // after the page's own frame callback, which drew (it was first in line)
    const car = window.__view.carStates()[index], newest = window.__view.newestCar(index);
    if (pressedAt !== null && arrivedAt === null && newest && newest[2] > standZ + riseUu) {
      arrivedAt = window.__view.newestArrivalMs();
    }
    if (pressedAt !== null && car && car[2] > standZ + riseUu) {
      window.removeEventListener("keydown", onKey);
      resolve([drawnAt - pressedAt, (arrivedAt ?? drawnAt) - pressedAt]);
    } else if (performance.now() > giveUp) {
      window.removeEventListener("keydown", onKey);
      resolve(null);
    } else requestAnimationFrame(check);
  };
  requestAnimationFrame(check);
})"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=60)
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    load_before = os.getloadavg()
    procs = Procs()
    with tempfile.TemporaryDirectory() as tmp:
        try:
            _, endpoint = procs.serve(Path(tmp), name="latency")
            _, url = procs.web("--connect", endpoint, "--server", "latency", "--play", "--replays", tmp)
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=shutil.which("chromium"), headless=True,
                                                     args=CHROMIUM_ARGS)
                page = browser.new_page(viewport=VIEWPORT)
                page.goto(url)
                page.wait_for_function("window.__view && window.__view.ready")
                page.wait_for_selector("#play-panel:not([hidden])", timeout=20_000)
                page.select_option("#play-config", "matches/4v4.yaml")
                page.select_option("#play-opponent", "scripted:ball_chaser")
                page.click("#play-create")
                page.wait_for_function("window.__view.seat() !== null && window.__view.stats().frames > 10",
                                       timeout=300_000)
                index = page.evaluate("window.__view.roster().agents").index(page.evaluate("window.__view.seat().slot"))
                latencies_ms, arrivals_ms, fps_readings, missed, started = [], [], [], 0, time.monotonic()
                while len(latencies_ms) + missed < args.samples:
                    page.wait_for_function(f"(window.__view.carStates()[{index}] || [])[8] & {FLAG_ON_GROUND}",
                                           timeout=30_000)
                    time.sleep(0.3)  # settled on its wheels
                    # started, not awaited: the promise resolves after the key press below
                    page.evaluate(f"(a) => {{ window.__latencySample = ({WATCH_RESPONSE})(a); }}", [index, RISE_UU])
                    page.keyboard.down("Space")
                    time.sleep(0.15)
                    page.keyboard.up("Space")
                    latency = page.evaluate("window.__latencySample")
                    fps_readings.append(page.evaluate("window.__view.stats().fps"))
                    if latency is None:
                        missed += 1
                    else:
                        latencies_ms.append(latency[0])
                        arrivals_ms.append(latency[1])
                    time.sleep(1.2)  # lands
                stats = page.evaluate("window.__view.stats()")
                acks_ms = page.evaluate("window.__view.inputAcksMs()")
                browser.close()
        finally:
            procs.stop_all()
    print("load average (1, 5, 15 min) before: " + " ".join(f"{v:.2f}" for v in load_before)
          + ", after: " + " ".join(f"{v:.2f}" for v in os.getloadavg()) + f" on {os.cpu_count()} CPUs")
    values = np.array(latencies_ms)
    p50, p95, p99 = np.percentile(values, [50, 95, 99])
    print(f"key press to the car's response drawn, live 4v4 at {VIEWPORT['width']}x{VIEWPORT['height']}, "
          f"{len(values)} samples ({missed} without a response in 3 s) over {time.monotonic() - started:.0f} s: "
          f"p50 {p50:.0f} ms, p95 {p95:.0f} ms, p99 {p99:.0f} ms, max {values.max():.0f} ms")
    arrived = np.array(arrivals_ms)
    print("where it goes (p50 / p95): key to the page server's ack "
          f"{np.percentile(acks_ms, 50):.0f} / {np.percentile(acks_ms, 95):.0f} ms (round trip); key to the first "
          f"state showing the jump arriving {np.percentile(arrived, 50):.0f} / {np.percentile(arrived, 95):.0f} ms; "
          f"that state's arrival to the frame drawing it {np.percentile(values - arrived, 50):.0f} / "
          f"{np.percentile(values - arrived, 95):.0f} ms")
    print(f"page: median {np.median(fps_readings):.1f} fps (min {min(fps_readings):.1f}; each over the 2 s before a "
          f"sample), {stats['statesPerS']:.1f} states/s, page loop {stats['loopMs']:.2f} ms/frame, drawing at "
          f"pixel ratio {stats['pixelRatio']:.2f} at the end (the page draws fewer pixels below 28 fps)")


if __name__ == "__main__":
    main()
