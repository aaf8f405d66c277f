"""Playing one scheduled match: in this process on a local env, or on a match server when a remote
entrant takes part. Either way the outcome is one ``MatchResult`` for the league's results store."""
from __future__ import annotations

import secrets
import threading
import time

from rocketdrl_ma.engine import float32_controls
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.policies.base import Policy
from rocketdrl_ma.results import MatchResult
from rocketdrl_ma.rules.state import GameState

from .config import LeagueConfig
from .digest import match_digests
from .schedule import ScheduledMatch

TEAMS = ("blue", "orange")


def slot_players(cfg: LeagueConfig, match: ScheduledMatch) -> dict[str, tuple[str, str | None]]:
    """``{slot: (player name, policy spec or None for a remote bot)}`` for every car of the match."""
    out = {}
    for team, entrant_name in zip(TEAMS, (match.blue, match.orange)):
        for k, player in enumerate(cfg.entrant(entrant_name).slot_players(cfg.team_size)):
            out[f"{team}_{k}"] = (player.name, player.policy)
    return out


def _result(cfg: LeagueConfig, match: ScheduledMatch, score: dict, duration_s: float, details: dict) -> MatchResult:
    players = {slot: name for slot, (name, _) in slot_players(cfg, match).items()}
    entrants = {slot: match.blue if slot.startswith("blue") else match.orange for slot in players}
    return MatchResult(match_key=match.key, source="league", config=cfg.game_config, entrants=entrants,
                       score_blue=int(score["blue"]), score_orange=int(score["orange"]), duration_s=duration_s,
                       seed=match.seed, details={"league": cfg.name, "index": match.index, "players": players,
                                                 **details})


class LocalMatch:
    """A scheduled match on a local env of its own, driven decision by decision from outside: ``cars()`` says who
    must act, ``step`` takes their controls; ``result()`` once ``over``. ``policies``: one per car (its slot)."""

    def __init__(self, cfg: LeagueConfig, match: ScheduledMatch, policies: dict[str, Policy]):
        import rocketdrl_ma

        self.cfg, self.match, self.policies = cfg, match, policies
        self.env = rocketdrl_ma.parallel_env(cfg.match, **cfg.overrides)
        self.env.reset(seed=match.seed)
        self.state = self.env.rules.game_state()
        for policy in policies.values():
            policy.reset(self.state)
        self.summary: dict = {}
        self.events: list = []

    @property
    def over(self) -> bool:
        return not self.env.agents

    def cars(self) -> list[tuple[Policy, str, GameState]]:
        """``(policy, agent, state)`` of every live car this decision."""
        self.state = self.env.rules.game_state()
        return [(self.policies[agent], agent, self.state) for agent in self.env.agents]

    def step(self, controls: list[CarControls]) -> None:
        """One decision with ``controls`` of the cars ``cars()`` named, in its order."""
        env = self.env
        # without the env's own observations: every policy builds its own from the state
        _, _, _, _, infos = env.play(float32_controls(dict(zip(env.agents, controls))), observe=False)
        self.summary = next(iter(infos.values())).get("summary", self.summary)
        self.events += self.env.game_state.events

    def result(self) -> MatchResult:
        state = self.env.rules.game_state()
        return _result(self.cfg, self.match, self.summary["score"], state.tick / state.tick_rate,
                       {"where": "local", "overtime": bool(self.summary.get("overtime", False)),
                        "stats": self.summary.get("stats", {}), "team": self.summary.get("team", {}),
                        **match_digests(self.env, self.events)})

    def close(self) -> None:
        self.env.close()


def play_local(cfg: LeagueConfig, match: ScheduledMatch) -> MatchResult:
    """A full match on a local env, every car driven by its player's policy (one instance per car, one
    ``controls`` call per car and decision): the reference every batched way of playing it reproduces."""
    from rocketdrl_ma.policies.registry import load_policy

    game = LocalMatch(cfg, match, {slot: load_policy(spec) for slot, (_, spec) in slot_players(cfg, match).items()})
    try:
        while not game.over:
            game.step([policy.controls(agent, state) for policy, agent, state in game.cars()])
        return game.result()
    finally:
        game.close()


