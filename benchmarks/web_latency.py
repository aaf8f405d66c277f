"""Playing in the browser: key press to the car's response drawn, and the frame rate of a live 4v4.

A real `rocketdrl-ma serve` and `rocketdrl-ma web --play` on loopback; Debian's chromium (WebGL through
SwiftShader when there is no GPU) at 1280x720 creates a real-time 4v4 against scripted ball-chasers and plays
blue_0. Each sample: with the car drawn on its wheels, not demolished and no kickoff countdown holding the cars
(a press could get no response then), Playwright presses the jump key for 0.15 s; the page notes the key
event's time and, at every animation frame, whether the car it draws has left the ground (5 uu above where
it stood). The latency is the time from the key event to the first frame that draws the car off the ground (read
just after the page's own frame callback has issued the drawing):
the page's websocket, the page server's seat, Zenoh, the server's next 120 Hz tick, the physics' first ticks of
the jump, the next state the real-time match publishes (60 a second), Zenoh, the page server (which sends a
player's page each state as it arrives), the websocket and the page's next frame (a player's own match is drawn
at its newest state, with no jitter buffer). Between samples the car lands and settles. fps: the page's frames
per second over the 2 s before each sample, the 4v4 live the whole time. The machine's load average is printed
before and after: figures taken beside other jobs are "loaded" figures. A press with no response within 3 s is
counted and described (the kickoff and the car's flags when it was pressed).

``--legs`` runs both servers under ``benchmarks/web_latency_probe.py`` (timestamps at each hop, on the wall
clock the page's ``performance.timeOrigin + performance.now()`` shares) and prints each leg of every answered
sample's path, and how far each unanswered press got.

Run from the repo root (after ``make web-deps``; ``rocketdrl-ma warmup`` first, or the first match compiles
its kernels): ``.venv/bin/python benchmarks/web_latency.py --samples 30`` (default 60; ``--legs``).
"""
from __future__ import annotations

import argparse
import json
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

from ports import free_port  # noqa: E402
from web_helpers import CHROMIUM_ARGS, Procs  # noqa: E402

