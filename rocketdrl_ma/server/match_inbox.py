"""What comes in to a match from its bots: one Zenoh subscriber per taken slot, and each action checked (size,
protocol version, the MAC under the slot's secret, the decision number, the action's shape and range) and parsed
into ``CarControls`` on the callback thread, so nothing a bot sends reaches the game unchecked, and nobody but the
slot's bot can act for its car."""
from __future__ import annotations

import threading
from collections import Counter
from typing import Any

from rocketdrl_ma.env.actions import ActionParser

from .crypto import action_mac, same_mac
from .match_wire import MatchWire
from .protocol import Keys, ProtocolError, VersionError, split_action, unpack_map
from .slots import Slot


class ActionInbox:
    """The incoming side of match ``match_id``: ``decision`` is the decision whose actions are being collected
    (the match loop advances it under ``cond``), ``rejected`` counts refused actions by reason. Actions are parsed
    with their slot's parser, else ``parser`` (the match's)."""

    def __init__(self, session, keys: Keys, match_id: str, mode: str, parser: ActionParser,
                 cond: threading.Condition, wire: MatchWire):
        self.session, self.keys, self.match_id, self.mode, self.parser = session, keys, match_id, mode, parser
        self.cond, self.wire = cond, wire
        self.decision = 0
        self.rejected: Counter = Counter()
        self.jump_pressed: set[str] = set()  # real-time: slots whose jump was pressed since the last tick
        # One subscriber per taken slot, on that slot's own key: with access control, Zenoh tells a client
        # about a subscriber only if the key lies within what the client may use (its own prefix).
        self._subscribers: dict[str, Any] = {}

    def listen(self, slot: Slot) -> None:
        """Subscribe to ``slot``'s ``act`` key (again after a rejoin: the old subscriber goes)."""
        self.forget(slot)
        key = self.keys.slot(slot.user, self.match_id, slot.name, "act")
        self._subscribers[slot.name] = self.session.declare_subscriber(key, lambda sample: self.on_action(slot, sample))

    def forget(self, slot: Slot) -> None:
        old = self._subscribers.pop(slot.name, None)
        if old is not None:
            old.undeclare()

    def subscribers(self) -> list[Any]:
        return list(self._subscribers.values())

    def reject(self, reason: str, slot: Slot | None = None, message: str | None = None) -> None:
        with self.cond:
            self.rejected[reason] += 1
            if slot is not None and reason == "invalid_action":
                slot.counts["invalid"] += 1
        if slot is not None and message is not None:
            # Only an authenticated sender learns why, on its own slot's key. A priority above the per-decision
            # stream's keeps the reply out of a queue full of states on a busy link; DROP, as there, so a
            # congested bot never stalls the Zenoh callback that serves every other slot. Not express: replies
            # to a burst of bad actions share a batch, where express ones took a batch each and overflowed that
            # priority's queue (two batches) whenever Zenoh's sender waited for the CPU.
            import zenoh
            self.session.put(self.keys.slot(slot.user, self.match_id, slot.name, "error"), self.wire.seal(
                {"kind": "error", "slot": slot.name, "decision": self.decision, "error": message}),
                priority=zenoh.Priority.DATA_HIGH, congestion_control=zenoh.CongestionControl.DROP)

    def on_action(self, slot: Slot, sample) -> None:
        """Zenoh callback for a slot's ``act`` key: check everything, then hand the controls to the match."""
        if slot.secret is None:
            self.reject("no_player")  # the bot left the running match
            return
        try:
            body, mac = split_action(sample.payload.to_bytes())
        except VersionError:
            self.reject("bad_version")
            return
        except ProtocolError as e:
            self.reject("oversize" if "over the limit" in str(e) else "malformed")
            return
        secret = slot.secret
        if secret is None or not same_mac(mac, action_mac(secret, body)):
            self.reject("bad_mac")
            return
        try:
            message = unpack_map(body, len(body), "action")
        except ProtocolError as e:
            self.reject("invalid_action", slot, str(e))
            return
        decision = message.get("decision")
        if message.get("match") != self.match_id or message.get("slot") != slot.name:
            self.reject("invalid_action", slot, f"action: names match {message.get('match')!r} slot "
                                                f"{message.get('slot')!r}, not this key's")
            return
        if isinstance(decision, bool) or not isinstance(decision, int):
            self.reject("invalid_action", slot, f"decision: expected the decision number, got {decision!r}")
            return
        try:
            controls = (slot.action_parser or self.parser).parse(slot.name, message.get("action"))
        except ValueError as e:
            self.reject("invalid_action", slot, str(e))
            return
        with self.cond:
            slot.heard()
            if self.mode == "lockstep":
                if decision != self.decision:
                    late = decision < self.decision
                    self.rejected["late" if late else "future_decision"] += 1
                    slot.counts["late" if late else "invalid"] += 1
                    self.cond.notify_all()
                    return
                if slot.pending is not None:  # one action per decision: the first one counts
                    self.rejected["duplicate"] += 1
                    return
                slot.pending = controls
            else:  # realtime: the newest action wins, whenever it arrives
                if decision > self.decision or decision < slot.acted_decision:
                    self.rejected["future_decision" if decision > self.decision else "late"] += 1
                    return
                if controls.jump and not slot.last_controls.jump:  # a tap released before the next tick still jumps
                    self.jump_pressed.add(slot.name)
                slot.last_controls = controls
                if decision == slot.acted_decision:  # a newer action for the same decision: counted once
                    return
            slot.acted_decision = decision
            slot.counts["received"] += 1
            self.cond.notify_all()
