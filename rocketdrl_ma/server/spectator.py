"""Following a match as a spectator: its published states and events, verified and typed.

    with Spectator("M", server="local") as spec:          # or client=ClientSettings.load("web.yaml")
        for update in spec.updates():
            if isinstance(update, StateUpdate): ...        # update.state is a GameState
            elif isinstance(update, EventsUpdate): ...     # update.events: goals, touches, demos...
            elif isinstance(update, MatchEnd): ...         # the last update: status, summary, result key

Only messages signed by the server's key, for this match instance, newer than the last one on their
key, become updates; the rest is dropped and counted (``dropped``). A forged end never ends the stream.
"""
from __future__ import annotations

import functools
import queue
import time
from collections import Counter
from dataclasses import dataclass
from typing import Any, Iterator, Union

from rocketdrl_ma.rules.events import GameEvent
from rocketdrl_ma.rules.state import GameState

from .client import LobbyClient, SealedStream, ServerError, resolve_client
from .protocol import ENDED_STATUSES, Keys, MatchStatus, ProtocolError, decode_events, decode_state
from .settings import ClientSettings

#: after the end-of-match message, how long to wait for a last state still on its way
FINAL_GRACE_S = 0.5


@dataclass(frozen=True)
class StateUpdate:
    """A state as the server published it (``wire_state``: the wire map, numpy arrays): each decision's, and in a
    real-time match also every 2 ticks between decisions (with the decision's number)."""
    match: str
    decision: int
    seq: int
    status: str
    done: bool
    scoreboard: dict
    slots: dict
    wire_state: dict

    @functools.cached_property
    def state(self) -> GameState:
        return decode_state(self.wire_state)


@dataclass(frozen=True)
class EventsUpdate:
    """The events of one decision, typed (``rocketdrl_ma.rules.events``)."""
    match: str
    decision: int
    seq: int
    events: list[GameEvent]


@dataclass(frozen=True)
class MatchEnd:
    """The match is over: ``status`` finished, stopped or failed; ``summary`` (score, stats) when finished."""
    match: str
    decision: int
    status: str
    summary: dict | None
    result_key: str | None
    error: str | None


Update = Union[StateUpdate, EventsUpdate, MatchEnd]


class Spectator:
    """A verified view of one match. ``client`` (or its fields as keywords) says how to reach and trust
    the server; ``session`` shares an open Zenoh session. Use as a context manager, or ``open``/``close``."""

    def __init__(self, match: str, *, client: ClientSettings | None = None, session=None, **client_fields: Any):
        self.match = match
        self.client = resolve_client(client, **client_fields)
        self._session, self._own = session, session is None
        self._queue: queue.Queue = queue.Queue()
        self._declared: list[Any] = []
        self._server_left = False
        self._ended: MatchEnd | None = None
        self._pending_end: MatchEnd | None = None
        self._grace_until = 0.0
        self._final_state_seen = False
        self.dropped: Counter = Counter()
        self.info: dict = {}
        self.lobby: LobbyClient | None = None

    def open(self) -> "Spectator":
        """Subscribe; ``info`` is the match's verified ``inspect`` reply from then."""
        from zenoh import SampleKind
        if self._session is None:
            self._session = self.client.zenoh.open()
        try:
            self.lobby = LobbyClient(self._session, self.client)
            self.info = self.lobby.inspect(self.match)
            keys, instance = Keys(self.client.server), self.info["instance"]
            states = SealedStream(self.lobby.server_key, self.client.server, self.match, instance, ("state",),
                                  dropped=self.dropped)
            events = SealedStream(self.lobby.server_key, self.client.server, self.match, instance, ("events",),
                                  dropped=self.dropped)

            def on_state(sample) -> None:
                body = states.open(sample.payload.to_bytes())
                if body is not None:
                    self._queue.put(StateUpdate(self.match, body["decision"], body["seq"], body["status"],
                                                bool(body["done"]), body["scoreboard"], body["slots"],
                                                body["state"]))

            def on_events(sample) -> None:
                body = events.open(sample.payload.to_bytes())
                if body is None:
                    return
                if body.get("final"):
                    self._queue.put(MatchEnd(self.match, body["decision"], body["status"], body.get("summary"),
                                             body.get("result_key"), body.get("error")))
                else:
                    try:
                        decoded = decode_events(body["events"])
                    except ProtocolError:  # signed by the server yet not events this version can read
                        self.dropped["malformed"] += 1
                        return
                    self._queue.put(EventsUpdate(self.match, body["decision"], body["seq"], decoded))

            def on_server(sample) -> None:
                if sample.kind == SampleKind.DELETE:
                    self._server_left = True

            s = self._session
            self._declared = [s.declare_subscriber(keys.state(self.match), on_state),
                              s.declare_subscriber(keys.events(self.match), on_events),
                              s.liveliness().declare_subscriber(keys.server_alive, on_server, history=True)]
        except BaseException:
            self.close()
            raise
        return self

    def close(self) -> None:
        for d in reversed(self._declared):
            try:
                d.undeclare()
            except Exception:
                pass
        self._declared = []
        if self._own and self._session is not None:
            self._session.close()
        self._session = None

    def __enter__(self) -> "Spectator":
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()

    def _check_server(self) -> MatchEnd | None:
        """The server's liveliness token went away (anyone may drop one on that key): ask the lobby."""
        self._server_left = False
        try:
            info = self.lobby.inspect(self.match)
        except ServerError:
            info = {"status": MatchStatus.FINISHED, "instance": None}
        if info.get("instance") != self.info["instance"] or info["status"] in ENDED_STATUSES:
            return MatchEnd(self.match, info.get("decision", -1), info["status"], info.get("summary"),
                            info.get("result_key"), info.get("error"))
        return None

    def poll(self, timeout_s: float | None = None) -> Update | None:
        """The next update, or None after ``timeout_s`` without one (or once the end was returned).
        ``ServerGone`` when the server left without ending the match."""
        if self._ended is not None:
            return None
        end_by = None if timeout_s is None else time.monotonic() + timeout_s
        while True:
            wait = 0.2 if end_by is None else min(0.2, max(0.0, end_by - time.monotonic()))
            try:
                update = self._queue.get(timeout=wait)
            except queue.Empty:
                update = None
            if isinstance(update, MatchEnd):
                # the last state may still be on its way on the other key: give it a moment
                self._pending_end, self._grace_until = update, time.monotonic() + FINAL_GRACE_S
            elif update is not None:
                if isinstance(update, StateUpdate) and update.done:
                    self._final_state_seen = True
                return update
            if self._pending_end is not None:
                if self._final_state_seen or time.monotonic() >= self._grace_until:
                    self._ended = self._pending_end
                    return self._ended
                continue
            if self._server_left:
                checked = self._check_server()  # raises ServerGone if no signed reply comes back
                if checked is not None:
                    self._ended = checked
                    return checked
            if end_by is not None and time.monotonic() >= end_by:
                return None

    def updates(self, timeout_s: float | None = None) -> Iterator[Update]:
        """Every update until the match ends (the ``MatchEnd`` is the last); ``TimeoutError`` if it does
        not end within ``timeout_s``."""
        started = time.monotonic()
        while self._ended is None:
            left = None if timeout_s is None else timeout_s - (time.monotonic() - started)
            if left is not None and left <= 0:
                raise TimeoutError(f"match {self.match!r} did not end within {timeout_s} s")
            update = self.poll(left if left is not None else 1.0)
            if update is not None:
                yield update
