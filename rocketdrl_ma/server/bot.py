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
"""
from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .protocol import Keys, ProtocolError, decode_space, decode_state, pack, unpack
from .settings import DEFAULT_ENDPOINT, ZenohSettings

log = logging.getLogger(__name__)
#: observations carry the game state; a generous bound that still refuses absurd messages
MAX_OBS_BYTES = 16 * 1024 * 1024
#: a bot that hears nothing for this long asks the lobby whether its match is still on
IDLE_CHECK_S = 2.0


class ServerError(RuntimeError):
    """The server answered a request with an error (the message says why)."""


class ServerGone(ConnectionError):
    """The server's liveliness token disappeared, or no server answers on the lobby key."""


def local_client_settings(connect: list[str] | None = None) -> ZenohSettings:
    """Client mode to a server (or router) on this machine: nothing listens on the bot's side."""
    return ZenohSettings(mode="client", connect=tuple(connect or (DEFAULT_ENDPOINT,)))


class LobbyClient:
    """Requests to a server's lobby queryable over an open Zenoh session."""

    def __init__(self, session, server: str = "local", timeout_s: float = 5.0):
        self.session, self.keys, self.timeout_s = session, Keys(server), timeout_s

    def request(self, op: str, **fields: Any) -> dict:
        replies = self.session.get(self.keys.lobby, payload=pack({"op": op, **fields}), timeout=self.timeout_s)
        for reply in replies:
            if reply.ok is not None:
                return unpack(reply.ok.payload.to_bytes(), MAX_OBS_BYTES)
            raw = reply.err.payload.to_bytes()
            try:
                message = unpack(raw).get("error", raw)
            except ProtocolError:
                message = raw.decode("utf-8", "replace")  # Zenoh's own errors, e.g. "Timeout"
            raise ServerError(f"{op}: {message}")
        raise ServerGone(f"no match server {self.keys.server!r} answered on {self.keys.lobby}")

    def create(self, config: str | dict, match_id: str | None = None, **options: Any) -> dict:
        fields = {"config": config, **options}
        if match_id is not None:
            fields["id"] = match_id
        return self.request("create", **fields)

    def list(self) -> list[dict]:
        return self.request("list")["matches"]

    def inspect(self, match: str) -> dict:
        return self.request("inspect", match=match)

    def stop(self, match: str, **fields: Any) -> dict:
        return self.request("stop", match=match, **fields)

    def join(self, match: str, slot: str | None = None, **fields: Any) -> "JoinInfo":
        return JoinInfo.from_reply(self.request("join", match=match, slot=slot, **fields))

    def leave(self, match: str, token: str) -> dict:
        return self.request("leave", match=match, token=token)


@dataclass
class JoinInfo:
    """The server's answer to a join: the seat, its secret token, and what the match looks like."""
    match: str
    slot: str
    token: str
    lease: str
    status: str
    mode: str
    deadline_ms: float
    decision_ticks: int
    config: dict
    observation: dict
    action: dict
    observation_space: Any
    action_space: Any
    keys: dict

    @classmethod
    def from_reply(cls, r: dict) -> "JoinInfo":
        return cls(match=r["match"], slot=r["slot"], token=r["token"], lease=r["lease"], status=r["status"],
                   mode=r["mode"], deadline_ms=r["deadline_ms"], decision_ticks=r["decision_ticks"],
                   config=r["config"], observation=r["observation"], action=r["action"],
                   observation_space=decode_space(r["observation_space"]),
                   action_space=decode_space(r["action_space"]), keys=r["keys"])


@dataclass
class BotReport:
    """How a bot's match went from its side."""
    match: str
    slot: str
    token: str
    decisions: int = 0  # actions sent
    reason: str = ""  # finished | stopped
    summary: dict | None = None
    errors: list[str] = field(default_factory=list)  # why the server refused some of our actions


