"""Nothing a bot does can stall or break a match: killed bots, slow bots, malformed and forged actions,
join/leave churn, a killed server, and a server that listens on loopback only. Real Zenoh sessions on
loopback, real bot subprocesses (``rocketdrl-ma bot`` and ``botproc.py``). Attacks by other clients on
the network are in ``test_attacks.py``."""
from __future__ import annotations

import os
import signal
import sqlite3
from pathlib import Path

import msgpack
import numpy as np
import psutil
import pytest
import zenoh
from server_helpers import SHORT, RawBot, wait_for

from rocketdrl_ma.results import ResultsStore
from rocketdrl_ma.server import LobbyClient, ServerError
from rocketdrl_ma.server.crypto import random_bytes
from rocketdrl_ma.server.protocol import PROTOCOL_VERSION, action_message, open_sealed, pack

# On 2 xdist workers (`make test XDIST=...`) this module's tests share one, so its module fixtures are made once
pytestmark = pytest.mark.xdist_group("test_reliability")

NEUTRAL = np.array([0, 0, 0, 0, 0, -1, -1, -1], np.float32)


def slot_info(running, match: str, slot: str) -> dict:
    return running.lobby.inspect(match)["slot_status"][slot]


@pytest.mark.slow
def test_killed_bot_is_replaced_shown_disconnected_and_rejoins(running, procs):
    # orange answers every decision 25 ms late (within the deadline): it sets a pace a test can follow
    running.lobby.create("matches/1v1.yaml", "m", overrides={**SHORT, "clock_s": 40.0}, ready_timeout_s=120)
    blue = procs.bot(running, "m", "blue_0")
    procs.botproc(running, "m", ["orange_0"], "--delay-ms", "25")
    token = blue.line("joined match m as blue_0").rsplit("--rejoin ", 1)[1]  # a private file: blue_0:<key>
    assert Path(token).read_text().startswith("blue_0:") and Path(token).stat().st_mode & 0o077 == 0
    wait_for(lambda: slot_info(running, "m", "blue_0")["received"] >= 20, 60, "blue to play 20 decisions")
    os.kill(blue.pid, signal.SIGKILL)
    gone = wait_for(lambda: (lambda s: s if not s["connected"] else None)(slot_info(running, "m", "blue_0")), 15,
                    "liveliness to show blue_0 disconnected")
    received_at_kill = gone["received"]
    # the match goes on without it: decisions advance, blue's are replaced and counted as disconnected
    wait_for(lambda: slot_info(running, "m", "blue_0")["disconnected"] >= 10, 30, "replaced decisions")
    assert running.lobby.inspect("m")["status"] == "running"
    rejoined = procs.bot(running, "m", rejoin=token)
    assert rejoined.line("joined match m as blue_0").endswith(token)  # its new token, in the same file
    wait_for(lambda: (lambda s: s["connected"] and s["received"] > received_at_kill + 10)(
        slot_info(running, "m", "blue_0")), 60, "the rejoined bot to play")
    info = running.wait_status("m", timeout_s=120)
    assert rejoined.wait(60) == 0 and "match m finished" in rejoined.line("match m")
    [result] = ResultsStore(running.results).results()
    slot = info["slot_status"]["blue_0"]
    assert result.details["missed_decisions"]["blue_0"] == slot["missed"] + slot["disconnected"] > 0
    assert slot["received"] + slot["missed"] + slot["disconnected"] == info["decision"]


def test_slow_bot_never_slows_the_others(running, procs):
    # the slow bot thinks 5x longer than the deadline (generous: the fast bot must answer within it)
    running.lobby.create("matches/1v1.yaml", "m", overrides={**SHORT, "clock_s": 2.0}, ready_timeout_s=120,
                         deadline_ms=150)
    fast = procs.bot(running, "m", "blue_0")
    slow_bot = procs.botproc(running, "m", ["orange_0"], "--delay-ms", "750")
    info = running.wait_status("m", timeout_s=120)
    assert fast.wait(60) == 0 and slow_bot.wait(60) == 0
    n = info["decision"]
    slow, quick = info["slot_status"]["orange_0"], info["slot_status"]["blue_0"]
    assert slow["missed"] >= 0.8 * n and slow["late"] > 0  # its answers come after the deadline: dropped
    assert quick["missed"] <= 0.1 * n and quick["received"] >= 0.9 * n
    # The match never waited for the slow bot: it only answered the decisions it found on waking, so it
    # sent a fraction of them (were decisions held until it answered, it would have sent one per decision).
    [sent] = [int(line.split()[2]) for line in slow_bot.lines if line.startswith("done orange_0")]
    assert sent <= 0.5 * n and slow["received"] + slow["late"] <= sent
    [result] = ResultsStore(running.results).results()
    assert result.details["missed_decisions"]["orange_0"] == slow["missed"]


