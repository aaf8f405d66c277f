"""The two-machine recipe, on loopback, every part its own process as docs/guides/server.md runs it:
``rocketdrl-ma keys`` (key, admin secret, passwords, TLS CA and certificate, one client file per user),
``rocketdrl-ma router`` (TLS for the bots, user/password authentication, access control generated from the
server's YAML), a match server that is the router's client and listens on nothing, and bots and the lobby
as clients with their own files. Wrong passwords, a missing CA and plaintext are refused."""
from __future__ import annotations

import psutil
import pytest
from server_helpers import ROLES, cli, free_endpoint, free_tls_endpoint, write_yaml

from rocketdrl_ma.results import ResultsStore


@pytest.mark.slow
def test_router_with_tls_users_and_access_control(procs, tmp_path):
    tls_endpoint, server_endpoint = free_tls_endpoint(), free_endpoint()
    keys = tmp_path / "keys"
    server_cfg = write_yaml(tmp_path / "server.yaml", {
        "name": "rt", "zenoh": {"mode": "client", "connect": [server_endpoint]}, "key_dir": str(keys),
        "access": {"users_file": str(keys / "users.txt"), "roles": ROLES}, "match_defaults": {"open": False}})
    router_cfg = write_yaml(tmp_path / "router.yaml", {
        "zenoh": {"mode": "router", "listen": [tls_endpoint, server_endpoint],
                  "tls": {"listen_certificate": str(keys / "tls/cert.pem"),
                          "listen_private_key": str(keys / "tls/key.pem")}},
        "serves": server_cfg})
    made = procs.start(cli("keys", router_cfg, "--tls-host", "127.0.0.1"))
    assert made.wait(60) == 0, made.output()
    assert made.line("client config for alice (player)") and made.line("TLS certificate for ['127.0.0.1']")
    assert (keys / "users.txt").stat().st_mode & 0o077 == 0 and (keys / "tls/key.pem").stat().st_mode & 0o077 == 0
    router = procs.start(cli("router", router_cfg))
    assert "access control for server 'rt'" in router.line("router listening", 60)
    server = procs.start(cli("serve", server_cfg, "--results", str(tmp_path / "results.sqlite")))
    assert "client listening on (none)" in server.line("serving 'rt'", 60)
    assert "access control on" in server.line("server key ed25519:")
    own = psutil.Process(server.pid).net_connections(kind="inet")
    assert not [c for c in own if c.status == psutil.CONN_LISTEN], own  # it only dials the router

    client = lambda user: ["--config", str(keys / "clients" / f"{user}.yaml")]  # noqa: E731
    bad = write_yaml(tmp_path / "bad.yaml", {
        "server": "rt", "zenoh": {"mode": "client", "connect": [tls_endpoint], "auth": {"user": "alice",
                                                                                         "password": "guess"}}})
    plain = write_yaml(tmp_path / "plain.yaml", {
        "server": "rt", "zenoh": {"mode": "client", "connect": [tls_endpoint.replace("tls/", "tcp/")]}})
    for refused_cfg in (bad, plain):
        refused = procs.start(cli("lobby", "list", "--config", refused_cfg))
        assert refused.wait(60) == 2 and refused.line("error: zenoh: cannot open a client session")
    not_admin = procs.start(cli("lobby", "create", "matches/1v1.yaml", *client("alice")))
    assert not_admin.wait(60) == 2 and not_admin.line("error: create: op 'create': needs the admin role")

    create = procs.start(cli("lobby", "create", "matches/1v1.yaml", "--id", "R", "--ready-timeout", "120",
                             "--print-tickets",
                             "--set", "clock_s=2", "--set", "kickoff_countdown_s=0", "--set", "overtime_limit_s=1",
                             *client("ops")))
    assert create.wait(60) == 0, create.output()
    tickets = {line.split()[1]: line.split()[2] for line in create.lines if line.startswith("ticket ")}
    assert set(tickets) == {"blue_0", "orange_0"}
    bots = [procs.start(cli("bot", "--policy", policy, "--match", "R", "--slot", slot, "--ticket", tickets[slot],
                            *client(user)))
            for slot, policy, user in (("blue_0", "scripted:ball_chaser", "alice"), ("orange_0", "scripted:goalie",
                                                                                      "bob"))]
    for bot in bots:
        assert bot.wait(120) == 0, bot.output()
        assert bot.line("match R finished")
    [result] = ResultsStore(tmp_path / "results.sqlite").results()
    assert result.entrants == {"blue_0": "scripted:ball_chaser", "orange_0": "scripted:goalie"}
    assert {b["user"] for b in result.details["bots"].values()} == {"alice", "bob"}
    assert all(b["received"] > 0 for b in result.details["bots"].values())
    for proc in (server, router):
        proc.popen.terminate()
        assert proc.wait(30) == 0, proc.output()
