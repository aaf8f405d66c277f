"""One match on the server: its slots, joining and leaving, the lockstep or real-time loop, the result.

Each match runs in its own thread. Bots' actions arrive on Zenoh callback threads (``on_action``):
they are checked (size, protocol version, that the key's user holds the slot, the MAC under the slot's
secret, the decision number, the action's shape and range) and parsed into ``CarControls`` there, so
nothing a bot sends can reach the env unchecked, and nobody but the slot's bot can act for its car.
Everything the match publishes is signed by the server (``protocol.seal``) and numbered (``seq``).
"""
from __future__ import annotations

import logging
import threading
import time
import traceback
import uuid
from collections import Counter
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

import rocketdrl_ma
from rocketdrl_ma.config import load_config
from rocketdrl_ma.env.actions import make_action_parser
from rocketdrl_ma.env.observations import make_obs_builder
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.results import MatchResult
from rocketdrl_ma.rules.events import GameEvent, Goal

from .crypto import KeyExchange, ServerIdentity, action_mac, random_bytes, same_mac
from .protocol import (ENDED_STATUSES, Keys, MatchStatus, ProtocolError, VersionError, encode_space, encode_state,
                       pack_value, split_action, unpack_map)
from .settings import Limits, MatchOptions
from .match_wire import MatchWire
from .slots import NEUTRAL, Slot, slot_observations

log = logging.getLogger(__name__)
REALTIME_TICK_HZ = 120.0
#: real-time matches publish their state every this many ticks (60 Hz), not only at decisions: a human's page draws
#: the car's response to a key one state sooner
REALTIME_STATE_TICKS = 2
INTERNAL_ERROR = "internal error (details in the server's log)"
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


def _percentile_ms(values: list[float], q: float) -> float | None:
    return round(float(np.percentile(values, q)) * 1e3, 3) if values else None


