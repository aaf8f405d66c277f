"""The lobby and matches on a real in-process server (Zenoh peer on a free loopback port): create, list,
inspect, stop (with the admin secret, never sent); joining (open matches, tickets, seats), rejoining with
the slot's secret; lockstep and real-time play with SDK bots; replacement actions; results."""
from __future__ import annotations

import threading
import time

import msgpack
import numpy as np
import pytest
from gymnasium import spaces
from server_helpers import SHORT, RawBot, wait_for

from rocketdrl_ma.env.actions import DriveActions
from rocketdrl_ma.policies.scripted import make_scripted
from rocketdrl_ma.results import ResultsStore
from rocketdrl_ma.rules.state import GameState
from rocketdrl_ma.server import PROTOCOL_VERSION, Bot, PolicyBot, ServerError
from rocketdrl_ma.server.client import LobbyClient
from rocketdrl_ma.server.crypto import random_bytes
from rocketdrl_ma.server.protocol import open_sealed, pack, pack_value


def raw_query(running, payload: bytes, user: str = "guest", timeout_s: float = 5.0) -> tuple[bool, dict] | None:
    """One lobby get with an arbitrary payload: (ok, verified reply body), or None without any reply."""
    for reply in running.session.get(running.server.keys.lobby(user), payload=payload, timeout=timeout_s):
        if reply.ok is not None:
            return True, open_sealed(running.lobby.server_key, reply.ok.payload.to_bytes(), 1 << 24)
        raw = reply.err.payload.to_bytes()
        return (False, open_sealed(running.lobby.server_key, raw, 1 << 24)) if raw != b"Timeout" else None
    return None


def request(op: str, **args) -> bytes:
    return pack({"op": op, "nonce": random_bytes(), "args": pack_value(args)})


def test_create_list_inspect_stop_several_matches(running):
    lobby = running.lobby
    a = lobby.create("matches/1v1.yaml", "a", ready_timeout_s=60)
    b = lobby.create("minigames/penalty.yaml", "b", ready_timeout_s=60)
    c = lobby.create("matches/3v3.yaml", "c", ready_timeout_s=60, overrides={"clock_s": 60.0})
    assert a["status"] == b["status"] == c["status"] == "waiting"
    assert list(a["slot_status"]) == ["blue_0", "orange_0"] and list(b["slot_status"]) == ["blue_0"]
    assert len(c["slot_status"]) == 6 and c["game_config"]["clock_s"] == 60.0
    assert {m["id"]: m["status"] for m in lobby.list()} == {"a": "waiting", "b": "waiting", "c": "waiting"}
    info = lobby.inspect("b")
    assert info["game_config"]["mode"] == "penalty" and info["options"]["deadline_ms"] == 50
    lobby.stop("a")
    running.wait_status("a", ("stopped",))
    assert {m["id"]: m["status"] for m in lobby.list()} == {"a": "stopped", "b": "waiting", "c": "waiting"}
    with pytest.raises(ServerError, match="already exists"):
        lobby.create("matches/1v1.yaml", "b")
    with pytest.raises(ServerError, match=r"overrides: \['clok_s'\] may not be changed"):
        lobby.create("matches/1v1.yaml", overrides={"clok_s": 3})
    with pytest.raises(ServerError, match="no config 'matches/9v9.yaml' on this server"):
        lobby.create("matches/9v9.yaml")
    with pytest.raises(ServerError, match="replacement"):
        lobby.create("matches/1v1.yaml", replacement="sometimes")
    with pytest.raises(ServerError, match="no match 'zz'"):
        lobby.inspect("zz")
    with pytest.raises(ServerError, match="unknown lobby op 'dance'"):
        lobby.request("dance")
    assert len(ResultsStore(running.results)) == 0  # stopped matches are not results


def test_bad_requests_get_signed_error_replies_and_the_server_goes_on(running):
    ok, reply = raw_query(running, msgpack.packb({"v": PROTOCOL_VERSION + 98, "op": "list"}))
    assert not ok and reply["error"] == (f"v: protocol version {PROTOCOL_VERSION + 98} is not supported; this "
                                         f"server speaks version {PROTOCOL_VERSION}")
    ok, reply = raw_query(running, np.random.default_rng(1).bytes(1000))
    assert not ok and "not valid msgpack" in reply["error"]
    ok, reply = raw_query(running, msgpack.packb([1, 2]))
    assert not ok and "expected a map" in reply["error"]
    ok, reply = raw_query(running, pack({"op": "list"}))
    assert not ok and reply["error"].startswith("nonce:")
    ok, reply = raw_query(running, request("create", config="matches/1v1.yaml", id="x/y"))
    assert not ok and reply["error"].startswith("op 'create': needs the admin secret")
    ok, reply = raw_query(running, pack({"op": "list", "nonce": random_bytes(), "args": {"not": "bin"}}))
    assert not ok and reply["error"].startswith("args:")
    ok, reply = raw_query(running, request("list"), user="*")  # a wildcard query asks as nobody
    assert not ok and reply["error"].startswith("user: expected 1-64 letters")
    assert running.server.requests_rejected == 7
    # 10 MB is over what Zenoh itself reassembles for the server (max_message_size): dropped unread
    assert raw_query(running, b"\x00" * (10 * 1024 * 1024), timeout_s=1.0) is None
    assert running.server.requests_rejected == 7
    nonce = random_bytes()
    ok, reply = raw_query(running, pack({"op": "list", "nonce": nonce, "args": pack_value({})}))
    assert ok and reply["matches"] == [] and reply["nonce"] == nonce and reply["op"] == "list"


