"""The browser view: bytes per state on the wire and frames per second in headless Chromium.

Bytes: every state of a 4v4 replay of scripted ball-chasers as the page receives it (``web/frames.py``),
against the same states in the match server's own state encoding (``server/protocol.encode_state``, what
the bridge reads from Zenoh) and the 2 kB budget. Frames per second: Debian's chromium (WebGL through
SwiftShader when there is no GPU) playing that replay at ×1 in the broadcast camera, at two window sizes,
against the same page showing only the arena (the reference: what the rendering costs before any car).
``loop ms`` is the page's own work per frame (timeline, interpolation, HUD, draw calls).

Run from the repo root (after ``make web-deps``): ``nice -n 10 .venv/bin/python benchmarks/web_view.py``
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "web"))

from rocketdrl_ma.env.replay import load_replay  # noqa: E402
from rocketdrl_ma.server.protocol import encode_state, pack_value  # noqa: E402
from rocketdrl_ma.web.frames import frame, pack_message, roster  # noqa: E402
from web_helpers import CHROMIUM_ARGS, cli, write_replay  # noqa: E402

SIZES = ((1280, 720), (640, 360))
MEASURE_S = 5.0


def wire_sizes(path: Path) -> tuple[np.ndarray, np.ndarray]:
    replay = load_replay(path)
    agents = roster(replay.state(0))["agents"]
    page = np.array([len(pack_message(frame(s, agents, s.events))) for s in replay])
    server = np.array([len(pack_value(encode_state(s))) for s in replay])
    return page, server


def fps(url: str, size: tuple[int, int]) -> dict:
    from playwright.sync_api import sync_playwright
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=shutil.which("chromium"), headless=True, args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": size[0], "height": size[1]})
        page.goto(url)
        page.wait_for_function("window.__view && window.__view.ready")
        time.sleep(MEASURE_S)
        stats = page.evaluate("window.__view.stats()")
        browser.close()
    return stats


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = write_replay(Path(tmp) / "bench" / "4v4.npz", "matches/4v4.yaml", decisions=600, seed=1)
        page_bytes, server_bytes = wire_sizes(path)
        print(f"bytes per 4v4 state ({len(page_bytes)} states): page frame mean {page_bytes.mean():.0f}, max "
              f"{page_bytes.max()} (budget 2000); server state encoding mean {server_bytes.mean():.0f} "
              f"({server_bytes.mean() / page_bytes.mean():.1f}x the page frame)")
        web = subprocess.Popen(cli("web", "--no-zenoh", "--port", "0", "--replays", str(path.parent)), cwd=ROOT,
                               stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        try:
            url = next(line.split()[2] for line in web.stdout if line.startswith("page at "))
            print(f"{'window':>10} {'arena only fps':>15} {'4v4 replay fps':>15} {'loop ms':>8}")
            for size in SIZES:
                empty = fps(url, size)
                playing = fps(url + "#replay=bench/4v4.npz", size)
                print(f"{size[0]:>5}x{size[1]:<4} {empty['fps']:>15.1f} {playing['fps']:>15.1f} "
                      f"{playing['loopMs']:>8.2f}")
        finally:
            web.terminate()
            web.wait(10)


if __name__ == "__main__":
    main()
