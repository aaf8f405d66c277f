"""One match's seats: who plays each agent slot, its secret, its counters, the observation builder and action
parser its bot asked for; and each remote slot's observations of the game.

A slot is ``open`` (nobody yet), ``remote`` (a bot joined and holds its secret; it may be connected or
not, per its Zenoh liveliness token and its recent actions) or ``fill`` (the server plays it: a scripted
bot or idle). A slot may be reserved: for a ticket's holder, or for a user (a seat).
"""
from __future__ import annotations

import secrets
from dataclasses import dataclass, field

import numpy as np

from rocketdrl_ma.env.actions import ActionParser
from rocketdrl_ma.env.observations import ObsBuilder
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.rules.state import GameState

NEUTRAL = CarControls()


@dataclass
class Slot:
    name: str
    occupant: str = "open"  # open | remote | fill
    bot: str | None = None  # the entrant's name
    user: str | None = None  # the player's user: its keys live under rocketdrl/<server>/u/<user>
    secret: bytes | None = None  # agreed at the join (X25519); keys every action's MAC
    rejoin_key: bytes | None = None  # agreed with it: what a rejoin proves (never the action key)
    ticket: bytes | None = None  # needed to join this slot unless the match is open or the slot a seat
    seat: str | None = None  # the only user who may join this slot
    lease: str | None = None  # public id of the current connection's liveliness token
    alive: bool = False
    stalled: bool = False  # missed a streak of decisions: not waited for until its next action
    left: bool = False  # the bot left a running match: its secret no longer works
    obs_spec: dict | None = None  # a requested observation builder (None: the match's)
    action_spec: dict | None = None
    obs_builder: ObsBuilder | None = None
    action_parser: ActionParser | None = None
    with_state: bool = True
    last_controls: CarControls = field(default_factory=CarControls)
    pending: CarControls | None = None  # this decision's action, once it arrived
    acted_decision: int = -1  # last decision this slot answered
    missed_streak: int = 0
    counts: dict = field(default_factory=lambda: dict.fromkeys(
        ("received", "missed", "disconnected", "late", "invalid"), 0))

    def take(self, bot: str, user: str, secret: bytes, rejoin_key: bytes) -> None:
        self.occupant, self.bot, self.user, self.secret, self.left = "remote", bot, user, secret, False
        self.rejoin_key = rejoin_key
        self.new_lease()

    def new_lease(self) -> None:
        self.lease = secrets.token_hex(8)
        self.alive = self.stalled = False
        self.missed_streak = 0

    def release(self) -> None:
        self.occupant, self.bot, self.user, self.secret, self.lease, self.alive = "open", None, None, None, None, False
        self.rejoin_key = None
        self.obs_spec = self.action_spec = self.obs_builder = self.action_parser = None

    def heard(self) -> None:
        """An authenticated action arrived: the bot is there, whatever its liveliness says."""
        self.missed_streak, self.stalled = 0, False

    def missed(self, streak_limit: int) -> str:
        """Count one decision without this slot's action; ``missed`` or ``disconnected``."""
        if not self.waits_for:
            self.counts["disconnected"] += 1
            return "disconnected"
        self.counts["missed"] += 1
        self.missed_streak += 1
        if streak_limit and self.missed_streak >= streak_limit:
            self.stalled = True  # a forged liveliness token cannot make the match wait for a dead bot
        return "missed"

    @property
    def waits_for(self) -> bool:
        """A connected remote bot the server expects an action from."""
        return self.occupant == "remote" and self.alive and not self.left and not self.stalled

    def public(self) -> dict:
        return {"occupant": self.occupant, "bot": self.bot, "user": self.user, "connected": self.waits_for,
                "alive": self.alive, "stalled": self.stalled, "left": self.left, "seat": self.seat,
                "ticket": self.ticket is not None, **self.counts}


def slot_observations(slots: dict[str, Slot], default: ObsBuilder, state: GameState,
                      new_episode: bool = False) -> dict[str, np.ndarray]:
    """Each remote slot's observation of ``state``, from the builder its bot asked for or the match's ``default``;
    the slots the server plays get none (nobody would read it). ``new_episode``: ``state`` begins an episode, so
    the bots' own builders reset first (the match's env resets ``default``)."""
    observations = {}
    for name, slot in slots.items():
        if slot.occupant != "remote":
            continue
        builder = slot.obs_builder or default
        if new_episode and slot.obs_builder is not None:
            builder.reset(state)
        observations[name] = builder.build(name, state)
    return observations
