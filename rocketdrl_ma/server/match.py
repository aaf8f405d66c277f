"""One match on the server from creation to its result: the seats filled, the lockstep or real-time loop, what it
publishes, the result recorded.

Each match runs in its own thread. Who sits where is ``match_seats.MatchSeats``; the bots' actions arrive on Zenoh
callback threads and are checked there (``match_inbox.ActionInbox``); everything the match publishes is signed by
the server and numbered (``match_wire.MatchWire``); the tally behind its result is ``match_record.MatchRecord``.
"""
from __future__ import annotations

import logging
import threading
import time
import traceback
import uuid
from collections import Counter
from dataclasses import replace
from typing import Any, Callable

import numpy as np

import rocketdrl_ma
from rocketdrl_ma.config import load_config
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.results import MatchResult
from rocketdrl_ma.rules.events import GameEvent

from .crypto import KeyExchange, ServerIdentity
from .match_inbox import ActionInbox
from .match_record import MatchRecord
from .match_seats import JoinRequest, MatchSeats
from .match_wire import MatchWire
from .protocol import ENDED_STATUSES, Keys, MatchStatus, encode_space, encode_state, pack_value
from .settings import Limits, MatchOptions
from .slots import NEUTRAL, Slot, slot_observations

__all__ = ["INTERNAL_ERROR", "JoinRequest", "MatchRunner", "REALTIME_TICK_HZ"]

