"""Bot SDK: play a match on a match server from any process.

    class MyBot(Bot):
        name = "my-bot"
        def act(self, obs, info):          # obs: this slot's observation (numpy), info: see ``Bot.act``
            return policy(obs)             # an action in the action parser's format

    report = MyBot().run("m1", slot="blue_0")   # blocks until the match ends

The bot sees exactly what a training env gives its agent: the observation of the match's observation
builder (or the one it asks for with ``observation``), and answers in the match's action format (or
the one it asks for with ``action``), so a policy trained on the env plays remotely unchanged.
``PolicyBot`` plays any ``load_policy`` spec (``scripted:ball_chaser``, ``checkpoint:PATH``) from the
game state each message carries.

A bot acts only on what the server signed for its own slot of this match, newer than what it saw last:
forged, replayed or misdirected observations (and a forged ``done``) are dropped and counted in
``BotReport.dropped``. Each action carries a MAC under the slot's secret, agreed at the join and never sent.
"""
from __future__ import annotations

import logging
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .client import (Backoff, JoinInfo, LobbyClient, SealedStream, ServerError, ServerGone, parse_rejoin_token,
                     resolve_client)
from .protocol import ENDED_STATUSES, MatchStatus, ProtocolError, action_message, decode_events, decode_state
from .settings import DEFAULT_ENDPOINT, ClientSettings, ZenohSettings

log = logging.getLogger(__name__)
#: a bot that hears nothing for this long asks the lobby whether its match is still on
IDLE_CHECK_S = 2.0
__all__ = ["Bot", "BotReport", "JoinInfo", "LobbyClient", "PolicyBot", "ServerError", "ServerGone",
           "local_client_settings"]


def local_client_settings(connect: list[str] | None = None) -> ZenohSettings:
    """Client mode to a server (or router) on this machine: nothing listens on the bot's side."""
    return ZenohSettings(mode="client", connect=tuple(connect or (DEFAULT_ENDPOINT,)))


@dataclass
class BotReport:
    """How a bot's match went from its side."""
    match: str
    slot: str
    rejoin_token: str
    decisions: int = 0  # actions sent
    reason: str = ""  # finished | stopped
    summary: dict | None = None
    errors: list[str] = field(default_factory=list)  # why the server refused some of our actions
    dropped: Counter = field(default_factory=Counter)  # messages that failed the checks, by reason


class _Mailbox:
    """The newest verified observation (older unread ones are dropped: a bot always answers the latest)."""

    def __init__(self):
        self._cond = threading.Condition()
        self._latest: dict | None = None
        self.server_left = False  # the server's liveliness token went away (checked with the lobby)
        self.errors: list[str] = []

    def put(self, body: dict) -> None:
        with self._cond:
            self._latest = body
            self._cond.notify()

    def take(self, timeout_s: float) -> dict | None:
        with self._cond:
            if self._latest is None and not self.server_left:
                self._cond.wait(timeout_s)
            body, self._latest = self._latest, None
            return body

    def left(self) -> None:
        with self._cond:
            self.server_left = True
            self._cond.notify()


def _wire_action(action: Any) -> Any:
    if isinstance(action, (int, np.integer)) and not isinstance(action, bool):
        return int(action)
    arr = np.asarray(action)
    if arr.dtype.kind in "iu" and arr.shape in ((), (1,)):
        return int(arr.reshape(-1)[0])
    return arr.astype(np.float32) if arr.dtype.kind in "fb" else arr