def play_on_server(cfg: LeagueConfig, match: ScheduledMatch, session, client=None) -> MatchResult:
    """A match on the match server: remote players are invited (``remote.invite``), the others join as
    ``PolicyBot``s from this process; the result is read back from the lobby once the match ends.
    ``client``: how this process is known to the server and trusts it (a ``ClientSettings``; default: the
    server's name, unauthenticated, its key and admin secret from its key dir on this machine)."""
    from rocketdrl_ma.server.bot import PolicyBot
    from rocketdrl_ma.server.client import LobbyClient, resolve_client
    from rocketdrl_ma.server.protocol import ENDED_STATUSES, MatchStatus

    from .remote import invite

    link = cfg.server
    client = resolve_client(client, server=link.name)
    lobby = LobbyClient(session, client)
    slots = slot_players(cfg, match)
    remote: dict[str, list[str]] = {}
    for slot, (name, spec) in slots.items():
        if spec is None:
            remote.setdefault(name, []).append(slot)
    # Every seat is reserved: a remote entrant's for its user (the entrant's name), the others for ours.
    seats = {slot: name if spec is None else lobby.user for slot, (name, spec) in slots.items()}
    # a fresh id each attempt: a match interrupted on the server must not block its replay
    match_id = f"{cfg.name}-{match.index}-{secrets.token_hex(3)}"
    created = lobby.create(cfg.match, match_id, overrides=cfg.overrides, seed=match.seed, mode=link.mode,
                           deadline_ms=link.deadline_ms, ready_timeout_s=2 * link.join_timeout_s, fill="idle",
                           seats=seats)
    try:
        for name, its_slots in remote.items():
            invite(session, link.name, name, match_id, its_slots, created["signed"], link.join_timeout_s)
    except Exception:
        lobby.stop(match_id)
        raise
    errors: list[BaseException] = []

    def run_bot(slot: str, name: str, spec: str) -> None:
        try:
            PolicyBot(spec, name=name).run(match_id, slot, client=client, session=session)
        except BaseException as e:  # reported by the league thread below
            errors.append(e)

    # not daemon threads: see ``remote.serve_invitations``
    threads = [threading.Thread(target=run_bot, args=(slot, name, spec))
               for slot, (name, spec) in slots.items() if spec is not None]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    info = lobby.inspect(match_id)
    while info["status"] not in ENDED_STATUSES:
        time.sleep(0.2)
        info = lobby.inspect(match_id)
    if errors:
        raise RuntimeError(f"match {match.key}: a local bot failed on the server: {errors[0]!r}")
    if info["status"] != MatchStatus.FINISHED:
        raise RuntimeError(f"match {match.key}: server match {match_id} ended {info['status']} ({info.get('error')})")
    not_joined = [s for s, st in info["slot_status"].items() if st["occupant"] != "remote"]
    if not_joined:
        raise RuntimeError(f"match {match.key}: slot(s) {not_joined} never got their bot; not recorded")
    # who actually played each seat, as the server saw them (its users are authenticated)
    impostors = {s: st["user"] for s, st in info["slot_status"].items() if st["user"] != seats[s]}
    if impostors:
        raise RuntimeError(f"match {match.key}: slot(s) played by other users than their seats {impostors}; "
                           "not recorded")
    summary = info["summary"]
    clock_s = float(cfg.game_config["clock_s"])
    duration_s = clock_s + summary["clock_s"] if summary["overtime"] else clock_s - summary["clock_s"]
    missed = {s: st.get("missed", 0) + st.get("disconnected", 0) for s, st in info["slot_status"].items()}
    return _result(cfg, match, summary["score"], duration_s,
                   {"where": "server", "server": link.name, "server_match": match_id,
                    "server_result": info.get("result_key"), "overtime": bool(summary["overtime"]),
                    "stats": summary.get("stats", {}), "team": summary.get("team", {}), "missed_decisions": missed})