def test_malformed_payloads_are_dropped_and_counted(running, procs):
    # a deadline the bots meet on a loaded machine: a missed decision means a hostile message cost it one
    running.lobby.create("matches/1v1.yaml", "m", overrides={**SHORT, "clock_s": 30.0}, ready_timeout_s=120,
                         deadline_ms=1000)
    states = []
    sub = running.session.declare_subscriber(running.server.keys.state("m"), lambda s: states.append(
        open_sealed(running.lobby.server_key, s.payload.to_bytes(), 1 << 24)))
    procs.bot(running, "m", "blue_0")
    orange = RawBot(running.session, running.lobby, "m", "orange_0", answer=lambda m: NEUTRAL)
    wait_for(lambda: len(orange.messages) > 5, 60, "the match to run")
    key, secret = orange.join.keys["act"], orange.join.secret

    def put(k: str, payload: bytes) -> None:
        # BLOCK: every hostile message must reach the server (a put's default, DROP, may lose one on a busy machine)
        running.session.put(k, payload, congestion_control=zenoh.CongestionControl.BLOCK)

    decision = lambda: orange.messages[-1]["decision"]  # noqa: E731
    put(key, np.random.default_rng(0).bytes(200))                                             # malformed
    put(key, msgpack.packb([1, 2, 3]))                                                        # malformed
    put(key, b"\x00" * (512 * 1024))                                                          # oversize
    put(key, b"\x00" * (10 * 1024 * 1024))                         # over Zenoh's max_message_size: never seen
    put(key, msgpack.packb({"v": PROTOCOL_VERSION + 1, "body": b"", "mac": b"\0" * 32}))      # bad_version
    put(key, pack({"body": pack({"decision": decision()}), "mac": random_bytes(32)}))         # bad_mac
    # keys of no slot, or of the slot under another user's prefix: the server does not even listen there
    put(key.replace("orange_0", "purple_0"), action_message(secret, "m", "purple_0", 0, NEUTRAL))
    put(key.replace("/u/guest/", "/u/mallory/"), action_message(secret, "m", "orange_0", 0, NEUTRAL))
    orange.send(NEUTRAL, decision(), slot="blue_0")                 # invalid: the body names another slot
    orange.send(np.zeros(5, np.float32), decision())                                          # invalid
    orange.send(np.full(8, np.nan, np.float32), decision())                                   # invalid
    orange.send(np.full(8, 7.0, np.float32), decision())                                      # invalid
    orange.send({"$nd": "|O", "shape": [1], "data": b"\0" * 8}, decision())                   # invalid
    expected = {"malformed": 2, "oversize": 1, "bad_version": 1, "bad_mac": 1, "invalid_action": 5}
    wait_for(lambda: all(running.lobby.inspect("m")["rejected"].get(k, 0) >= v for k, v in expected.items()),
             30, f"the server to count {expected}")
    wait_for(lambda: len(orange.errors) == 5, 10, "signed error messages to the slot's bot")
    assert sum(e.startswith("action for orange_0") for e in orange.errors) == 3, orange.errors
    info = running.wait_status("m", timeout_s=120)
    # Besides the hostile messages the server may count its own NEUTRAL answers as ``late`` on a loaded machine
    rejected = {k: v for k, v in info["rejected"].items() if k != "late"}
    assert rejected == expected, sorted(info["rejected"].items())
    assert info["slot_status"]["orange_0"]["invalid"] == 5
    assert info["slot_status"]["orange_0"]["received"] >= 0.9 * info["decision"]
    # no state was corrupted: every published state is finite and the match ended normally with a result
    for s in states:
        for car in s["state"]["cars"].values():
            assert np.all(np.isfinite(car["pos"])) and np.all(np.isfinite(car["vel"]))
        assert np.all(np.isfinite(s["state"]["ball"]["pos"]))
    assert set(s["state"]["last_controls"]["orange_0"][0] for s in states) == {0.0}
    assert len(ResultsStore(running.results)) == 1
    assert running.lobby.list()[0]["status"] == "finished"
    sub.undeclare()
    orange.disconnect()