class Bot:
    """Subclass and implement ``act``; ``run`` joins a match and plays it to the end.

    Class attributes a subclass may set: ``name`` (shown on scoreboards and stored with results),
    ``observation`` / ``action`` (a builder / parser spec such as ``"general_sensors"`` or
    ``{"name": "ray", "n_rays": 12}``; None = the match's), ``with_state`` (each message carries the
    full ``GameState``; scripted bots need it).
    """

    name: str = "bot"
    observation: str | dict | None = None
    action: str | dict | None = None
    with_state: bool = True

    def on_join(self, join: JoinInfo) -> None:
        """Called once seated (``join.slot``, ``join.observation_space``, ``join.action_space``...)."""

    def act(self, obs: np.ndarray, info: dict) -> Any:
        """This decision's action. ``info``: ``agent`` (the slot), ``decision``, ``reward`` (since the last
        decision), ``scoreboard``, ``events`` (typed: ``rocketdrl_ma.rules.events``), ``state`` (a ``GameState`` or None), ``done`` (False)."""
        raise NotImplementedError

    def on_end(self, info: dict) -> None:
        """The match ended: ``info`` as in ``act`` plus ``summary`` and ``reason`` (finished / stopped)."""

    def run(self, match: str, slot: str | None = None, *, client: ClientSettings | None = None, session=None,
            ticket: str | None = None, rejoin: str | None = None, idle_timeout_s: float | None = None,
            on_joined=None, **client_fields: Any) -> BotReport:
        """Join ``match`` (the named slot, or any this user may take) and play until the match ends.

        ``client`` (or its fields as keywords: ``server=``, ``zenoh=``, ``user=``, ``server_key=``...) says
        how to reach and trust the server; the default is a client of a server on this machine. Pass
        ``session`` to share an open Zenoh session. ``ticket``: the slot's ticket from the match's creator
        (not needed for open matches and seats). ``rejoin``: the ``<slot>:<secret>`` token of a slot this
        bot held before a crash. ``idle_timeout_s``: give up after this long without a message.
        ``on_joined(join)`` is called right after the join (e.g. to print ``join.rejoin_token``)."""
        client = resolve_client(client, **client_fields)
        own = session is None
        session = session if session is not None else client.zenoh.open()
        declared: list[Any] = []
        try:
            lobby = LobbyClient(session, client)
            if rejoin is not None:
                rejoin_slot, secret = parse_rejoin_token(rejoin)
                join = lobby.rejoin(match, rejoin_slot, secret)
            else:
                join = lobby.join(match, slot, ticket=ticket, name=self.name, observation=self.observation,
                                  action=self.action, with_state=self.with_state)
            if on_joined is not None:
                on_joined(join)
            report = BotReport(match, join.slot, join.rejoin_token)
            from zenoh import SampleKind as zenoh_kinds
            mailbox = _Mailbox()
            liveliness = session.liveliness()
            stream = lambda kinds: SealedStream(lobby.server_key, client.server, match, join.instance,  # noqa: E731
                                                kinds, slot=join.slot, dropped=report.dropped)
            observations, errors = stream(("obs",)), stream(("error",))

            def on_obs(sample) -> None:
                body = observations.open(sample.payload.to_bytes())
                if body is not None:
                    mailbox.put(body)

            def on_error(sample) -> None:
                body = errors.open(sample.payload.to_bytes())
                if body is not None:
                    mailbox.errors.append(str(body.get("error")))
                    log.warning("server refused an action of %s: %s", join.slot, body.get("error"))

            def on_server(sample) -> None:
                if sample.kind == zenoh_kinds.DELETE:
                    mailbox.left()

            declared.append(session.declare_subscriber(join.keys["obs"], on_obs))
            declared.append(session.declare_subscriber(join.keys["error"], on_error))
            declared.append(liveliness.declare_subscriber(join.keys["server_alive"], on_server, history=True))
            publisher = session.declare_publisher(join.keys["act"], express=True)
            declared.append(publisher)
            # Declared last: the server waits for this token, and by then our subscriber is in place.
            declared.append(liveliness.declare_token(join.keys["alive"]))
            self.on_join(join)
            self._play(join, lobby, mailbox, publisher, report, idle_timeout_s)
            report.errors = list(mailbox.errors)
            return report
        finally:
            for d in reversed(declared):
                try:
                    d.undeclare()
                except Exception:
                    pass
            if own:
                session.close()

    def _play(self, join: JoinInfo, lobby: LobbyClient, mailbox: _Mailbox, publisher, report: BotReport,
              idle_timeout_s: float | None) -> None:
        last_message = last_check = time.monotonic()
        # set while the lobby gives no signed reply (flooded, rate limited): when to ask it again
        backoff: Backoff | None = None
        retry_at: float | None = None
        while True:
            if retry_at is not None:
                mailbox.server_left = False  # already asking the lobby: only a message ends the pause early
            body = mailbox.take(0.5 if retry_at is None else min(0.5, max(0.0, retry_at - time.monotonic())))
            if body is None:
                now = time.monotonic()
                if idle_timeout_s is not None and now - last_message > idle_timeout_s:
                    raise TimeoutError(f"no message from match {join.match!r} for {idle_timeout_s} s")
                due = now >= retry_at if retry_at is not None else \
                    mailbox.server_left or now - max(last_message, last_check) > IDLE_CHECK_S
                if due:
                    # Quiet for a while, or the server's liveliness went away (anyone may declare and drop
                    # a token on that key, so only a lobby without a signed reply means it is gone):
                    # not started yet, or did we miss the end? Ask the lobby.
                    mailbox.server_left, last_check, retry_at = False, now, None
                    try:
                        info = lobby.inspect(join.match, retry_s=0.0)
                    except ServerError:  # the server no longer knows the match: long over
                        info = {"status": MatchStatus.FINISHED, "instance": join.instance}
                    except ServerGone as e:
                        # asked again after a pause, waiting for observations meanwhile: a flood of the lobby
                        # must not make a bot quit, nor miss its match while it waits for the lobby
                        backoff = backoff or Backoff(lobby.client.inspect_retry_s)
                        pause_s = backoff.next_pause_s()
                        if pause_s is None:
                            raise backoff.gave_up(f"inspect {join.match!r}", e) from None
                        log.info("inspect %r: no signed reply (%s); trying again in %.2f s", join.match, e, pause_s)
                        retry_at = time.monotonic() + pause_s
                        continue
                    backoff = None
                    if info.get("instance") != join.instance or info["status"] in ENDED_STATUSES:
                        report.summary, report.reason = info.get("summary"), info["status"]
                        self.on_end({"agent": join.slot, "done": True, "summary": report.summary,
                                     "reason": report.reason, "state": None})
                        return
                continue
            last_message, backoff, retry_at = time.monotonic(), None, None
            try:
                info = {"agent": join.slot, "decision": body["decision"], "reward": body["reward"],
                        "scoreboard": body["scoreboard"], "events": decode_events(body["events"]),
                        "done": body["done"], "state": decode_state(body["state"]) if "state" in body else None}
            except ProtocolError:  # signed by the server, yet not a message this version can read
                report.dropped["malformed"] += 1
                continue
            if body["done"]:
                report.summary, report.reason = body.get("summary"), body.get("reason", MatchStatus.FINISHED)
                info.update(summary=report.summary, reason=report.reason)
                self.on_end(info)
                return
            action = self.act(np.asarray(body["obs"]), info)
            publisher.put(action_message(join.secret, join.match, join.slot, body["decision"], _wire_action(action)))
            report.decisions += 1


class PolicyBot(Bot):
    """Plays a ``load_policy`` spec (``scripted:ball_chaser``, ``checkpoint:PATH``...) from the game state.

    It asks for the continuous action format, which carries any ``CarControls`` exactly, so a policy's
    controls reach the car unchanged whatever format the match uses.
    """

    action = {"name": "continuous"}

    def __init__(self, spec: str, name: str | None = None):
        from rocketdrl_ma.env.actions import ContinuousActions
        from rocketdrl_ma.policies.registry import load_policy

        self.policy = load_policy(spec)
        self.name = name or spec
        self._encoder = ContinuousActions()
        self._reset_done = False

    def act(self, obs: np.ndarray, info: dict) -> np.ndarray:
        state = info["state"]
        if not self._reset_done:
            self.policy.reset(state)
            self._reset_done = True
        return self._encoder.encode(self.policy.controls(info["agent"], state))