def test_admin_secret_guards_create_and_stop_and_never_travels(running, tmp_path):
    admin_secret = (running.key_dir / "admin.secret").read_text().strip()
    # a client without the admin secret (another folder, nothing pinned but the server key)
    stranger = LobbyClient(running.session, running.client(key_dir=str(tmp_path / "elsewhere"),
                                                           server_key=running.lobby.server_key.text))
    with pytest.raises(ServerError, match="needs the admin secret"):
        stranger.create("matches/1v1.yaml", "m")
    wrong = LobbyClient(running.session, running.client(admin_secret="ab" * 32))
    with pytest.raises(ServerError, match="needs the admin secret"):
        wrong.create("matches/1v1.yaml", "m")
    queries = []
    spy = running.session.declare_queryable(running.server.keys.lobby("guest"),
                                            lambda q: queries.append(q.payload.to_bytes() if q.payload else b""))
    running.lobby.create("matches/1v1.yaml", "m", ready_timeout_s=60)
    spy.undeclare()
    assert queries and not any(admin_secret.encode() in q or bytes.fromhex(admin_secret) in q for q in queries)
    # a create request seen on the way cannot be replayed: its challenge is used up
    create = next(q for q in queries if b"create" in q)
    ok, reply = raw_query(running, create)
    assert not ok and "admin secret" in reply["error"]
    with pytest.raises(ServerError, match="needs the admin secret"):
        stranger.stop("m")
    assert running.lobby.list()[0]["id"] == "m" and running.lobby.inspect("m")["status"] == "waiting"
    running.lobby.stop("m")
    running.wait_status("m", ("stopped",))


def test_ended_matches_are_forgotten_beyond_the_bound(tmp_path):
    from server_helpers import Running
    r = Running(tmp_path, max_finished_kept=2)
    try:
        for i in range(4):
            r.lobby.create("matches/1v1.yaml", f"s{i}", ready_timeout_s=60)
            r.lobby.stop(f"s{i}")
            r.wait_status(f"s{i}", ("stopped",))
        r.lobby.create("matches/1v1.yaml", "new", ready_timeout_s=60)
        assert {m["id"] for m in r.lobby.list()} == {"s3", "new"}  # at most 2 kept, the new one included
        with pytest.raises(ServerError, match="no match 's0'"):
            r.lobby.inspect("s0")
    finally:
        r.close()


def test_joining_slots_secrets_and_requested_formats(running):
    lobby = running.lobby
    lobby.create("matches/2v2.yaml", "m", ready_timeout_s=60)
    first = lobby.join("m")
    assert first.slot == "blue_0" and len(first.secret) == 32 and first.status == "waiting"
    assert first.keys["act"] == "rocketdrl/test/u/guest/match/m/blue_0/act"
    assert first.observation_space.shape == (127,) and first.action_space.shape == (8,)
    named = lobby.join("m", "orange_1", observation="general_sensors", action="lookup")
    assert named.slot == "orange_1" and named.observation_space.shape == (18,)
    assert named.action_space == spaces.Discrete(90) and named.observation == {"name": "general_sensors"}
    assert named.secret != first.secret
    with pytest.raises(ServerError, match=r"'orange_1' of match 'm' is taken; open slots: \['blue_1', 'orange_0'\]"):
        lobby.join("m", "orange_1")
    with pytest.raises(ServerError, match="'purple_0' is not a slot"):
        lobby.join("m", "purple_0")
    with pytest.raises(ServerError, match="unknown observation builder 'eyes'"):
        lobby.join("m", observation="eyes")
    # a reconnect proves the rejoin key (not the action key) and gets new keys and a new lease
    with pytest.raises(ServerError, match="does not prove the rejoin key of slot 'blue_0'"):
        lobby.rejoin("m", "blue_0", first.secret)
    again = lobby.rejoin("m", "blue_0", first.rejoin_key)
    assert again.slot == "blue_0" and again.lease != first.lease and first.rejoin_key != first.secret
    assert {again.secret, again.rejoin_key}.isdisjoint({first.secret, first.rejoin_key})
    with pytest.raises(ServerError, match="does not prove the rejoin key of slot 'blue_0'"):
        lobby.rejoin("m", "blue_0", first.rejoin_key)  # the old keys stopped working
    with pytest.raises(ServerError, match="does not prove the rejoin key of slot 'orange_1'"):
        lobby.rejoin("m", "orange_1", again.rejoin_key)  # a key works for its own slot only
    other_user = LobbyClient(running.session, running.client(user="mallory"))
    with pytest.raises(ServerError, match="for user 'mallory'"):
        other_user.rejoin("m", "blue_0", again.rejoin_key)  # and for its own user only
    with pytest.raises(ServerError, match="does not prove the secret of slot 'blue_0'"):
        lobby.leave("m", "blue_0", first.secret)
    first = again
    lobby.leave("m", "blue_0", first.secret)
    assert lobby.inspect("m")["slot_status"]["blue_0"]["occupant"] == "open"
    lobby.join("m"), lobby.join("m"), lobby.join("m")
    with pytest.raises(ServerError, match="no open slot"):
        lobby.join("m")


