"""What a match sends: its signed, numbered messages and the Zenoh publishers they go out on (the state and events
keys, each remote slot's ``obs`` key)."""
from __future__ import annotations

import itertools
from typing import Any

from .crypto import ServerIdentity
from .protocol import Keys, seal


class MatchWire:
    """The outgoing side of match ``match_id`` (``instance`` tells it from an earlier match of that id)."""

    def __init__(self, session, keys: Keys, identity: ServerIdentity, match_id: str, instance: str):
        self.session, self.keys, self.identity = session, keys, identity
        self.match_id, self.instance = match_id, instance
        self._seq = itertools.count()
        self._publishers: dict[str, Any] = {}

    def seal(self, body: dict, raw: dict[str, bytes] | None = None) -> bytes:
        """A signed message of this match: who sends it, for which match instance, its sequence number."""
        return seal(self.identity, {**body, "server": self.keys.server, "match": self.match_id,
                                    "instance": self.instance, "seq": next(self._seq)}, raw)

    def open(self, slot_keys: dict[str, str]) -> None:
        """Publishers for the match's state and events and for each slot in ``slot_keys`` (name -> its obs key)."""
        import zenoh
        # DROP, not BLOCK: a bot whose link is congested must never stall the match thread. The per-decision
        # messages go express; events (a goal for a spectator's feed) are rare and each one counts, so they go
        # above the states' priority and batched: with every message of a decision express, each taking one of the
        # priority's two batches, a goal's events were dropped whenever Zenoh's sender waited for the CPU.
        keys = {"state": self.keys.state(self.match_id), **slot_keys}
        self._publishers = {name: self.session.declare_publisher(
            key, express=True, congestion_control=zenoh.CongestionControl.DROP) for name, key in keys.items()}
        self._publishers["events"] = self.session.declare_publisher(
            self.keys.events(self.match_id), priority=zenoh.Priority.DATA_HIGH,
            congestion_control=zenoh.CongestionControl.DROP)

    def has(self, name: str) -> bool:
        return name in self._publishers

    def put(self, name: str, payload: bytes, final: bool = False) -> None:
        if not final:
            self._publishers[name].put(payload)
            return
        # The last message of a match must arrive (a bot waits for it): it may wait for a full queue,
        # which per-decision messages never do. Zenoh bounds that wait and closes a link that stays stuck. At its
        # key's priority: Zenoh keeps the order within a priority, and a message that overtook the key's last ones
        # would make them stale to the receiver (a lower ``seq``).
        import zenoh
        publisher = self._publishers[name]
        self.session.put(publisher.key_expr, payload, express=True, priority=publisher.priority,
                         congestion_control=zenoh.CongestionControl.BLOCK)

    def close(self, subscribers: list[Any] = ()) -> None:
        """Undeclare every publisher and ``subscribers`` (the match's action subscribers)."""
        for declared in [*subscribers, *self._publishers.values()]:
            try:
                declared.undeclare()
            except Exception:  # the session may already be closing
                pass
        self._publishers = {}
