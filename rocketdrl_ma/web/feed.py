"""The page server's one door to the Zenoh network: it lists a server's matches and the training runs that
publish evaluation episodes, and follows one of them (its states and events), read-only.

Nothing else in ``rocketdrl_ma.web`` touches Zenoh keys or payloads. A match's states and events are
signed by its server: a follower shows only those that verify against the server's key, for that match
instance, in order (``rocketdrl_ma.server.client.SealedStream``). A follower shows only the newest state
(the page shows at most ``max_rate`` states a second, decoded on ``poll``) but every event, so
throttling never loses a goal. A training run counts as its user's when Zenoh lets only that user publish
on its prefix (the server's own users), or when each message is signed by the key the server lists for that
member (``rocketdrl_ma.server.members``; unsigned ones are dropped); any other run is listed as ``unverified``.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Any, Callable

from rocketdrl_ma.rules.events import GameEvent
from rocketdrl_ma.rules.state import GameState
from rocketdrl_ma.server.client import LobbyClient, SealedStream, ServerError, ServerGone
from rocketdrl_ma.server.members import Member, open_run
from rocketdrl_ma.server.protocol import Keys, MatchStatus, ProtocolError, decode_events, decode_state, unpack
from rocketdrl_ma.validation import check_name
from rocketdrl_ma.server.settings import ClientSettings

from .training import TrainingKeys

SOURCE_KINDS = ("match", "train")
#: the largest state or events message decoded; anything bigger is dropped
MAX_STATE_BYTES = 16 * 1024 * 1024
#: unread state payloads kept between polls: the newest one that opens is shown
KEPT_STATES = 64
#: the page's status of a match whose server went away without ending it (killed, or its machine gone)
LOST_STATUS = "lost"


def _plain(payload: bytes, kind: str) -> dict | None:
    """A training run's message (not signed: a run is no match result)."""
    try:
        return unpack(payload, MAX_STATE_BYTES)
    except ProtocolError:
        return None


def _sealed(lobby: LobbyClient, info: dict) -> Callable[[bytes, str], dict | None]:
    """A match's messages: signed by its server for this match instance, newer than the last one."""
    streams = {kind: SealedStream(lobby.server_key, lobby.keys.server, info["id"], info["instance"], (kind,))
               for kind in ("state", "events")}
    return lambda payload, kind: streams[kind].open(payload)


@dataclass
class LiveState:
    """One published state: the game, the scoreboard, the match status and who plays each slot."""
    state: GameState
    scoreboard: dict
    status: str
    decision: int
    names: dict[str, str] = field(default_factory=dict)
    info: dict = field(default_factory=dict)  # a training run's iteration and run name


@dataclass
class FeedUpdate:
    """What arrived since the last poll: the newest state (or None), every event, the final message."""
    state: LiveState | None
    events: list[GameEvent]
    final: dict | None
    errors: int  # payloads that did not decode (dropped)
    server_left: bool = False  # the match server's liveliness token went away since the last poll


class Follower:
    """Follows one source's state and events keys until ``close``."""

    def __init__(self, session, state_key: str, events_key: str):
        self.info: dict = {}  # a match's lobby ``inspect`` reply when it was followed
        self.opener: Callable[[bytes, str], dict | None] = _plain  # a payload as a message, or None: dropped
        self._lock = threading.Lock()
        self._states: list[bytes] = []
        self._events: list[bytes] = []
        self._server_left = False
        self.lobby: LobbyClient | None = None  # a match's lobby, asked whether a silent server is gone
        #: called (from Zenoh's thread) when anything arrives: the page server sends it on at once, not at its next look
        self.on_arrival: Callable[[], None] = lambda: None
        self._declared = [session.declare_subscriber(state_key, self._on_state),
                          session.declare_subscriber(events_key, self._on_events)]

    def watch_server(self, session, alive_key: str) -> None:
        """Note when the server's liveliness token goes away (a killed server ends no match by itself)."""
        from zenoh import SampleKind

        def on_alive(sample) -> None:
            if sample.kind == SampleKind.DELETE:
                with self._lock:
                    self._server_left = True
                self.on_arrival()
        self._declared.append(session.liveliness().declare_subscriber(alive_key, on_alive, history=True))

    def lost_end(self) -> dict | None:
        """After the server's token went away (anyone may drop one on that key): the final message of a match
        whose server no longer answers, None while it still does (ask again at the next token loss)."""
        try:
            info = self.lobby.inspect(self.info["id"], retry_s=0.0)
        except ServerGone as e:
            return {"final": True, "status": LOST_STATUS, "summary": None, "result_key": None, "info": {},
                    "error": f"the match server stopped answering ({e})"}
        except ServerError:  # the server was restarted and no longer knows the match
            return {"final": True, "status": LOST_STATUS, "summary": None, "result_key": None, "info": {},
                    "error": "the match server no longer knows this match (restarted?)"}
        if info.get("instance") != self.info.get("instance"):
            return {"final": True, "status": LOST_STATUS, "summary": None, "result_key": None, "info": {},
                    "error": "the match server restarted: this match is gone"}
        return None

    def _on_state(self, sample) -> None:
        payload = sample.payload.to_bytes()
        with self._lock:
            self._states.append(payload)
            del self._states[:-KEPT_STATES]
        self.on_arrival()

    def _on_events(self, sample) -> None:
        payload = sample.payload.to_bytes()
        with self._lock:
            self._events.append(payload)
        self.on_arrival()

    def poll(self) -> FeedUpdate:
        with self._lock:
            raw_states, raw_events, self._states, self._events = self._states, self._events, [], []
            server_left, self._server_left = self._server_left, False
        errors, state, events, final = 0, None, [], None
        for raw in reversed(raw_states):  # the newest state that opens; older ones are not shown anyway
            message = self.opener(raw, "state")
            if message is None:
                errors += 1
                continue
            try:
                slots = message.get("slots") or {}
                state = LiveState(decode_state(message["state"]), dict(message.get("scoreboard") or {}),
                                  str(message.get("status", MatchStatus.RUNNING)), int(message.get("decision", 0)),
                                  {slot: str(s.get("bot") or s.get("occupant") or slot) for slot, s in slots.items()
                                   if isinstance(s, dict)},
                                  dict(message.get("info") or {}))
                break
            except (ProtocolError, KeyError, TypeError, ValueError):
                errors += 1
        for raw in raw_events:
            message = self.opener(raw, "events")
            if message is None:
                errors += 1
                continue
            if message.get("final"):
                final = message
            try:
                events += decode_events(message.get("events") or ())
            except ProtocolError:
                errors += 1
        return FeedUpdate(state, events, final, errors, server_left)

    def close(self) -> None:
        for declared in reversed(self._declared):
            try:
                declared.undeclare()
            except Exception:  # the session may be closing already
                pass
        self._declared = []


