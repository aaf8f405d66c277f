"""Who may sit in which slot of a match: joining, rejoining, leaving, liveliness. The caller holds the match's lock
and decides when seating is allowed (before the match runs); this module checks who asks and what they ask for."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from rocketdrl_ma.env.actions import make_action_parser
from rocketdrl_ma.env.observations import make_obs_builder

from .crypto import KeyExchange, random_bytes
from .settings import Limits, MatchOptions
from .slots import Slot

_MAX_SPEC_NAME = 64


@dataclass
class JoinRequest:
    """A join, rejoin or leave as the lobby hands it to the match: who asks (the user of the lobby key),
    the decoded ``args``, the request's ``nonce``, and ``proves(key)``: whether the request carries a valid
    MAC under ``key`` over a fresh challenge (``crypto.request_mac``)."""
    user: str
    args: dict
    nonce: bytes
    proves: Callable[[bytes], bool]


def _spec(value: Any, field: str) -> dict:
    """``"ray"`` or ``{"name": "ray", "n_rays": 12}`` -> a spec mapping; anything else is a ValueError."""
    spec = {"name": value} if isinstance(value, str) else dict(value) if isinstance(value, dict) else None
    if spec is None or not isinstance(spec.get("name"), str) or not 0 < len(spec["name"]) <= _MAX_SPEC_NAME:
        raise ValueError(f"{field}: expected a name (at most {_MAX_SPEC_NAME} characters) or a mapping with "
                         f"'name' and its options, got {value!r}")
    return spec


class MatchSeats:
    """The slots of match ``match_id`` (one per agent of ``agents``), their reservations (seats, tickets) and
    who holds each. ``team_sizes`` (blue, orange) bound the observation builders a bot may ask for."""

    def __init__(self, match_id: str, agents: list[str], options: MatchOptions, limits: Limits, server_name: str,
                 team_sizes: tuple[int, int]):
        self.match_id, self.options, self.limits, self.server_name = match_id, options, limits, server_name
        self.team_sizes = team_sizes
        self.slots: dict[str, Slot] = {agent: Slot(agent) for agent in agents}
        unknown = sorted(set(options.seats) - set(self.slots))
        if unknown:
            raise ValueError(f"seats: {unknown} are not slots of this match; slots: {list(self.slots)}")
        self.tickets: dict[str, str] = {}
        for slot in self.slots.values():
            slot.seat = options.seats.get(slot.name)
            if not options.open and slot.seat is None:
                slot.ticket = random_bytes()
                self.tickets[slot.name] = slot.ticket.hex()

    def join_args(self, args: dict) -> tuple[str, str | None]:
        """A join's bot name and the slot it wants (None: any), checked."""
        name = args.get("name", "bot")
        # printable only: the name is shown on terminals, where control characters would restyle them
        if not isinstance(name, str) or not 0 < len(name) <= 64 or not name.isprintable():
            raise ValueError(f"name: expected a bot name of 1-64 printable characters, got {name!r}")
        return name, self.slot_arg(args, required=False)

    def seat(self, request: JoinRequest, exchange: KeyExchange) -> Slot:
        """Seat a bot in the named open slot, or the first one it may take: the match is open, the slot is the
        user's seat, or the request proves the slot's ticket. The slot's secret comes from the X25519
        exchange (``client_key``)."""
        args = request.args
        name, wanted = self.join_args(args)
        open_slots = [s for s in self.slots.values() if s.occupant == "open"]
        if wanted is not None:
            slot = self.slots[wanted]
            if slot.occupant != "open":
                raise ValueError(f"slot: {wanted!r} of match {self.match_id!r} is taken; open slots: "
                                 f"{[s.name for s in open_slots]}")
            if not self._may_take(slot, request):
                raise ValueError(f"slot: {wanted!r} of match {self.match_id!r} is reserved: " +
                                 (f"it is user {slot.seat!r}'s seat" if slot.seat else
                                  "join with its ticket (from the match's creator)"))
        else:
            slot = next((s for s in open_slots if self._may_take(s, request)), None)
            if slot is None:
                raise ValueError(f"match {self.match_id!r} has no open slot for user {request.user!r}" +
                                 ("" if not open_slots or self.options.open else
                                  "; its slots need a ticket or a seat"))
        obs_builder = action_parser = None
        obs_spec = action_spec = None
        if args.get("observation") is not None:
            obs_spec = _spec(args["observation"], "observation")
            options = {k: v for k, v in obs_spec.items() if k != "name"}
            obs_builder = make_obs_builder(obs_spec["name"], **options)
            # fits this match, and this server's budget?
            self.limits.check_observation(obs_spec["name"], obs_builder, *self.team_sizes)
        if args.get("action") is not None:
            action_spec = _spec(args["action"], "action")
            action_parser = make_action_parser(action_spec["name"],
                                               **{k: v for k, v in action_spec.items() if k != "name"})
        secret, rejoin_key = exchange.slot_keys(args.get("client_key"), request.nonce, self.server_name,
                                                self.match_id, slot.name)
        slot.take(name, request.user, secret, rejoin_key)
        slot.obs_spec, slot.action_spec = obs_spec, action_spec
        slot.obs_builder, slot.action_parser = obs_builder, action_parser
        slot.with_state = bool(args.get("with_state", True))
        return slot

    def reseat(self, request: JoinRequest, exchange: KeyExchange) -> Slot:
        """A bot back after a crash: same slot, new keys from a new exchange (the old ones stop working), a new
        lease for its new liveliness token."""
        slot = self.own_slot(request, rejoin=True)
        slot.secret, slot.rejoin_key = exchange.slot_keys(request.args.get("client_key"), request.nonce,
                                                          self.server_name, self.match_id, slot.name)
        slot.new_lease()
        return slot

    def unseat(self, request: JoinRequest, running: bool) -> Slot:
        """The slot a leave names, freed before the match runs; mid-match (``running``) the seat stays, played by
        replacement actions, and its secret stops working."""
        slot = self.own_slot(request)
        if not running:
            slot.release()
        else:
            slot.left, slot.secret, slot.rejoin_key, slot.alive = True, None, None, False
        return slot

    def set_alive(self, user: str, slot_name: str, lease: str, alive: bool) -> bool:
        """Mark a slot's bot (dis)connected if ``user`` holds the slot under ``lease``; whether it was."""
        slot = self.slots.get(slot_name)
        if slot is not None and slot.user == user and slot.lease is not None and slot.lease == lease \
                and not slot.left:
            slot.alive = alive
            return True
        return False

    def fill_open(self, fill: str) -> None:
        """Slots nobody took are played by the server's ``fill`` bot."""
        for slot in self.slots.values():
            if slot.occupant == "open":
                slot.occupant, slot.bot = "fill", fill

    def all_ready(self) -> bool:
        return all(s.waits_for for s in self.slots.values())

    def remote(self) -> list[Slot]:
        return [s for s in self.slots.values() if s.occupant == "remote"]

    def public(self) -> dict:
        return {n: s.public() for n, s in self.slots.items()}

    def _may_take(self, slot: Slot, request: JoinRequest) -> bool:
        if slot.seat is not None:
            return slot.seat == request.user
        return self.options.open or (slot.ticket is not None and request.proves(slot.ticket))

    def slot_arg(self, args: dict, required: bool = True) -> str | None:
        wanted = args.get("slot")
        if wanted is None and not required:
            return None
        if wanted not in self.slots:
            raise ValueError(f"slot: {wanted!r} is not a slot of match {self.match_id!r}; slots: {list(self.slots)}")
        return wanted

    def own_slot(self, request: JoinRequest, rejoin: bool = False) -> Slot:
        """The slot a leave (or, ``rejoin``, a rejoin) names, if the request proves the slot's secret (its rejoin
        key) and comes from its user."""
        slot = self.slots[self.slot_arg(request.args)]
        key = slot.rejoin_key if rejoin else slot.secret
        if slot.secret is None or slot.left or slot.user != request.user or key is None or not request.proves(key):
            raise ValueError(f"slot: this request does not prove the {'rejoin key' if rejoin else 'secret'} of slot "
                             f"{slot.name!r} of match {self.match_id!r} (for user {request.user!r})")
        return slot
