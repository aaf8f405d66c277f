"""Spectating: follow a match's published states and events with a live scoreboard; record a replay
and render a video from them (``rocketdrl-ma watch M --video match.mp4``)."""
from __future__ import annotations

import os
import queue
import tempfile
import time
from typing import Any

from .bot import LobbyClient, ServerGone, local_client_settings
from .protocol import Keys, decode_state, unpack
from .settings import ZenohSettings

SHOWN_EVENTS = ("goal", "save", "demo", "shot")
MAX_STATE_BYTES = 16 * 1024 * 1024


def describe_event(event: dict, tick_rate: int = 120) -> str:
    t = event.get("tick", 0) / tick_rate
    kind = event["kind"]
    if kind == "goal":
        return f"{t:6.1f} s  GOAL {event.get('team')} ({event.get('scorer') or 'nobody'})"
    if kind == "demo":
        return f"{t:6.1f} s  demo: {event.get('agent')} destroyed {event.get('victim')}"
    return f"{t:6.1f} s  {kind} by {event.get('agent')}"


def scoreboard(match: str, message: dict | None, recent: list[str]):
    """A rich renderable of the latest state message: score, clock, each slot's bot and counters."""
    from rich.console import Group
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    if message is None:
        return Text(f"match {match}: waiting for the first state...")
    board = message["scoreboard"]
    score = board.get("score", {})
    clock = board.get("clock_s", 0.0)
    title = (f"match {match} [{message.get('status', '?')}]  blue {score.get('blue', 0)} - "
             f"{score.get('orange', 0)} orange   {int(clock // 60)}:{clock % 60:04.1f}"
             f"{' OT' if board.get('overtime') else ''}   decision {message['decision']}")
    table = Table(title=escape(title))  # "[running]" is no markup tag
    for column in ("slot", "bot", "occupant", "connected", "received", "missed", "late", "invalid"):
        table.add_column(column)
    for slot, s in message.get("slots", {}).items():
        style = "blue" if slot.startswith("blue") else "dark_orange"
        table.add_row(slot, str(s["bot"]), s["occupant"], "yes" if s["connected"] else "no", str(s["received"]),
                      str(s["missed"] + s["disconnected"]), str(s["late"]), str(s["invalid"]), style=style)
    return Group(table, Text("\n".join(recent[-5:])))


def watch(match: str, *, server: str = "local", zenoh: ZenohSettings | None = None, video: str | None = None,
          replay: str | None = None, live: bool = True, timeout_s: float | None = None, console=None) -> dict:
    """Follow ``match`` until it ends; returns its final message (status, summary, result key).

    ``replay`` records every published state to a replay file; ``video`` renders them afterwards (mp4 or
    gif). States published before the spectator arrived are not in either.
    """
    from rich.console import Console
    from rich.live import Live
    from zenoh import SampleKind

    console = console or Console()
    keys = Keys(server)
    states: queue.Queue = queue.Queue()
    events: queue.Queue = queue.Queue()
    session = (zenoh or local_client_settings()).open()
    declared: list[Any] = []
    writer, replay_path, tmp_dir = None, replay, None
    try:
        info = LobbyClient(session, server).inspect(match)
        if info["status"] in ("finished", "stopped", "failed"):
            raise ValueError(f"match: {match!r} already {info['status']} (result {info.get('result_key')})")
        if video and not replay_path:
            tmp_dir = tempfile.mkdtemp(prefix="rocketdrl-watch-")
            replay_path = os.path.join(tmp_dir, "match.npz")
        if replay_path:
            from rocketdrl_ma.env.replay import ReplayWriter
            writer = ReplayWriter(replay_path, meta={"match": match, "server": server, "config": info["game_config"]})
        gone = []
        declared.append(session.declare_subscriber(keys.state(match), lambda s: states.put(s.payload.to_bytes())))
        declared.append(session.declare_subscriber(keys.events(match), lambda s: events.put(s.payload.to_bytes())))
        declared.append(session.liveliness().declare_subscriber(
            keys.server_alive, lambda s: gone.append(True) if s.kind == SampleKind.DELETE else None, history=True))
        # Subscribed from here on: a caller (or a test) knows which states the replay can hold.
        console.print(f"watching match {match} on server {server!r} (status {info['status']})")
        latest, recent, final = None, [], None
        started = time.monotonic()
        with Live(scoreboard(match, None, recent), console=console, auto_refresh=False,
                  transient=False) if live else _NoLive() as view:
            while final is None:
                try:
                    raw = states.get(timeout=0.2)
                    latest = unpack(raw, MAX_STATE_BYTES)
                    if writer is not None:
                        writer.add(decode_state(latest["state"]))
                except queue.Empty:
                    pass
                while not events.empty():
                    message = unpack(events.get(), MAX_STATE_BYTES)
                    if message.get("final"):
                        final = message
                        break
                    recent += [describe_event(e) for e in message["events"] if e["kind"] in SHOWN_EVENTS]
                view.update(scoreboard(match, latest, recent), refresh=True)
                if gone and final is None and states.empty():
                    raise ServerGone(f"server {server!r} left while match {match!r} was running")
                if timeout_s is not None and time.monotonic() - started > timeout_s:
                    raise TimeoutError(f"match {match!r} did not end within {timeout_s} s")
        if live:
            console.line()  # the live view leaves its cursor at the end of its last line
        while not states.empty() and writer is not None:  # states that arrived with the final message
            writer.add(decode_state(unpack(states.get(), MAX_STATE_BYTES)["state"]))
        if writer is not None:
            writer.close()
            if video:
                from rocketdrl_ma.env.replay import render_replay
                render_replay(replay_path, video)
        return final
    finally:
        for d in reversed(declared):
            try:
                d.undeclare()
            except Exception:
                pass
        session.close()
        if tmp_dir is not None:
            for name in os.listdir(tmp_dir):
                os.remove(os.path.join(tmp_dir, name))
            os.rmdir(tmp_dir)


class _NoLive:
    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    def update(self, *args, **kwargs) -> None:
        pass
