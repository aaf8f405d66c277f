"""Spectating: follow a match's published states and events with a live scoreboard; record a replay
and render a video from them (``rocketdrl-ma watch M --video match.mp4``). Built on ``Spectator``: only
what the server signed for this match shows, goes into the replay, or ends the watch."""
from __future__ import annotations

import os
import tempfile
from typing import Any

from rocketdrl_ma.rules.events import GameEventKind, describe_event

from .protocol import ENDED_STATUSES
from .settings import ClientSettings
from .spectator import EventsUpdate, MatchEnd, Spectator, StateUpdate

SHOWN_EVENTS = (GameEventKind.GOAL, GameEventKind.SAVE, GameEventKind.DEMO, GameEventKind.SHOT)


def scoreboard(match: str, message: StateUpdate | None, recent: list[str]):
    """A rich renderable of the latest state message: score, clock, each slot's bot and counters."""
    from rich.console import Group
    from rich.markup import escape
    from rich.table import Table
    from rich.text import Text

    if message is None:
        return Text(f"match {match}: waiting for the first state...")
    board = message.scoreboard
    score = board.get("score", {})
    clock = board.get("clock_s", 0.0)
    title = (f"match {match} [{message.status}]  blue {score.get('blue', 0)} - "
             f"{score.get('orange', 0)} orange   {int(clock // 60)}:{clock % 60:04.1f}"
             f"{' OT' if board.get('overtime') else ''}   decision {message.decision}")
    table = Table(title=escape(title))  # "[running]" is no markup tag
    for column in ("slot", "bot", "occupant", "connected", "received", "missed", "late", "invalid"):
        table.add_column(column)
    for slot, s in message.slots.items():
        style = "blue" if slot.startswith("blue") else "dark_orange"
        # Text cells, never markup: a bot names itself, and "[/]" in a name would crash the view
        cells = (slot, s["bot"], s["occupant"], "yes" if s["connected"] else "no", s["received"],
                 s["missed"] + s["disconnected"], s["late"], s["invalid"])
        table.add_row(*(Text(str(cell)) for cell in cells), style=style)
    return Group(table, Text("\n".join(recent[-5:])))


def watch(match: str, *, client: ClientSettings | None = None, video: str | None = None,
          replay: str | None = None, live: bool = True, timeout_s: float | None = None, console=None,
          **client_fields: Any) -> MatchEnd:
    """Follow ``match`` until it ends; returns its end (status, summary, result key).

    ``replay`` records every published state to a replay file; ``video`` renders them afterwards (mp4 or
    gif). States published before the spectator arrived are not in either.
    """
    from rich.console import Console
    from rich.live import Live

    console = console or Console()
    writer, replay_path, tmp_dir = None, replay, None
    try:
        with Spectator(match, client=client, **client_fields) as spectator:
            info = spectator.info
            if info["status"] in ENDED_STATUSES:
                raise ValueError(f"match: {match!r} already {info['status']} (result {info.get('result_key')})")
            if video and not replay_path:
                tmp_dir = tempfile.mkdtemp(prefix="rocketdrl-watch-")
                replay_path = os.path.join(tmp_dir, "match.npz")
            if replay_path:
                from rocketdrl_ma.env.replay import ReplayWriter
                writer = ReplayWriter(replay_path, meta={"match": match, "server": spectator.client.server,
                                                         "config": info["game_config"]})
            # Subscribed from here on: a caller (or a test) knows which states the replay can hold.
            console.print(f"watching match {match} on server {spectator.client.server!r} (status {info['status']})",
                          markup=False)
            latest, recent, final = None, [], None
            with Live(scoreboard(match, None, recent), console=console, auto_refresh=False,
                      transient=False) if live else _NoLive() as view:
                recorder = DecisionRecorder(writer) if writer is not None else None
                for update in spectator.updates(timeout_s):
                    if isinstance(update, StateUpdate):
                        latest = update
                        if recorder is not None:
                            recorder.state(update)
                    elif isinstance(update, EventsUpdate):
                        recent += [describe_event(e) for e in update.events if e.kind in SHOWN_EVENTS]
                        if recorder is not None:
                            recorder.events(update)
                    else:
                        final = update
                    view.update(scoreboard(match, latest, recent), refresh=True)
                if recorder is not None:
                    recorder.flush()
            if live:
                console.line()  # the live view leaves its cursor at the end of its last line
            if spectator.dropped:
                console.print(f"dropped {sum(spectator.dropped.values())} messages that failed the checks: "
                              f"{dict(spectator.dropped)}", markup=False)
        if writer is not None:
            writer.close()
            if video:
                from rocketdrl_ma.env.replay import render_replay
                render_replay(replay_path, video)
        return final
    finally:
        if tmp_dir is not None:
            for name in os.listdir(tmp_dir):
                os.remove(os.path.join(tmp_dir, name))
            os.rmdir(tmp_dir)


class DecisionRecorder:
    """Writes each decision's state with every event of its decision. The published state carries only its last
    tick's events; the decision's events message carries all of them, and may arrive before or after its state
    (another key, another priority). A state is written once the next one comes (or at the end), with the events
    of its decision and any earlier ones that came late, each event once."""

    def __init__(self, writer):
        self.writer = writer
        self._held: StateUpdate | None = None
        self._pending: dict[int, list] = {}  # decision -> its events, until written
        self._written: set = set()  # the events already written, by kind, tick and car

    def state(self, update: StateUpdate) -> None:
        self.flush()
        self._held = update

    def events(self, update: EventsUpdate) -> None:
        self._pending.setdefault(update.decision, []).extend(update.events)

    def flush(self) -> None:
        if self._held is None:
            return
        state, decision = self._held.state, self._held.decision
        arrived = [d for d in sorted(self._pending) if d <= decision]
        events = [e for d in arrived for e in self._pending.pop(d)]
        if decision not in arrived:
            events += state.events  # its decision's events message has not come: at least the last tick's
        unique = {}
        for event in events:
            key = (event.kind, event.tick, getattr(event, "agent", None))
            if key not in self._written:
                unique.setdefault(key, event)
        self._written.update(unique)
        state.events = sorted(unique.values(), key=lambda e: e.tick)
        self.writer.add(state)
        self._held = None


class _NoLive:
    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    def update(self, *args, **kwargs) -> None:
        pass