class SpectatorFeed:
    """A Zenoh session that reads one match server's lobby list, its matches and the training runs, as the
    client ``client`` (its user and password, the server's key it trusts)."""

    def __init__(self, client: ClientSettings, lobby_timeout_s: float = 2.0):
        self.client, self.settings, self.server = client, client.zenoh, client.server
        self.keys, self.training_keys = Keys(self.server), TrainingKeys(self.server)
        self.lobby_timeout_s = lobby_timeout_s
        self.session = None

    def open(self) -> "SpectatorFeed":
        self.session = self.settings.open()
        return self

    def close(self) -> None:
        if self.session is not None:
            self.session.close()
            self.session = None

    def matches(self) -> list[dict]:
        """The lobby's list (id, status, mode, config, score...); empty when no server answers."""
        try:
            return LobbyClient(self.session, self.client, self.lobby_timeout_s).list()
        except (ServerGone, ServerError):
            return []

    def _run_signers(self) -> tuple[dict[str, Member], set[str]]:
        """The server's members (whose runs must be signed) and the users Zenoh authenticates (whose prefix is
        theirs alone), from its signed ``members`` reply; none when no server answers."""
        try:
            reply = LobbyClient(self.session, self.client, self.lobby_timeout_s).request("members")
        except (ServerGone, ServerError, ValueError):  # no server, or no key to trust it by: nothing verified
            return {}, set()
        members = {name: Member(name, m["role"], m["key"]) for name, m in reply["members"].items()}
        return members, set(reply["zenoh_users"])

    def training_runs(self) -> list[dict]:
        """Training runs publishing evaluation episodes now (their liveliness tokens): this client's user's by
        their name, another user's as ``<user>.<run>``; ``unverified`` unless the run is a server user's or a
        member's (whose messages are checked when followed)."""
        members, zenoh_users = self._run_signers()
        runs = []
        for reply in self.session.liveliness().get(self.training_keys.all_alive, timeout=self.lobby_timeout_s):
            if reply.ok is not None:
                found = self.training_keys.parse_alive(str(reply.ok.key_expr))
                if found is not None:
                    user, run = found
                    run_id = run if user == self.client.user_name else f"{user}.{run}"
                    verified = user in zenoh_users or user in members
                    runs.append({"id": run_id, "status": "training" if verified else "unverified", "user": user})
        return sorted(runs, key=lambda r: r["id"])

    def follow(self, kind: str, source_id: Any) -> Follower:
        """Follow a match (``kind="match"``, which must exist) or a training run's evaluation episodes
        (``"train"``, which may start publishing later). Blocks for the lobby's answer."""
        if kind not in SOURCE_KINDS:
            raise ValueError(f"kind: {kind!r} is not one of {list(SOURCE_KINDS)}")
        source_id = check_name("id", source_id)
        if kind == "match":
            # subscribed first, then asked: a match that ends in between still shows its end
            follower = Follower(self.session, self.keys.state(source_id), self.keys.events(source_id))
            try:  # a match the server does not know is an error now, not a page that waits forever
                lobby = LobbyClient(self.session, self.client, self.lobby_timeout_s)
                follower.info = lobby.inspect(source_id)
            except (ServerGone, ServerError) as e:
                follower.close()
                raise ValueError(str(e)) from None
            follower.opener = _sealed(lobby, follower.info)
            follower.lobby = lobby
            follower.watch_server(self.session, self.keys.server_alive)
            return follower
        user, _, run = source_id.rpartition(".")
        user = user or self.client.user_name
        follower = Follower(self.session, self.training_keys.state(user, run), self.training_keys.events(user, run))
        member = self._run_signers()[0].get(user)
        if member is not None:  # only the member's signed messages show
            follower.opener = lambda payload, kind: open_run(member, self.server, user, run, payload, MAX_STATE_BYTES)
        return follower