log = logging.getLogger(__name__)
REALTIME_TICK_HZ = 120.0
#: real-time matches publish their state every this many ticks (60 Hz), not only at decisions: a human's page draws
#: the car's response to a key one state sooner
REALTIME_STATE_TICKS = 2
INTERNAL_ERROR = "internal error (details in the server's log)"


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
        try:
            team_sizes = (self.env.rules.blue_size, self.env.rules.orange_size)
            self.seats = MatchSeats(match_id, self.env.possible_agents, options, self.limits, keys.server, team_sizes)
            if creator is not None:
                self.limits.check_observation(env_config["observation"]["name"], self.env.obs_builder, *team_sizes)
        except ValueError:
            self.env.close()
            raise
        self.slots: dict[str, Slot] = self.seats.slots
        self.tickets: dict[str, str] = self.seats.tickets
        # The env plays every car from CarControls: the inbox parses and checks each bot's action with its slot's
        # parser (or the match's) when it arrives, and the match builds only remote slots' observations.
        self._match_obs = self.env.obs_builder
        self._fill: dict[str, Any] = {}
        self.status = MatchStatus.WAITING
        self.instance = uuid.uuid4().hex  # tells this match from an earlier one of the same id
        self.created_at = time.time()
        self.started_at: float | None = None
        self.seed = options.seed if options.seed is not None else int.from_bytes(uuid.uuid4().bytes[:4], "little")
        self.result_key: str | None = None
        self.final_summary: dict | None = None
        self.error: str | None = None
        self.scoreboard: dict = {}
        self.tally = MatchRecord()
        self._cond = threading.Condition()
        self._stop = threading.Event()
        self._wire = MatchWire(session, keys, identity, match_id, self.instance)
        self.inbox = ActionInbox(session, keys, match_id, options.mode, self.env.action_parser, self._cond,
                                 self._wire)
        self._thread = threading.Thread(target=self._run, name=f"match-{match_id}", daemon=True)

    def start(self) -> None:
        self._thread.start()

    @property
    def live(self) -> bool:
        return self.status not in ENDED_STATUSES

    @property
    def decision(self) -> int:
        """The decision whose actions are being collected."""
        return self.inbox.decision

    @property
    def rejected(self) -> Counter:
        """Refused actions by reason (the inbox's)."""
        return self.inbox.rejected

    # ------------------------------------------------------------------------------------------ lobby side
    def join(self, request: JoinRequest) -> dict:
        """Seat a bot (``MatchSeats.seat``) while the match waits for its bots."""
        self.seats.join_args(request.args)
        exchange = KeyExchange()
        with self._cond:
            if self.status != MatchStatus.WAITING:
                raise ValueError(f"match {self.id!r} is {self.status}; only its own bots can rejoin (op rejoin)")
            slot = self.seats.seat(request, exchange)
            self.inbox.listen(slot)
            self._cond.notify_all()
            return {**self._join_reply(slot), "server_key_exchange": exchange.public_bytes}

    def rejoin(self, request: JoinRequest) -> dict:
        """A bot back after a crash (``MatchSeats.reseat``)."""
        exchange = KeyExchange()
        with self._cond:
            slot = self.seats.reseat(request, exchange)
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
            "action_space": encode_space((slot.action_parser or self.inbox.parser).space()),
            "keys": keys | {"alive": self.keys.bot_alive(slot.user, self.id, slot.name, slot.lease),
                            "state": self.keys.state(self.id), "events": self.keys.events(self.id),
                            "server_alive": self.keys.server_alive},
        }

    def leave(self, request: JoinRequest) -> dict:
        with self._cond:
            running = self.status != MatchStatus.WAITING
            slot = self.seats.unseat(request, running)
            if not running:
                self.inbox.forget(slot)
            self._cond.notify_all()
            return {"match": self.id, "slot": slot.name}

    def set_alive(self, user: str, slot_name: str, lease: str, alive: bool) -> None:
        with self._cond:
            if self.seats.set_alive(user, slot_name, lease, alive):
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
                    "scoreboard": self.scoreboard, "slot_status": self.seats.public(),
                    "rejected": dict(self.rejected), "events": dict(self.tally.event_counts), "error": self.error,
                    "timing": self.tally.timing(), "summary": self.final_summary}

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
                if self.seats.all_ready():
                    break
                remaining = deadline - time.time()
                if remaining <= 0:
                    break
                self._cond.wait(remaining)
            self.seats.fill_open(self.options.fill)
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
                self.inbox.decision += 1  # actions for the decision just closed are late from now on
            self.tally.wait_s.append(time.perf_counter() - t_wait)
            for agent in env.agents:
                actions.setdefault(agent, NEUTRAL)  # an idle fill slot
            _, rewards, _, _, _ = env.play(actions, observe=False)
            observations = self._observe()
            self.tally.count_events(env.game_state.events)
            self.tally.decision_s.append(time.perf_counter() - t0)
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
                        self.inbox.decision += 1
                        now = time.perf_counter()
                        self.tally.decision_s.append(now - last_decision_t)
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
                for name in self.inbox.jump_pressed & actions.keys():
                    actions[name] = replace(actions[name], jump=True)
                self.inbox.jump_pressed.clear()
            actions.update(fill)
            for agent in env.agents:
                actions.setdefault(agent, NEUTRAL)
            _, step_rewards, _, _, _ = env.play(actions, observe=False)
            for agent, r in step_rewards.items():
                acc_rewards[agent] += r
            events += env.game_state.events
            self.tally.count_events(env.game_state.events)
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
            return self.seats.public()

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

    def _end(self, status: str) -> None:
        summary = None
        if status == MatchStatus.FINISHED:
            summary = self.env.rules.summary()
            key = f"{self.keys.server}/{self.id}/{uuid.uuid4().hex[:12]}"
            self._record(self.tally.result(
                key, self.config, {n: s.bot or "idle" for n, s in self.slots.items()}, self.env.game_state, self.seed,
                summary, {"match_id": self.id, "mode": self.options.mode, "options": self.options.as_dict()},
                self.seats.public(), dict(self.rejected)))
            self.result_key = key
        self.final_summary = summary
        with self._cond:
            self.status = status
        if self._wire.has("events"):
            self._wire.put("events", self._wire.seal({
                "kind": "events", "decision": self.decision, "done": True, "final": True, "events": [],
                "status": status, "summary": summary, "error": self.error, "result_key": self.result_key}), final=True)
        self._wire.close(self.inbox.subscribers())
        self.env.close()

    def discard(self) -> None:
        """Stop a match that never ran (server shutdown before start) and free what it holds."""
        self.stop()
        self.join_thread(5.0)