class MatchRunner:
    """A match from creation to its result. ``session`` is the server's Zenoh session, ``identity`` its
    signing key; ``creator`` the user who created it (None: the server's own YAML); ``limits`` bound what
    its bots (and, for a lobby-created match, its creator) may ask for."""

    def __init__(self, match_id: str, options: MatchOptions, session, keys: Keys, identity: ServerIdentity,
                 record: Callable[[MatchResult], None], creator: str | None = None, limits: Limits | None = None):
        self.id, self.options, self.session, self.keys, self._record = match_id, options, session, keys, record
        self.limits = limits or Limits()
        self.identity, self.creator, self.missed_streak = identity, creator, self.limits.missed_streak
        overrides = dict(options.overrides)
        env_config = load_config(options.config, overrides)  # ValueError naming the key if bad
        self.config = env_config
        self.decision_ticks: int = env_config["tick_skip"]
        if options.mode == "realtime":
            # One env step per physics tick, so the latest actions apply at every 120 Hz tick.
            overrides["tick_skip"] = 1
            if env_config["max_cycles"] is not None:
                overrides["max_cycles"] = env_config["max_cycles"] * self.decision_ticks
        self.env = rocketdrl_ma.parallel_env(options.config, **overrides)
        self.slots: dict[str, Slot] = {agent: Slot(agent) for agent in self.env.possible_agents}
        unknown = sorted(set(options.seats) - set(self.slots))
        if unknown:
            self.env.close()
            raise ValueError(f"seats: {unknown} are not slots of this match; slots: {list(self.slots)}")
        if creator is not None:
            try:
                self.limits.check_observation(env_config["observation"]["name"], self.env.obs_builder,
                                              self.env.rules.blue_size, self.env.rules.orange_size)
            except ValueError:
                self.env.close()
                raise
        self.tickets: dict[str, str] = {}
        for slot in self.slots.values():
            slot.seat = options.seats.get(slot.name)
            if not options.open and slot.seat is None:
                slot.ticket = random_bytes()
                self.tickets[slot.name] = slot.ticket.hex()
        # The env plays every car from CarControls: the server parses and checks each bot's action with its slot's
        # parser (or the match's, ``self._match_parser``) when it arrives, and builds only remote slots' observations.
        self._match_parser = self.env.action_parser
        self._match_obs = self.env.obs_builder
        self._fill: dict[str, Any] = {}
        self._jump_pressed: set[str] = set()  # real-time: slots whose jump was pressed since the last tick
        self.status = MatchStatus.WAITING
        self.instance = uuid.uuid4().hex  # tells this match from an earlier one of the same id
        self.created_at = time.time()
        self.started_at: float | None = None
        self.seed = options.seed if options.seed is not None else int.from_bytes(uuid.uuid4().bytes[:4], "little")
        self.result_key: str | None = None
        self.final_summary: dict | None = None
        self.error: str | None = None
        self.decision = 0  # the decision whose actions are being collected
        self.scoreboard: dict = {}
        self.rejected: Counter = Counter()
        self._event_counts: Counter = Counter()
        self._goals: list[dict] = []
        self._decision_s: list[float] = []
        self._wait_s: list[float] = []
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._wire = MatchWire(session, keys, identity, match_id, self.instance)
        # One subscriber per taken slot, on that slot's own key: with access control, Zenoh tells a client
        # about a subscriber only if the key lies within what the client may use (its own prefix).
        self._act_subs: dict[str, Any] = {}
        self._thread = threading.Thread(target=self._run, name=f"match-{match_id}", daemon=True)

    def start(self) -> None:
        self._thread.start()

    @property
    def live(self) -> bool:
        return self.status not in ENDED_STATUSES

    # ------------------------------------------------------------------------------------------ lobby side
    def join(self, request: JoinRequest) -> dict:
        """Seat a bot in the named open slot, or the first one it may take: the match is open, the slot is the
        user's seat, or the request proves the slot's ticket. The slot's secret comes from the X25519
        exchange (``client_key``)."""
        args = request.args
        name = args.get("name", "bot")
        # printable only: the name is shown on terminals, where control characters would restyle them
        if not isinstance(name, str) or not 0 < len(name) <= 64 or not name.isprintable():
            raise ValueError(f"name: expected a bot name of 1-64 printable characters, got {name!r}")
        wanted = self._slot_arg(args, required=False)
        exchange = KeyExchange()
        with self._cond:
            if self.status != MatchStatus.WAITING:
                raise ValueError(f"match {self.id!r} is {self.status}; only its own bots can rejoin (op rejoin)")
            open_slots = [s for s in self.slots.values() if s.occupant == "open"]
            if wanted is not None:
                slot = self.slots[wanted]
                if slot.occupant != "open":
                    raise ValueError(f"slot: {wanted!r} of match {self.id!r} is taken; open slots: "
                                     f"{[s.name for s in open_slots]}")
                if not self._may_take(slot, request):
                    raise ValueError(f"slot: {wanted!r} of match {self.id!r} is reserved: " +
                                     (f"it is user {slot.seat!r}'s seat" if slot.seat else
                                      "join with its ticket (from the match's creator)"))
            else:
                slot = next((s for s in open_slots if self._may_take(s, request)), None)
                if slot is None:
                    raise ValueError(f"match {self.id!r} has no open slot for user {request.user!r}" +
                                     ("" if not open_slots or self.options.open else
                                      "; its slots need a ticket or a seat"))
            obs_builder = action_parser = None
            obs_spec = action_spec = None
            if args.get("observation") is not None:
                obs_spec = _spec(args["observation"], "observation")
                options = {k: v for k, v in obs_spec.items() if k != "name"}
                obs_builder = make_obs_builder(obs_spec["name"], **options)
                # fits this match, and this server's budget?
                self.limits.check_observation(obs_spec["name"], obs_builder, self.env.rules.blue_size,
                                              self.env.rules.orange_size)
            if args.get("action") is not None:
                action_spec = _spec(args["action"], "action")
                action_parser = make_action_parser(action_spec["name"],
                                                   **{k: v for k, v in action_spec.items() if k != "name"})
            secret, rejoin_key = exchange.slot_keys(args.get("client_key"), request.nonce, self.keys.server, self.id,
                                                    slot.name)
            slot.take(name, request.user, secret, rejoin_key)
            slot.obs_spec, slot.action_spec = obs_spec, action_spec
            slot.obs_builder, slot.action_parser = obs_builder, action_parser
            slot.with_state = bool(args.get("with_state", True))
            self._listen_for_actions(slot)
            self._cond.notify_all()
            return {**self._join_reply(slot), "server_key_exchange": exchange.public_bytes}

    def _listen_for_actions(self, slot: Slot) -> None:
        old = self._act_subs.pop(slot.name, None)
        if old is not None:
            old.undeclare()
        key = self.keys.slot(slot.user, self.id, slot.name, "act")
        self._act_subs[slot.name] = self.session.declare_subscriber(key, lambda sample: self.on_action(slot, sample))

    def _may_take(self, slot: Slot, request: JoinRequest) -> bool:
        if slot.seat is not None:
            return slot.seat == request.user
        return self.options.open or (slot.ticket is not None and request.proves(slot.ticket))

    def _slot_arg(self, args: dict, required: bool = True) -> str | None:
        wanted = args.get("slot")
        if wanted is None and not required:
            return None
        if wanted not in self.slots:
            raise ValueError(f"slot: {wanted!r} is not a slot of match {self.id!r}; slots: {list(self.slots)}")
        return wanted

    def _own_slot(self, request: JoinRequest, rejoin: bool = False) -> Slot:
        """The slot a leave (or, ``rejoin``, a rejoin) names, if the request proves the slot's secret (its rejoin
        key) and comes from its user."""
        slot = self.slots[self._slot_arg(request.args)]
        key = slot.rejoin_key if rejoin else slot.secret
        if slot.secret is None or slot.left or slot.user != request.user or key is None or not request.proves(key):
            raise ValueError(f"slot: this request does not prove the {'rejoin key' if rejoin else 'secret'} of slot "
                             f"{slot.name!r} of match {self.id!r} (for user {request.user!r})")
        return slot

    def rejoin(self, request: JoinRequest) -> dict:
        """A bot back after a crash: same slot, new keys from a new exchange (the old ones stop working), a new
        lease for its new liveliness token."""
        exchange = KeyExchange()
        with self._cond:
            slot = self._own_slot(request, rejoin=True)
            slot.secret, slot.rejoin_key = exchange.slot_keys(request.args.get("client_key"), request.nonce,
                                                              self.keys.server, self.id, slot.name)
            slot.new_lease()
            self._cond.notify_all()
            return {**self._join_reply(slot), "server_key_exchange": exchange.public_bytes}

    def _join_reply(self, slot: Slot) -> dict:
        rules = self.env.rules
        obs_space = (slot.obs_builder or self._match_obs).space(rules.blue_size, rules.orange_size)
        keys = {leaf: self.keys.slot(slot.user, self.id, slot.name, leaf) for leaf in ("obs", "act", "error")}
        return {
            "match": self.id, "instance": self.instance, "slot": slot.name, "user": slot.user, "lease": slot.lease,
            "status": self.status, "config": self.config, "mode": self.options.mode,
            "deadline_ms": self.options.deadline_ms, "decision_ticks": self.decision_ticks,
            "tick_rate": int(REALTIME_TICK_HZ), "server_key": self.identity.public_text,
            "observation": slot.obs_spec or self.config["observation"],
            "action": slot.action_spec or self.config["action"],
            "observation_space": encode_space(obs_space),
            "action_space": encode_space((slot.action_parser or self._match_parser).space()),
            "keys": keys | {"alive": self.keys.bot_alive(slot.user, self.id, slot.name, slot.lease),
                            "state": self.keys.state(self.id), "events": self.keys.events(self.id),
                            "server_alive": self.keys.server_alive},
        }

    def leave(self, request: JoinRequest) -> dict:
        with self._cond:
            slot = self._own_slot(request)
            if self.status == MatchStatus.WAITING:
                slot.release()
                self._act_subs.pop(slot.name).undeclare()
            else:  # mid-match the seat stays, played by replacement actions; the secret stops working
                slot.left, slot.secret, slot.rejoin_key, slot.alive = True, None, None, False
            self._cond.notify_all()
            return {"match": self.id, "slot": slot.name}

    def set_alive(self, user: str, slot_name: str, lease: str, alive: bool) -> None:
        with self._cond:
            slot = self.slots.get(slot_name)
            if slot is not None and slot.user == user and slot.lease is not None and slot.lease == lease \
                    and not slot.left:
                slot.alive = alive
                self._cond.notify_all()

    def stop(self) -> None:
        self._stop.set()
        with self._cond:
            self._cond.notify_all()

    def join_thread(self, timeout_s: float | None = None) -> None:
        if self._thread.is_alive():
            self._thread.join(timeout_s)

    def summary(self) -> dict:
        """What the lobby lists for this match."""
        with self._cond:
            return self._summary()

    def _summary(self) -> dict:
        return {"id": self.id, "instance": self.instance, "status": self.status, "mode": self.options.mode,
                "config": self.options.config if isinstance(self.options.config, str) else self.config["mode"],
                "open": self.options.open, "creator": self.creator, "slots": len(self.slots),
                "joined": sum(s.occupant == "remote" for s in self.slots.values()),
                "decision": self.decision, "score": self.scoreboard.get("score"), "result_key": self.result_key}

    def inspect(self) -> dict:
        """Everything about the match: options, config, slots and their counters, rejections, timing."""
        with self._cond:
            return {**self._summary(), "options": self.options.as_dict(), "game_config": self.config,
                    "seed": self.seed, "created_at": self.created_at, "started_at": self.started_at,
                    "scoreboard": self.scoreboard, "slot_status": {n: s.public() for n, s in self.slots.items()},
                    "rejected": dict(self.rejected), "events": dict(self._event_counts), "error": self.error,
                    "timing": self._timing(), "summary": self.final_summary}

    # ------------------------------------------------------------------------------------------ actions in
    def _reject(self, reason: str, slot: Slot | None = None, message: str | None = None) -> None:
        with self._cond:
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
            self.session.put(self.keys.slot(slot.user, self.id, slot.name, "error"), self._wire.seal(
                {"kind": "error", "slot": slot.name, "decision": self.decision, "error": message}),
                priority=zenoh.Priority.DATA_HIGH, congestion_control=zenoh.CongestionControl.DROP)

    def on_action(self, slot: Slot, sample) -> None:
        """Zenoh callback for a slot's ``act`` key: check everything, then hand the controls to the match."""
        if slot.secret is None:
            self._reject("no_player")  # the bot left the running match
            return
        try:
            body, mac = split_action(sample.payload.to_bytes())
        except VersionError:
            self._reject("bad_version")
            return
        except ProtocolError as e:
            self._reject("oversize" if "over the limit" in str(e) else "malformed")
            return
        secret = slot.secret
        if secret is None or not same_mac(mac, action_mac(secret, body)):
            self._reject("bad_mac")
            return
        try:
            message = unpack_map(body, len(body), "action")
        except ProtocolError as e:
            self._reject("invalid_action", slot, str(e))
            return
        decision = message.get("decision")
        if message.get("match") != self.id or message.get("slot") != slot.name:
            self._reject("invalid_action", slot, f"action: names match {message.get('match')!r} slot "
                                                 f"{message.get('slot')!r}, not this key's")
            return
        if isinstance(decision, bool) or not isinstance(decision, int):
            self._reject("invalid_action", slot, f"decision: expected the decision number, got {decision!r}")
            return
        try:
            controls = (slot.action_parser or self._match_parser).parse(slot.name, message.get("action"))
        except ValueError as e:
            self._reject("invalid_action", slot, str(e))
            return
        with self._cond:
            slot.heard()
            if self.options.mode == "lockstep":
                if decision != self.decision:
                    late = decision < self.decision
                    self.rejected["late" if late else "future_decision"] += 1
                    slot.counts["late" if late else "invalid"] += 1
                    self._cond.notify_all()
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
                    self._jump_pressed.add(slot.name)
                slot.last_controls = controls
                if decision == slot.acted_decision:  # a newer action for the same decision: counted once
                    return
            slot.acted_decision = decision
            slot.counts["received"] += 1
            self._cond.notify_all()

    # ------------------------------------------------------------------------------------------ the match
    def _run(self) -> None:
        try:
            self._wait_until_ready()
            if self._stop.is_set():
                self._end(MatchStatus.STOPPED)
                return
            self._play()
            self._end(MatchStatus.STOPPED if self._stop.is_set() else MatchStatus.FINISHED)
        except Exception as e:  # a bug must not take the server down: the match fails, others go on
            log.error("match %s failed (%s: %s):\n%s", self.id, type(e).__name__, e, traceback.format_exc())
            self.error = INTERNAL_ERROR  # clients learn that it failed, the log says why
            self._end(MatchStatus.FAILED)

    def _wait_until_ready(self) -> None:
        deadline = self.created_at + self.options.ready_timeout_s
        with self._cond:
            while not self._stop.is_set():
                if all(s.waits_for for s in self.slots.values()):
                    break
                remaining = deadline - time.time()
                if remaining <= 0:
                    break
                self._cond.wait(remaining)
            for slot in self.slots.values():
                if slot.occupant == "open":
                    slot.occupant, slot.bot = "fill", self.options.fill
            self.status = MatchStatus.RUNNING
            self.started_at = time.time()
        from rocketdrl_ma.policies.registry import load_policy
        for slot in self.slots.values():
            if slot.occupant == "fill" and self.options.fill != "idle":
                self._fill[slot.name] = load_policy(self.options.fill)
        self._wire.open({s.name: self.keys.slot(s.user, self.id, s.name, "obs") for s in self.slots.values()
                         if s.occupant == "remote"})

    def _fill_controls(self, state) -> dict[str, CarControls]:
        return {name: policy.controls(name, state) for name, policy in self._fill.items()}

    def _replacement(self, slot: Slot) -> CarControls:
        return slot.last_controls if self.options.replacement == "repeat" else NEUTRAL

    def _count_events(self, events: list[GameEvent]) -> None:
        for event in events:
            self._event_counts[event.kind.value] += 1
            if isinstance(event, Goal):
                self._goals.append({k: v for k, v in event.as_dict().items() if k != "kind"})

    def _observe(self, new_episode: bool = False) -> dict[str, np.ndarray]:
        return slot_observations(self.slots, self._match_obs, self.env.game_state, new_episode)

    def _play(self) -> None:
        env = self.env
        env.reset(seed=self.seed)
        observations = self._observe(new_episode=True)
        state = env.game_state
        for name, policy in self._fill.items():
            policy.reset(state)
        rewards = dict.fromkeys(self.slots, 0.0)
        if self.options.mode == "lockstep":
            self._lockstep(observations, rewards)
        else:
            self._realtime(observations, rewards)

    def _lockstep(self, observations: dict, rewards: dict) -> None:
        env, deadline_s = self.env, self.options.deadline_ms / 1e3
        while env.agents and not self._stop.is_set():
            t0 = time.perf_counter()
            state = env.game_state
            self._publish(observations, rewards, state, done=False)
            actions = self._fill_controls(state)
            t_wait = time.perf_counter()
            with self._cond:
                until = t0 + deadline_s
                while not self._stop.is_set():
                    waiting = [s for s in self.slots.values() if s.waits_for and s.pending is None]
                    remaining = until - time.perf_counter()
                    if not waiting or remaining <= 0:
                        break
                    self._cond.wait(remaining)
                for slot in self.slots.values():
                    if slot.occupant != "remote":
                        continue
                    if slot.pending is not None:
                        slot.last_controls = slot.pending
                        actions[slot.name] = slot.pending
                    else:
                        slot.missed(self.missed_streak)
                        actions[slot.name] = self._replacement(slot)
                        slot.last_controls = actions[slot.name]
                    slot.pending = None
                self.decision += 1  # actions for the decision just closed are late from now on
            self._wait_s.append(time.perf_counter() - t_wait)
            for agent in env.agents:
                actions.setdefault(agent, NEUTRAL)  # an idle fill slot
            _, rewards, _, _, _ = env.play(actions, observe=False)
            observations = self._observe()
            self._count_events(env.game_state.events)
            self._decision_s.append(time.perf_counter() - t0)
        self._publish(observations, rewards, env.game_state, done=True)

    def _realtime(self, observations: dict, rewards: dict) -> None:
        env, period = self.env, 1.0 / REALTIME_TICK_HZ
        tick, next_t = 0, time.perf_counter()
        fill: dict[str, CarControls] = {}
        acc_rewards = dict.fromkeys(self.slots, 0.0)
        events: list[GameEvent] = []
        last_decision_t = next_t
        while env.agents and not self._stop.is_set():
            if tick % self.decision_ticks == 0:
                state = env.game_state
                with self._cond:
                    if tick > 0:  # close the decision that just ended: who never answered it?
                        for slot in self.slots.values():
                            if slot.occupant == "remote" and slot.acted_decision < self.decision:
                                slot.missed(self.missed_streak)
                        self.decision += 1
                        now = time.perf_counter()
                        self._decision_s.append(now - last_decision_t)
                        last_decision_t = now
                if tick > 0:
                    observations = self._observe()
                self._publish(observations, acc_rewards, state, done=False, events=events)
                acc_rewards, events = dict.fromkeys(self.slots, 0.0), []
                fill = self._fill_controls(state)
            elif tick % REALTIME_STATE_TICKS == 0:
                self._publish_state(env.game_state, {"decision": self.decision, "done": False,
                                                      "scoreboard": self.env.rules.scoreboard()})
            with self._cond:
                actions = {s.name: s.last_controls if s.waits_for or self.options.replacement == "repeat"
                           else NEUTRAL for s in self.slots.values() if s.occupant == "remote"}
                for name in self._jump_pressed & actions.keys():
                    actions[name] = replace(actions[name], jump=True)
                self._jump_pressed.clear()
            actions.update(fill)
            for agent in env.agents:
                actions.setdefault(agent, NEUTRAL)
            _, step_rewards, _, _, _ = env.play(actions, observe=False)
            for agent, r in step_rewards.items():
                acc_rewards[agent] += r
            events += env.game_state.events
            self._count_events(env.game_state.events)
            tick += 1
            next_t += period
            delay = next_t - time.perf_counter()
            if delay > 0:
                self._stop.wait(delay)
            elif delay < -0.25:  # far behind (a stall): resynchronise rather than rush through the backlog
                next_t = time.perf_counter()
        if tick % self.decision_ticks == 0:
            observations = self._observe()
        else:  # the game ended between decisions: no bot acts on that tick, so none observes it
            observations = {}
        self._publish(observations, acc_rewards, env.game_state, done=True, events=events)

    # ------------------------------------------------------------------------------------------ publishing
    def _slots_public(self) -> dict:
        with self._cond:
            return {n: s.public() for n, s in self.slots.items()}

    def _publish(self, observations: dict, rewards: dict, state, done: bool, events: list | None = None) -> None:
        events = [event.as_dict() for event in (state.events if events is None else events)]
        self.scoreboard = self.env.rules.scoreboard()
        state_bytes = pack_value(encode_state(state))
        decision = self.decision
        common = {"decision": decision, "scoreboard": self.scoreboard, "done": done}
        summary = self.env.rules.summary() if done else None
        for name, slot in self.slots.items():
            if slot.occupant != "remote" or slot.left or not self._wire.has(name):
                continue
            message = {"kind": "obs", **common, "slot": name, "reward": float(rewards.get(name, 0.0)),
                       "events": events, "obs": observations.get(name, np.zeros(0, np.float32))}
            if done:
                message.update(summary=summary,
                               reason=MatchStatus.STOPPED if self._stop.is_set() else MatchStatus.FINISHED)
            raw = {"state": state_bytes} if slot.with_state else {}
            self._wire.put(name, self._wire.seal(message, raw), final=done)
        self._publish_state(state, common, state_bytes)
        if events:
            self._wire.put("events", self._wire.seal({"kind": "events", **common, "events": events}))

    def _publish_state(self, state, common: dict, state_bytes: bytes | None = None) -> None:
        self._wire.put("state", self._wire.seal({"kind": "state", **common, "status": self.status,
                                                 "slots": self._slots_public()},
                                                {"state": state_bytes or pack_value(encode_state(state))}))

    def _timing(self) -> dict:
        return {"decisions": len(self._decision_s), "decision_ms_median": _percentile_ms(self._decision_s, 50),
                "decision_ms_p99": _percentile_ms(self._decision_s, 99),
                "wait_ms_median": _percentile_ms(self._wait_s, 50), "wait_ms_p99": _percentile_ms(self._wait_s, 99),
                "wall_s": round(sum(self._decision_s), 4)}

    def _end(self, status: str) -> None:
        rules = self.env.rules
        summary = None
        if status == MatchStatus.FINISHED:
            summary = rules.summary()
            state = self.env.game_state
            slots = {n: s.public() for n, s in self.slots.items()}
            key = f"{self.keys.server}/{self.id}/{uuid.uuid4().hex[:12]}"
            result = MatchResult(
                match_key=key, source="server", config=self.config,
                entrants={n: s.bot or "idle" for n, s in self.slots.items()},
                score_blue=int(state.score[0]), score_orange=int(state.score[1]),
                duration_s=state.tick / state.tick_rate, seed=self.seed,
                details={"match_id": self.id, "mode": self.options.mode, "options": self.options.as_dict(),
                         "events": dict(self._event_counts), "goals": self._goals,
                         "stats": summary.get("stats", {}), "overtime": bool(summary.get("overtime", False)),
                         "missed_decisions": {n: s["missed"] + s["disconnected"] for n, s in slots.items()},
                         "bots": slots, "rejected": dict(self.rejected), "timing": self._timing()})
            self._record(result)
            self.result_key = key
        self.final_summary = summary
        with self._cond:
            self.status = status
        if self._wire.has("events"):
            self._wire.put("events", self._wire.seal({
                "kind": "events", "decision": self.decision, "done": True, "final": True, "events": [],
                "status": status, "summary": summary, "error": self.error, "result_key": self.result_key}), final=True)
        self._wire.close(list(self._act_subs.values()))
        self.env.close()

    def discard(self) -> None:
        """Stop a match that never ran (server shutdown before start) and free what it holds."""
        self.stop()
        self.join_thread(5.0)
