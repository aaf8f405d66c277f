"""The two-machine set-up, on loopback: ``rocketdrl-ma router`` (a Python process in Zenoh router mode
with user/password authentication), a match server in client mode that listens on nothing, and bots in
client mode, all meeting at the router. A client with a wrong password is refused."""
from __future__ import annotations

import json

import psutil
import pytest
from server_helpers import cli, free_endpoint

from rocketdrl_ma.results import ResultsStore


def write_yaml(path, data: dict) -> str:
    path.write_text(json.dumps(data))  # JSON is YAML
    return str(path)


@pytest.mark.slow
def test_router_with_auth_joins_a_client_mode_server_and_bots(procs, tmp_path):
    endpoint = free_endpoint()
    users = tmp_path / "users.txt"
    users.write_text("server:pw-server\nalice:pw-alice\n")
    router = procs.start(cli("router", write_yaml(tmp_path / "router.yaml", {
        "zenoh": {"mode": "router", "listen": [endpoint], "auth": {"dictionary_file": str(users)}}})))
    router.line("router listening", 60)
    server_cfg = write_yaml(tmp_path / "server.yaml", {
        "name": "rt", "zenoh": {"mode": "client", "connect": [endpoint],
                                "auth": {"user": "server", "password": "pw-server"}}})
    server = procs.start(cli("serve", server_cfg, "--results", str(tmp_path / "results.sqlite")))
    assert "client listening on (none)" in server.line("serving 'rt'", 60)
    own = psutil.Process(server.pid).net_connections(kind="inet")
    assert not [c for c in own if c.status == psutil.CONN_LISTEN], own  # it only dials the router

    client = ["--server", "rt", "--config", write_yaml(tmp_path / "client.yaml", {
        "zenoh": {"mode": "client", "connect": [endpoint], "auth": {"user": "alice", "password": "pw-alice"}}})]
    bad = ["--server", "rt", "--config", write_yaml(tmp_path / "bad.yaml", {
        "zenoh": {"mode": "client", "connect": [endpoint], "auth": {"user": "alice", "password": "guess"}}})]
    refused = procs.start(cli("lobby", "list", *bad))
    assert refused.wait(60) == 2 and refused.line("error: zenoh: cannot open a client session")

    create = procs.start(cli("lobby", "create", "matches/1v1.yaml", "--id", "R", "--ready-timeout", "120",
                             "--set", "clock_s=2", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=1",
                             *client))
    assert create.wait(60) == 0, create.output()
    bots = [procs.start(cli("bot", "--policy", policy, "--match", "R", "--slot", slot, *client))
            for slot, policy in (("blue_0", "scripted:ball_chaser"), ("orange_0", "scripted:goalie"))]
    for bot in bots:
        assert bot.wait(120) == 0, bot.output()
        assert bot.line("match R finished")
    [result] = ResultsStore(tmp_path / "results.sqlite").results()
    assert result.entrants == {"blue_0": "scripted:ball_chaser", "orange_0": "scripted:goalie"}
    assert all(b["received"] > 0 for b in result.details["bots"].values())
    for proc in (server, router):
        proc.popen.terminate()
        assert proc.wait(30) == 0, proc.output()