def test_tickets_and_seats_decide_who_joins(authed):
    running = authed  # seats need authenticated users
    lobby = running.lobby
    reply = lobby.create("matches/2v2.yaml", "t", ready_timeout_s=60, open=False, seats={"orange_1": "bob"})
    tickets = reply["tickets"]
    assert set(tickets) == {"blue_0", "blue_1", "orange_0"}  # the seat needs no ticket
    with pytest.raises(ServerError, match="reserved: join with its ticket"):
        lobby.join("t", "blue_0")
    with pytest.raises(ServerError, match="no open slot for user 'local'; its slots need a ticket or a seat"):
        lobby.join("t")
    with pytest.raises(ServerError, match="reserved"):
        lobby.join("t", "blue_0", ticket=tickets["blue_1"])  # a ticket opens its own slot only
    assert lobby.join("t", "blue_0", ticket=tickets["blue_0"]).slot == "blue_0"
    assert lobby.join("t", ticket=tickets["orange_0"]).slot == "orange_0"  # any slot the ticket opens
    with pytest.raises(ServerError, match="is taken"):
        lobby.join("t", "blue_0", ticket=tickets["blue_0"])  # used
    with pytest.raises(ServerError, match="user 'bob''s seat"):
        lobby.join("t", "orange_1")
    bob = running.lobby_as("bob")
    seat = bob.join("t")
    assert seat.slot == "orange_1" and seat.keys["obs"].startswith("rocketdrl/test/u/bob/")
    info = lobby.inspect("t")
    assert info["slot_status"]["orange_1"]["seat"] == "bob" and info["slot_status"]["blue_0"]["user"] == "local"
    assert "tickets" not in info  # only the creator's create reply holds them


class Recorder(Bot):
    """An SDK bot with its own sensors and action format (the seed's) that remembers what it saw; it
    chases the ball, answering in the seed's 5-number format."""

    observation = "general_sensors"
    action = "seed"
    name = "recorder"

    def __init__(self):
        self.seen: list[tuple] = []
        self.chaser, self.encoder = make_scripted("ball_chaser"), DriveActions()

    def act(self, obs, info):
        self.seen.append((obs.shape, obs.dtype, info["decision"], isinstance(info["state"], GameState)))
        return self.encoder.encode(self.chaser.controls(info["agent"], info["state"]))


def play_threads(*jobs) -> dict:
    reports, errors = {}, []

    def run(key, fn):
        try:
            reports[key] = fn()
        except Exception as e:
            errors.append(e)
    threads = [threading.Thread(target=run, args=job) for job in jobs]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    if errors:
        raise errors[0]
    return reports


def test_lockstep_match_with_sdk_bots_records_a_result(running):
    # every decision must be answered: the server's longest deadline, which a busy machine does not miss, costs
    # nothing here (lockstep moves on as soon as both bots answered)
    running.lobby.create("matches/1v1.yaml", "m", overrides=SHORT, ready_timeout_s=60, seed=7, deadline_ms=2000)
    recorder = Recorder()
    reports = play_threads(
        ("blue", lambda: recorder.run("m", "blue_0", client=running.client_settings)),
        ("orange", lambda: PolicyBot("scripted:goalie").run("m", "orange_0", client=running.client_settings)))
    info = running.wait_status("m")
    shapes = {s[:2] for s in recorder.seen}
    assert shapes == {((18,), np.dtype(np.float32))} and all(s[3] for s in recorder.seen)
    assert [s[2] for s in recorder.seen] == list(range(len(recorder.seen)))  # every decision, in order
    assert reports["blue"].reason == "finished" and reports["blue"].decisions == info["decision"]
    assert info["slot_status"]["blue_0"]["received"] == info["decision"]
    [result] = ResultsStore(running.results).results()
    assert result.source == "server" and result.match_key == info["result_key"] and result.seed == 7
    assert result.entrants == {"blue_0": "recorder", "orange_0": "scripted:goalie"}
    assert (result.score_blue, result.score_orange) == (reports["blue"].summary["score"]["blue"],
                                                        reports["blue"].summary["score"]["orange"])
    assert result.details["missed_decisions"] == {"blue_0": 0, "orange_0": 0}
    assert result.details["events"].get("touch", 0) >= 1 and result.details["mode"] == "lockstep"
    assert result.duration_s >= 3.0 and result.config["clock_s"] == 3.0
    assert result.details["stats"]["blue_0"]["touches"] == result.details["events"]["touch"] - \
        result.details["stats"]["orange_0"]["touches"]


