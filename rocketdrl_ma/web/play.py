"""A human at the page plays one slot of a real-time match, as an authenticated client of the match server.

The page server (started with ``--play``) joins the slot through the bot SDK (``rocketdrl_ma.server.bot``):
the lobby's join with the slot's ticket, the slot secret agreed at the join, every action MAC'd under it.
The page only sends its controls; it never sees the ticket or the secret, and a page drives only the seat
its own websocket took. Besides answering each decision's observation (as every bot does), the seat sends
the controls again the moment they change: a real-time match applies a slot's newest action at the next
tick, so a key press reaches the car within a tick instead of waiting for the next decision.

Matches the page server creates (``create_match``: the admin role, its secret in the server's key folder)
are real-time, with the other slots played by the server's fill bots: a scripted bot or one of the
checkpoints the page server was started with (``--opponent``); the page never names a file.
"""
from __future__ import annotations

import logging
import threading
from typing import Any

import numpy as np

from rocketdrl_ma.policies.scripted import SCRIPTED_BOTS
from rocketdrl_ma.server.bot import Bot, JoinInfo, LobbyClient
from rocketdrl_ma.server.client import ServerError, ServerGone
from rocketdrl_ma.server.protocol import action_message
from rocketdrl_ma.server.settings import ClientSettings

log = logging.getLogger(__name__)
#: the games a page may start
PLAY_CONFIGS = ("matches/1v1.yaml", "matches/2v2.yaml", "matches/3v3.yaml", "matches/4v4.yaml",
                "minigames/penalty.yaml")
#: throttle, steer, pitch, yaw, roll, jump, boost, handbrake: the continuous action format
CONTROLS = ("throttle", "steer", "pitch", "yaw", "roll", "jump", "boost", "handbrake")
#: a created match waits this long for the human before its empty slots go to the fill bots
CREATED_READY_TIMEOUT_S = 4.0


def check_controls(values: Any) -> np.ndarray:
    """The page's controls as the continuous format's vector (8 numbers in [-1, 1])."""
    if not isinstance(values, list) or len(values) != len(CONTROLS) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and -1.0 <= v <= 1.0 for v in values):
        raise ValueError(f"c: expected {len(CONTROLS)} numbers in [-1, 1] ({', '.join(CONTROLS)}), got {values!r}")
    return np.asarray(values, dtype=np.float32)


def opponent_choices(checkpoints: list[str] = ()) -> list[str]:
    """The policies a page may put against its human: every scripted bot, then the given checkpoint specs."""
    return [f"scripted:{name}" for name in sorted(SCRIPTED_BOTS)] + list(checkpoints)


class SeatLeft(Exception):
    """The page left its seat (or closed): ends the seat's bot loop at its next decision."""


class HumanSeat(Bot):
    """One page's slot. ``start`` joins and plays in a thread; ``set_controls`` from the page; ``leave``."""

    action = {"name": "continuous"}
    with_state = False

    def __init__(self, name: str, session, client: ClientSettings):
        self.name, self.session, self.client = name, session, client
        self._controls = np.zeros(len(CONTROLS), np.float32)
        self._lock = threading.Lock()
        self._left = threading.Event()
        self._joined = threading.Event()
        self._decision = 0
        self._publisher = None
        self.join_info: JoinInfo | None = None
        self.error: str | None = None
        self.ended: str | None = None  # finished | stopped, once the match is over
        self._thread: threading.Thread | None = None

    # ------------------------------------------------------------------ the bot's side (its own thread)
    def on_join(self, join: JoinInfo) -> None:
        # a publisher of our own on the slot's action key: the page's changes go out between decisions; rare, and
        # each one counts (a jump's press), so one waits for a full queue rather than being dropped
        import zenoh
        self._publisher = self.session.declare_publisher(join.keys["act"], express=True,
                                                         congestion_control=zenoh.CongestionControl.BLOCK)
        self.join_info = join
        self._joined.set()

    def act(self, obs: np.ndarray, info: dict) -> np.ndarray:
        if self._left.is_set():
            raise SeatLeft()
        with self._lock:
            self._decision = info["decision"]
            return self._controls.copy()

    def on_end(self, info: dict) -> None:
        self.ended = str(info.get("reason"))

    def _run(self, match: str, slot: str | None, ticket: str | None) -> None:
        try:
            self.run(match, slot, client=self.client, session=self.session, ticket=ticket)
        except SeatLeft:
            self._leave_lobby()
        except (ServerError, ServerGone, ValueError, TimeoutError) as e:
            log.warning("web: the human seat in match %s ended: %s", match, e)
            self.error = str(e)
        except Exception as e:  # a bug must not take the page server down
            log.exception("web: the human seat in match %s failed", match)
            self.error = str(e)
        finally:
            self._joined.set()
            if self._publisher is not None:
                self._publisher.undeclare()

    def _leave_lobby(self) -> None:
        join = self.join_info
        try:
            LobbyClient(self.session, self.client).leave(join.match, join.slot, join.secret)
        except (ServerError, ServerGone) as e:
            log.info("web: leaving %s %s: %s", join.match, join.slot, e)

    # ------------------------------------------------------------------ the page's side
    def start(self, match: str, slot: str | None, ticket: str | None, timeout_s: float = 15.0) -> JoinInfo:
        """Join (blocking until seated) and play in a thread; ValueError with the server's reason if refused."""
        self._thread = threading.Thread(target=self._run, args=(match, slot, ticket), name=f"seat-{match}",
                                        daemon=True)
        self._thread.start()
        if not self._joined.wait(timeout_s):
            self._left.set()
            raise ValueError(f"play: no seat in match {match!r} after {timeout_s:g} s")
        if self.join_info is None:
            raise ValueError(f"play: {self.error}")
        if self.join_info.mode != "realtime":
            self._left.set()
            raise ValueError(f"play: match {match!r} is {self.join_info.mode}; a human plays real-time matches only")
        return self.join_info

    def set_controls(self, values: Any) -> None:
        """The page's newest controls: answered at each decision and sent at once."""
        vector = check_controls(values)
        join = self.join_info
        # put under the lock: the bot's answer to a newer decision cannot overtake it (the server would drop this
        # one as late)
        with self._lock:
            changed = not np.array_equal(vector, self._controls)
            self._controls = vector
            if changed and join is not None and self._publisher is not None and not self._left.is_set():
                self._publisher.put(action_message(join.secret, join.match, join.slot, self._decision, vector))

    def leave(self) -> None:
        self._left.set()

    def wait(self, timeout_s: float) -> None:
        """Until the seat's thread has ended (it does at the match's next decision after ``leave``)."""
        if self._thread is not None:
            self._thread.join(timeout_s)

    @property
    def playing(self) -> bool:
        return self._thread is not None and self._thread.is_alive() and not self._left.is_set()


def create_match(lobby: LobbyClient, config: Any, opponent: Any, allowed_opponents: list[str]) -> dict:
    """A real-time match for a human: ``config`` one of ``PLAY_CONFIGS``, the other slots played by
    ``opponent`` (one of ``allowed_opponents``). The lobby's reply: its id and the slots' tickets."""
    if config not in PLAY_CONFIGS:
        raise ValueError(f"config: {config!r} is not one of {list(PLAY_CONFIGS)}")
    if opponent not in allowed_opponents:
        raise ValueError(f"opponent: {opponent!r} is not one of {allowed_opponents}")
    try:
        return lobby.create(config, mode="realtime", fill=opponent, ready_timeout_s=CREATED_READY_TIMEOUT_S)
    except (ServerError, ServerGone) as e:
        raise ValueError(f"play: the match server refused to create the match ({e})") from None