class _Mailbox:
    """The newest observation message (older unread ones are dropped: a bot always answers the latest)."""

    def __init__(self):
        self._cond = threading.Condition()
        self._latest: bytes | None = None
        self.server_gone = False
        self.errors: list[str] = []

    def put(self, raw: bytes) -> None:
        with self._cond:
            self._latest = raw
            self._cond.notify()

    def take(self, timeout_s: float) -> bytes | None:
        with self._cond:
            if self._latest is None and not self.server_gone:
                self._cond.wait(timeout_s)
            raw, self._latest = self._latest, None
            return raw

    def gone(self) -> None:
        with self._cond:
            self.server_gone = True
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
    ``observation`` / ``action`` (a builder / parser spec such as ``"seed_sensors"`` or
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
        decision), ``scoreboard``, ``events``, ``state`` (a ``GameState`` or None), ``done`` (False)."""
        raise NotImplementedError

    def on_end(self, info: dict) -> None:
        """The match ended: ``info`` as in ``act`` plus ``summary`` and ``reason`` (finished / stopped)."""

    def run(self, match: str, slot: str | None = None, *, server: str = "local",
            zenoh: ZenohSettings | None = None, token: str | None = None, session=None,
            idle_timeout_s: float | None = None, on_joined=None) -> BotReport:
        """Join ``match`` (the named slot, any open one, or with ``token`` the slot it held) and play until
        the match ends. ``zenoh`` defaults to a client of a server on this machine; pass ``session`` to
        share an open Zenoh session. ``idle_timeout_s``: give up after this long without a message.
        ``on_joined(join)`` is called right after the join (e.g. to print the token)."""
        own = session is None
        session = session if session is not None else (zenoh or local_client_settings()).open()
        declared: list[Any] = []
        try:
            lobby = LobbyClient(session, server)
            join = lobby.join(match, slot, token=token, name=self.name, observation=self.observation,
                              action=self.action, with_state=self.with_state)
            if on_joined is not None:
                on_joined(join)
            report = BotReport(match, join.slot, join.token)
            from zenoh import SampleKind as zenoh_kinds
            mailbox = _Mailbox()
            liveliness = session.liveliness()

            def on_server(sample) -> None:
                if sample.kind == zenoh_kinds.DELETE:
                    mailbox.gone()

            def on_error(sample) -> None:
                try:
                    message = unpack(sample.payload.to_bytes()).get("error", "?")
                except ProtocolError as e:
                    message = str(e)
                mailbox.errors.append(str(message))
                log.warning("server refused an action of %s: %s", join.slot, message)

            declared.append(session.declare_subscriber(join.keys["obs"], lambda s: mailbox.put(s.payload.to_bytes())))
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
        while True:
            raw = mailbox.take(0.5)
            if raw is None:
                now = time.monotonic()
                if mailbox.server_gone:
                    raise ServerGone(f"the match server left (liveliness {join.keys['server_alive']} is gone)")
                if idle_timeout_s is not None and now - last_message > idle_timeout_s:
                    raise TimeoutError(f"no message from match {join.match!r} for {idle_timeout_s} s")
                if now - max(last_message, last_check) > IDLE_CHECK_S:
                    # Quiet for a while: not started yet, or did we miss the end? Ask the lobby.
                    last_check = now
                    try:
                        info = lobby.inspect(join.match)
                    except ServerError:  # the server no longer knows the match: long over
                        info = {"status": "finished"}
                    if info["status"] in ("finished", "stopped", "failed"):
                        report.summary, report.reason = info.get("summary"), info["status"]
                        self.on_end({"agent": join.slot, "done": True, "summary": report.summary,
                                     "reason": report.reason, "state": None})
                        return
                continue
            last_message = time.monotonic()
            message = unpack(raw, MAX_OBS_BYTES)
            info = {"agent": join.slot, "decision": message["decision"], "reward": message["reward"],
                    "scoreboard": message["scoreboard"], "events": message["events"], "done": message["done"],
                    "state": decode_state(message["state"]) if "state" in message else None}
            if message["done"]:
                report.summary, report.reason = message.get("summary"), message.get("reason", "finished")
                info.update(summary=report.summary, reason=report.reason)
                self.on_end(info)
                return
            action = self.act(np.asarray(message["obs"]), info)
            publisher.put(pack({"token": join.token, "decision": message["decision"],
                                "action": _wire_action(action)}))
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