def test_readiness_timeout_fills_empty_slots(running):
    running.lobby.create("matches/2v2.yaml", "idle", overrides=SHORT, ready_timeout_s=0.3, fill="idle")
    running.lobby.create("matches/2v2.yaml", "chase", overrides=SHORT, ready_timeout_s=0.3)
    idle, chase = running.wait_status("idle"), running.wait_status("chase")
    assert {s["occupant"] for s in idle["slot_status"].values()} == {"fill"}
    results = {r.details["match_id"]: r for r in ResultsStore(running.results).results()}
    assert set(results["idle"].entrants.values()) == {"idle"}
    assert set(results["chase"].entrants.values()) == {"scripted:ball_chaser"}
    assert results["idle"].details["events"].get("touch", 0) == 0  # idle cars never reach the ball
    assert results["chase"].details["events"]["touch"] > 0


@pytest.mark.parametrize("replacement", ["repeat", "neutral"])
def test_missing_actions_are_replaced_and_counted(running, replacement):
    running.lobby.create("matches/1v1.yaml", "m", overrides=SHORT, ready_timeout_s=120, deadline_ms=20,
                         replacement=replacement)
    states = []
    sub = running.session.declare_subscriber(running.server.keys.state("m"), lambda s: states.append(
        open_sealed(running.lobby.server_key, s.payload.to_bytes(), 1 << 24)))
    full_throttle = np.array([1, 0, 0, 0, 0, -1, -1, -1], np.float32)
    coast = np.array([0, 0, 0, 0, 0, -1, -1, -1], np.float32)
    blue_0 = lambda: running.lobby.inspect("m")["slot_status"]["blue_0"]  # noqa: E731

    def send_decision_0(bot: RawBot) -> None:
        # sent and received before the match may start, so no deadline can miss it on a busy machine
        bot.send(full_throttle, 0)
        wait_for(lambda: blue_0()["received"] == 1, 30, "blue's action for decision 0 to arrive")
        assert running.lobby.inspect("m")["status"] == "waiting"

    # orange answers every decision; the match starts once both bots are seated and alive
    orange = RawBot(running.session, running.lobby, "m", "orange_0", answer=lambda m: coast)
    # Full throttle at decision 0, then silence: every later decision misses its deadline
    bot = RawBot(running.session, running.lobby, "m", "blue_0", before_alive=send_decision_0)
    info = running.wait_status("m")
    controls = [s["state"]["last_controls"]["blue_0"][0] for s in states if s["decision"] >= 3]
    assert controls and set(controls) == ({1.0} if replacement == "repeat" else {0.0})
    slot = info["slot_status"]["blue_0"]
    # a streak of missed decisions counts as a disconnect: the match stops waiting for the slot
    streak = running.server.settings.limits.missed_streak
    assert slot["received"] == 1 and slot["missed"] == streak and slot["stalled"] and not slot["connected"]
    assert slot["missed"] + slot["disconnected"] == info["decision"] - 1
    assert ResultsStore(running.results).results()[0].details["missed_decisions"]["blue_0"] == info["decision"] - 1
    sub.undeclare()
    bot.disconnect()
    orange.disconnect()


def test_realtime_mode_ticks_at_wall_clock(running):
    game_s = 1.5
    running.lobby.create("matches/1v1.yaml", "rt", mode="realtime", ready_timeout_s=0.5,
                         overrides={**SHORT, "clock_s": game_s})
    t0 = time.monotonic()
    report = PolicyBot("scripted:ball_chaser").run("rt", "blue_0", client=running.client_settings)
    wall_s = time.monotonic() - t0
    info = running.wait_status("rt")
    [result] = ResultsStore(running.results).results()
    # 120 ticks per second of wall clock: the game cannot run ahead of real time (lower bound only)
    assert wall_s >= result.duration_s * 0.95 and result.duration_s >= game_s
    assert info["decision"] == pytest.approx(result.duration_s * 15, abs=2)  # one decision per 8 ticks
    assert report.decisions > info["decision"] // 2 and info["slot_status"]["blue_0"]["received"] > 0