VIEWPORT = {"width": 1280, "height": 720}
FLAG_DEMOED = 1
FLAG_ON_GROUND = 8
RISE_UU = 5.0
TICK_RATE_HZ = 120.0
GIVE_UP_MS = 3000
#: a sample starts with the car drawn on its wheels, not demolished, and no kickoff countdown holding the cars
READY = """([index, flags]) => {
  const car = (window.__view.carStates() || [])[index];
  return !!car && (car[8] & flags.onGround) !== 0 && (car[8] & flags.demoed) === 0
    && window.__view.kickoffPending() === false;
}"""
#: the page-side half of a sample: remember when the key went down, then find the first frame drawing the car up.
#: Times on the wall clock (performance.timeOrigin + performance.now(), ms) so they line up with the servers'.
WATCH_RESPONSE = """([index, riseUu, giveUpMs]) => new Promise((resolve) => {
  const standZ = window.__view.carStates()[index][2];
  const wall = (ms) => performance.timeOrigin + ms;
  let pressedAt = null, arrivedAt = null, kickoffAtPress = null, flagsAtPress = null;
  const onKey = (e) => {
    if (e.code === "Space" && pressedAt === null) {
      pressedAt = e.timeStamp;
      kickoffAtPress = window.__view.kickoffPending();
      flagsAtPress = (window.__view.carStates()[index] || [])[8];
    }
  };
  window.addEventListener("keydown", onKey);
  const giveUp = performance.now() + giveUpMs;
  const done = (result) => { window.removeEventListener("keydown", onKey); resolve(result); };
  const check = () => {
    const drawnAt = performance.now(); // after the page's own frame callback, which drew (it was first in line)
    const car = window.__view.carStates()[index], newest = window.__view.newestCar(index);
    if (pressedAt !== null && arrivedAt === null && newest && newest[2] > standZ + riseUu) {
      arrivedAt = window.__view.newestArrivalMs();
    }
    const base = { standZ, pressed: pressedAt === null ? null : wall(pressedAt), kickoffAtPress, flagsAtPress };
    if (pressedAt !== null && car && car[2] > standZ + riseUu) {
      done({ ...base, drawn: wall(drawnAt), arrived: wall(arrivedAt ?? drawnAt), tick: window.__view.shownTick() });
    } else if (performance.now() > giveUp) {
      done({ ...base, drawn: null });
    } else requestAnimationFrame(check);
  };
  requestAnimationFrame(check);
})"""
#: the legs of the path, in order (``--legs``): name, what it is
LEGS = (("key_to_send", "the key event to the page's websocket send"),
        ("send_to_page_server", "the websocket to the page server's seat"),
        ("seat_put", "the seat signs and puts the action on Zenoh"),
        ("zenoh_to_match", "Zenoh to the match server"),
        ("wait_for_tick", "waiting for the next 120 Hz tick"),
        ("jump_ticks", "the physics ticks until the car is 5 uu up (game time)"),
        ("tick_to_publish", "those ticks' wall time beyond game time, and the state's publish"),
        ("zenoh_to_page_server", "Zenoh to the page server"),
        ("page_server_hold", "the page server: verify, decode, build the frame"),
        ("websocket_to_page", "the websocket to the page"),
        ("arrival_to_drawn", "the page: the state's arrival to the frame drawing it"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=60)
    parser.add_argument("--legs", action="store_true",
                        help="run the servers under benchmarks/web_latency_probe.py and print each leg of the path")
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    load_before = os.getloadavg()
    procs = Procs()
    with tempfile.TemporaryDirectory() as tmp:
        probe = {name: Path(tmp) / f"probe-{name}.jsonl" for name in ("serve", "web")}
        try:
            if args.legs:
                endpoint = f"tcp/127.0.0.1:{free_port()}"
                procs.start(probed(probe["serve"], "serve", "server/local.yaml", "--listen", endpoint, "--name",
                                   "latency", "--results", str(Path(tmp) / "results.sqlite"))).line("serving", 60.0)
                web = procs.start(probed(probe["web"], "web", "--port", "0", "--connect", endpoint, "--server",
                                         "latency", "--play", "--replays", tmp))
                url = web.line("page at ", 60.0).split()[2]
            else:
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
                flags = {"onGround": FLAG_ON_GROUND, "demoed": FLAG_DEMOED}
                samples, fps_readings, arrivals, interrupted, started = [], [], {}, 0, time.monotonic()
                while len(samples) < args.samples:
                    page.wait_for_function(f"({READY})({json.dumps([index, flags])})", timeout=30_000)
                    time.sleep(0.3)  # settled on its wheels
                    if not page.evaluate(f"({READY})({json.dumps([index, flags])})"):
                        continue  # a kickoff began, or the car was hit, meanwhile
                    # started, not awaited: the promise resolves after the key press below
                    page.evaluate(f"(a) => {{ window.__latencySample = ({WATCH_RESPONSE})(a); }}",
                                  [index, RISE_UU, GIVE_UP_MS])
                    page.keyboard.down("Space")
                    time.sleep(0.15)
                    page.keyboard.up("Space")
                    sample = page.evaluate("window.__latencySample")
                    if sample["drawn"] is None and sample["kickoffAtPress"]:
                        interrupted += 1  # a goal came between the check and the press: the cars are held
                    else:
                        samples.append(sample)
                    fps_readings.append(page.evaluate("window.__view.stats().fps"))
                    arrivals.update(page.evaluate("window.__view.frameArrivals()"))
                    time.sleep(1.2)  # lands
                stats = page.evaluate("window.__view.stats()")
                acks_ms = page.evaluate("window.__view.inputAcksMs()")
                inputs = page.evaluate("window.__view.inputTimes()")
                browser.close()
        finally:
            procs.stop_all()
        probe_lines = {name: read_probe(path) for name, path in probe.items()} if args.legs else None
    load_after = os.getloadavg()
    answered = [s for s in samples if s["drawn"] is not None]
    missed = [s for s in samples if s["drawn"] is None]
    latencies_ms = np.array([s["drawn"] - s["pressed"] for s in answered])
    print("load average (1, 5, 15 min) before: " + " ".join(f"{v:.2f}" for v in load_before)
          + ", after: " + " ".join(f"{v:.2f}" for v in load_after) + f" on {os.cpu_count()} CPUs")
    if not len(latencies_ms):
        print(f"no sample answered ({len(missed)} without a response in {GIVE_UP_MS / 1000:g} s)")
        return
    p50, p95, p99 = np.percentile(latencies_ms, [50, 95, 99])
    print(f"key press to the car's response drawn, live 4v4 at {VIEWPORT['width']}x{VIEWPORT['height']}, "
          f"{len(latencies_ms)} samples ({len(missed)} without a response in {GIVE_UP_MS / 1000:g} s; "
          f"{interrupted} more pressed as a kickoff countdown began, left out) over "
          f"{time.monotonic() - started:.0f} s: p50 {p50:.0f} ms, p95 {p95:.0f} ms, p99 {p99:.0f} ms, "
          f"max {latencies_ms.max():.0f} ms")
    for s in missed:
        print(f"  no response: kickoff countdown at the press {s['kickoffAtPress']}, car flags {s['flagsAtPress']}, "
              f"key event seen {s['pressed'] is not None}")
    arrived_ms = np.array([s["arrived"] - s["pressed"] for s in answered])
    print("where it goes (p50 / p95): key to the page server's ack "
          f"{np.percentile(acks_ms, 50):.0f} / {np.percentile(acks_ms, 95):.0f} ms (round trip); key to the first "
          f"state showing the jump arriving {np.percentile(arrived_ms, 50):.0f} / "
          f"{np.percentile(arrived_ms, 95):.0f} ms; that state's arrival to the frame drawing it "
          f"{np.percentile(latencies_ms - arrived_ms, 50):.0f} / {np.percentile(latencies_ms - arrived_ms, 95):.0f} ms")
    print(f"page: median {np.median(fps_readings):.1f} fps (min {min(fps_readings):.1f}; each over the 2 s before a "
          f"sample), {stats['statesPerS']:.1f} states/s, page loop {stats['loopMs']:.2f} ms/frame, drawing at "
          f"pixel ratio {stats['pixelRatio']:.2f} at the end (the page draws fewer pixels below 28 fps); the page "
          f"busy after each frame: median {stats['busyAfterFrameMs'] or 0:.1f} ms over its last 120 frames (key "
          f"events and states wait meanwhile)")
    if probe_lines is not None:
        print_legs(answered, inputs, sorted(arrivals.items()), probe_lines)
        for s in missed:
            print("  unanswered: " + trace_miss(s, inputs, probe_lines))


def probed(log: Path, command: str, *args: str) -> list[str]:
    return [sys.executable, str(ROOT / "benchmarks" / "web_latency_probe.py"), str(log), command, *args]


def read_probe(path: Path) -> dict[str, list[dict]]:
    by_kind: dict[str, list[dict]] = {}
    if path.is_file():
        for line in path.read_text().splitlines():
            record = json.loads(line)
            by_kind.setdefault(record["kind"], []).append(record)
    return by_kind


def first(records: list[dict], key: str, after: float, where=lambda r: True) -> dict | None:
    return next((r for r in records if r[key] is not None and r[key] >= after and where(r)), None)


def sample_legs(sample: dict, inputs: list[dict], arrivals: list, probe: dict) -> dict[str, float] | None:
    """One answered sample's legs in ms, lined up by wall-clock time and tick; None where a point is missing."""
    serve, web = probe["serve"], probe["web"]
    ms = 1000.0
    sent = next((i for i in inputs if i["key"] is not None and abs(i["key"] - sample["pressed"]) < 1.0
                 and i["c"][5] > 0), None)
    if sent is None:
        return None
    handed = first(web.get("seat_put", []), "at", sent["sent"] / ms - 0.005, lambda r: r["jump"])
    if handed is None:
        return None
    received = first(serve.get("action_rx", []), "at", handed["at"] - 0.005, lambda r: r["jump"])
    if received is None:
        return None
    jumped = first(serve.get("tick_jump", []), "t", received["at"])
    if jumped is None:
        return None
    shown = first(serve.get("state_pub", []), "tick", jumped["tick"], lambda r: r["z"] > sample["standZ"] + RISE_UU)
    if shown is None:
        return None
    arrived = first(web.get("state_rx", []), "tick", shown["tick"])
    built = first(web.get("frame_out", []), "tick", shown["tick"])
    at_page = next(((t, at) for t, at in arrivals if t >= shown["tick"]), None)
    if arrived is None or built is None or at_page is None:
        return None
    rise_s = (shown["tick"] - jumped["tick"]) / TICK_RATE_HZ
    return {"key_to_send": sent["sent"] - sample["pressed"], "send_to_page_server": handed["at"] * ms - sent["sent"],
            "seat_put": (handed["t"] - handed["at"]) * ms, "zenoh_to_match": (received["at"] - handed["t"]) * ms,
            "wait_for_tick": (jumped["t"] - received["at"]) * ms, "jump_ticks": rise_s * ms,
            "tick_to_publish": (shown["t"] - jumped["t"] - rise_s) * ms,
            "zenoh_to_page_server": (arrived["at"] - shown["t"]) * ms,
            "page_server_hold": (built["t"] - arrived["at"]) * ms, "websocket_to_page": at_page[1] - built["t"] * ms,
            "arrival_to_drawn": sample["drawn"] - at_page[1], "total": sample["drawn"] - sample["pressed"]}


def trace_miss(sample: dict, inputs: list[dict], probe: dict) -> str:
    """How far an unanswered press got: its input, the seat's put, the match server's actions and jump ticks."""
    serve, web = probe["serve"], probe["web"]
    pressed_s = sample["pressed"] / 1000.0
    window = lambda records, key: [r for r in records if r[key] is not None  # noqa: E731
                                   and pressed_s - 0.2 <= r[key] <= pressed_s + GIVE_UP_MS / 1000.0]
    sent = [(i["n"], i["c"][5], round(i["sent"] - sample["pressed"])) for i in inputs
            if i["sent"] is not None and -200 <= i["sent"] - sample["pressed"] <= GIVE_UP_MS]
    puts = [(round((r["at"] - pressed_s) * 1000), r["jump"]) for r in window(web.get("seat_put", []), "at")]
    actions = [(round((r["at"] - pressed_s) * 1000), r["jump"], r.get("acted"), r.get("decision"))
               for r in window(serve.get("action_rx", []), "at")]
    jumps = [(round((r["t"] - pressed_s) * 1000), r["tick"]) for r in window(serve.get("tick_jump", []), "t")]
    published = window(serve.get("state_pub", []), "t")
    top = max((r["z"] for r in published), default=None)
    held = any(r.get("kickoff") for r in published)
    return (f"inputs (n, jump, ms) {sent}; seat puts (ms, jump) {puts}; match server actions (ms, jump, acted, "
            f"decision) {actions}; jump ticks (ms, tick) {jumps}; highest z published {top} (stood at "
            f"{sample['standZ']:.1f}); a kickoff countdown in the states published meanwhile: {held}")


def print_legs(answered: list[dict], inputs: list[dict], arrivals: list, probe: dict) -> None:
    legs = [leg for leg in (sample_legs(s, inputs, arrivals, probe) for s in answered) if leg is not None]
    print(f"each leg (ms; {len(legs)} of {len(answered)} samples traced; wall clock across processes, "
          f"so a leg may read a millisecond below 0): p50 / p95 / max")
    for name, meaning in (*LEGS, ("total", "key press to the car's response drawn")):
        values = np.array([leg[name] for leg in legs])
        if len(values):
            print(f"  {name:22s} {np.percentile(values, 50):7.1f} {np.percentile(values, 95):7.1f} "
                  f"{values.max():7.1f}   {meaning}")


if __name__ == "__main__":
    main()