def test_acting_for_another_slot_with_its_own_secret_or_a_made_up_one_is_rejected(running, procs):
    # a deadline the bots meet on a loaded machine: what counts is which actions are refused, not latency
    running.lobby.create("matches/1v1.yaml", "m", overrides={**SHORT, "clock_s": 4.0}, ready_timeout_s=120,
                         deadline_ms=1000)
    states = []
    sub = running.session.declare_subscriber(running.server.keys.state("m"), lambda s: states.append(
        open_sealed(running.lobby.server_key, s.payload.to_bytes(), 1 << 24)))
    forged = np.array([-1, 1, 1, 1, 1, 1, 1, 1], np.float32)  # pitch, yaw and roll: scripted bots never use them
    holder = []

    def answer(message):
        blue = holder[0]
        orange_key = blue.join.keys["act"].replace("blue_0", "orange_0")
        blue.send(forged, message["decision"], key=orange_key, slot="orange_0")           # own secret, other slot
        blue.send(forged, message["decision"], secret=random_bytes(32), key=orange_key, slot="orange_0")
        return NEUTRAL

    procs.bot(running, "m", "orange_0")
    holder.append(RawBot(running.session, running.lobby, "m", "blue_0", answer=answer))
    info = running.wait_status("m", timeout_s=120)
    blue = holder[0]
    sent = 2 * sum(1 for m in blue.messages if not m["done"])
    wait_for(lambda: running.lobby.inspect("m")["rejected"].get("bad_mac", 0) == sent, 10, "all forgeries counted")
    assert info["slot_status"]["orange_0"]["received"] >= 0.9 * info["decision"]
    orange_controls = [s["state"]["last_controls"]["orange_0"] for s in states]
    assert orange_controls and not any(c[4] == 1.0 for c in orange_controls)  # no forged roll ever applied
    assert sent > 20
    sub.undeclare()
    blue.disconnect()


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """One ``rocketdrl-ma serve`` subprocess for the tests that watch the server process from outside."""
    import yaml
    from server_helpers import REPO, Procs
    procs = Procs()
    tmp = tmp_path_factory.mktemp("served")
    config = yaml.safe_load((REPO / "server/local.yaml").read_text())
    config["limits"] = {"requests_per_s": 0}  # the churn test sends thousands of lobby requests at once
    config["matches"] = [{"id": "duel", "config": "matches/1v1.yaml", "ready_timeout_s": 3600}]
    (tmp / "server.yaml").write_text(yaml.safe_dump(config))
    served = procs.serve(tmp, name="sub", config=str(tmp / "server.yaml"))
    session = served.client_settings.zenoh.open()
    yield served.proc, served.endpoint, LobbyClient(session, served.client_settings)
    session.close()
    procs.kill_all()


def test_server_listens_on_loopback_only(served):
    proc, endpoint, _ = served
    sockets = psutil.Process(proc.pid).net_connections(kind="inet")
    listening = [c for c in sockets if c.status == psutil.CONN_LISTEN or c.type == 2]  # 2: SOCK_DGRAM
    assert listening, "the server should listen somewhere"
    assert all(c.laddr.ip in ("127.0.0.1", "::1") for c in listening), listening
    assert any(c.laddr.port == int(endpoint.rsplit(":", 1)[1]) for c in listening)


def test_serve_prints_the_tickets_of_its_own_matches(served):
    proc, _, lobby = served
    path = Path(next(line for line in proc.lines if line.startswith("match duel: tickets in ")).split()[4])
    tickets = dict(line.split() for line in path.read_text().splitlines())
    assert set(tickets) == {"blue_0", "orange_0"} and path.stat().st_mode & 0o077 == 0
    with pytest.raises(ServerError, match="reserved: join with its ticket"):
        lobby.join("duel", "orange_0")
    join = lobby.join("duel", "orange_0", ticket=tickets["orange_0"])
    lobby.leave("duel", join.slot, join.secret)


def test_join_leave_cycles_do_not_leak(served):
    proc, _, lobby = served
    server = psutil.Process(proc.pid)
    lobby.create("matches/4v4.yaml", "churn", ready_timeout_s=3600, open=True)
    session = lobby.session

    def cycle():
        join = lobby.join("churn")
        token = session.liveliness().declare_token(join.keys["alive"])
        token.undeclare()
        lobby.leave("churn", join.slot, join.secret)

    for _ in range(100):  # warm-up: caches, allocator pools, Zenoh's own tables
        cycle()
    before = (server.num_threads(), server.num_fds(), server.memory_info().rss)
    for _ in range(1000):
        cycle()
    after = (server.num_threads(), server.num_fds(), server.memory_info().rss)
    assert after[0] - before[0] <= 2, f"threads {before[0]} -> {after[0]}"
    assert after[1] - before[1] <= 4, f"fds {before[1]} -> {after[1]}"
    assert after[2] - before[2] <= 16 * 1024 * 1024, f"rss {before[2] >> 20} -> {after[2] >> 20} MB"
    info = lobby.inspect("churn")
    assert {s["occupant"] for s in info["slot_status"].values()} == {"open"} and info["status"] == "waiting"


def test_killed_server_keeps_every_finished_match(procs, tmp_path):
    served = procs.serve(tmp_path, name="k")
    proc = served.proc
    session = served.client_settings.zenoh.open()
    lobby = LobbyClient(session, served.client_settings)
    for i in range(3):
        lobby.create("matches/1v1.yaml", f"done{i}", overrides=SHORT, ready_timeout_s=0)
    lobby.create("matches/1v1.yaml", "long", overrides={"clock_s": 300.0}, ready_timeout_s=0)
    finished = wait_for(lambda: (lambda ms: ms if all(m["result_key"] for m in ms) else None)(
        [m for m in lobby.list() if m["id"].startswith("done")]), 120, "three finished matches")
    wait_for(lambda: lobby.inspect("long")["decision"] > 10, 60, "the long match to run")
    session.close()
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(10)
    path = tmp_path / "results.sqlite"
    assert sqlite3.connect(path).execute("PRAGMA integrity_check").fetchone() == ("ok",)
    with ResultsStore(path) as store:
        stored = {r.match_key: r for r in store.results(source="server")}
    assert set(stored) == {m["result_key"] for m in finished}
    assert {r.details["match_id"] for r in stored.values()} == {"done0", "done1", "done2"}
