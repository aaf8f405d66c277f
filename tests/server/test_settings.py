"""Server, client, Zenoh and match settings: loopback unless the config says otherwise, TLS and users beyond
it, bounds on what the lobby accepts, errors that name keys."""
from __future__ import annotations

import pytest

from rocketdrl_ma.server.access import acl_config
from rocketdrl_ma.server.router import RouterSettings
from rocketdrl_ma.server.settings import (AccessSettings, ClientSettings, Limits, MatchOptions, ServerSettings,
                                          ZenohSettings, is_loopback_endpoint, is_wildcard_endpoint)
from server_helpers import REPO


def test_shipped_configs_load_and_are_secure(monkeypatch):
    monkeypatch.chdir(REPO)  # the router YAML names the server YAML by its path from the repository
    local = ServerSettings.load("server/local.yaml")
    assert local.zenoh.mode == "peer" and local.zenoh.listen_endpoints() == ("tcp/127.0.0.1:7447",)
    assert not local.zenoh.multicast and local.match_defaults.deadline_ms == 50 and not local.match_defaults.open
    # authenticated by default: its users' passwords made in its key dir on the first start
    assert local.access.enabled and local.access.roles == {"local": "admin"}
    assert str(local.keys_path) == "runs/server/local"
    assert str(local.users_path) == "runs/server/local/users.txt"
    demo = ServerSettings.load("server/open.yaml")  # the open mode, named as such
    assert not demo.access.enabled and demo.zenoh.listen_endpoints() == ("tcp/127.0.0.1:7447",) and demo.name == "local"
    lan = ServerSettings.load("server/lan.yaml")
    assert lan.zenoh.mode == "peer" and lan.access.enabled and not lan.match_defaults.open
    assert all(e.startswith("tls/") and not is_wildcard_endpoint(e) for e in lan.zenoh.remote_listen())
    assert set(lan.access.roles.values()) == {"admin", "player", "spectator"}
    remote = ServerSettings.load("server/remote-server.yaml")
    assert remote.zenoh.mode == "client" and remote.zenoh.listen_endpoints() == () and remote.access.enabled
    router = RouterSettings.load("server/router.yaml")
    assert router.zenoh.mode == "router" and router.serves.name == remote.name
    assert all(e.startswith("tls/") and not is_wildcard_endpoint(e) for e in router.zenoh.remote_listen())
    client = ClientSettings.load("server/client.yaml")
    assert client.zenoh.mode == "client" and client.zenoh.connect[0].startswith("tls/") and client.user_name == "alice"


@pytest.mark.parametrize("endpoint, loopback", [
    ("tcp/127.0.0.1:7447", True), ("tcp/[::1]:7447", True), ("tcp/localhost:7447", True),
    ("udp/127.0.0.5:1", True), ("tcp/0.0.0.0:7447", False), ("tcp/[::]:7447", False),
    ("tcp/192.168.1.4:7447", False), ("tcp/example.org:7447", False)])
def test_loopback_detection(endpoint, loopback):
    assert is_loopback_endpoint(endpoint) is loopback


def test_beyond_loopback_needs_allow_remote_tls_a_named_address_and_users():
    with pytest.raises(ValueError, match=r"zenoh.listen: \['tcp/0.0.0.0:7447'\] is not loopback.*allow_remote"):
        ZenohSettings.from_dict({"listen": ["tcp/0.0.0.0:7447"]})
    with pytest.raises(ValueError, match="zenoh.multicast"):
        ZenohSettings.from_dict({"multicast": True})
    with pytest.raises(ValueError, match=r"listens on every interface.*any_interface"):
        ZenohSettings.from_dict({"listen": ["tls/0.0.0.0:7447"], "allow_remote": True})
    with pytest.raises(ValueError, match=r"\['tcp/10.0.0.1:7447'\] would carry plaintext.*tls/HOST:PORT"):
        ZenohSettings.from_dict({"listen": ["tcp/10.0.0.1:7447"], "allow_remote": True})
    with pytest.raises(ValueError, match="plaintext"):  # a client too
        ZenohSettings.from_dict({"mode": "client", "connect": ["tcp/192.0.2.10:7447"]})
    assert ZenohSettings.from_dict({"listen": ["tls/10.0.0.1:7447"], "allow_remote": True}).allow_remote
    assert ZenohSettings.from_dict({"listen": ["tls/0.0.0.0:7447#iface=eth0"], "allow_remote": True})
    assert ZenohSettings.from_dict({"listen": ["tcp/10.0.0.1:7447"], "allow_remote": True, "insecure": True})
    # A peer or router with no listen entry listens on loopback, never on Zenoh's default [::]
    assert ZenohSettings.from_dict({"mode": "router"}).listen_endpoints() == ("tcp/127.0.0.1:7447",)
    with pytest.raises(ValueError, match="not loopback"):
        ZenohSettings().with_overrides(listen=["tcp/10.0.0.1:7447"])
    # TLS alone is not enough: a server listening beyond loopback must authenticate its users
    tls_peer = {"listen": ["tls/10.0.0.1:7447"], "allow_remote": True}
    with pytest.raises(ValueError, match="access.users_file: the server listens beyond loopback"):
        ServerSettings.from_dict({"zenoh": tls_peer})
    assert ServerSettings.from_dict({"zenoh": tls_peer, "access": {"users_file": "u.txt", "roles": {"a": "player"}}})
    with pytest.raises(ValueError, match="serves: the router listens beyond loopback"):
        RouterSettings.from_dict({"zenoh": {**tls_peer, "mode": "router"}})


def test_bad_settings_name_the_key():
    with pytest.raises(ValueError, match=r"zenoh: unknown key\(s\) \['lisen'\]"):
        ZenohSettings.from_dict({"lisen": []})
    with pytest.raises(ValueError, match="zenoh.mode"):
        ZenohSettings.from_dict({"mode": "hub"})
    with pytest.raises(ValueError, match="zenoh.connect: client mode"):
        ZenohSettings.from_dict({"mode": "client"})
    with pytest.raises(ValueError, match="zenoh.insecure: expected true or false"):
        ZenohSettings.from_dict({"insecure": "yes"})
    with pytest.raises(ValueError, match="zenoh.listen: expected a list"):
        ZenohSettings.from_dict({"listen": "tcp/127.0.0.1:1"})
    with pytest.raises(ValueError, match=r"server: unknown key\(s\) \['port'\]"):
        ServerSettings.from_dict({"port": 7447})
    with pytest.raises(ValueError, match="name"):
        ServerSettings.from_dict({"name": "a/b"})
    with pytest.raises(ValueError, match=r"matches\[0\]"):
        ServerSettings.from_dict({"matches": [3]})
    with pytest.raises(ValueError, match="zenoh: cannot set 'no/such/key'"):
        ZenohSettings(options={"no/such/key": 1}).zenoh_config()


@pytest.mark.parametrize("field, value, message", [
    ("mode", "turbo", "mode"), ("replacement", "random", "replacement"), ("deadline_ms", -1, "deadline_ms"),
    ("deadline_ms", float("nan"), "deadline_ms"), ("ready_timeout_s", "soon", "ready_timeout_s"),
    ("fill", "ball_chaser", "fill"), ("seed", 1.5, "seed"), ("overrides", [1], "overrides"),
    ("config", 3, "config"), ("open", "yes", "open"), ("seats", {"blue_0": "a/b"}, "seats.blue_0"),
    ("seats", ["blue_0"], "seats")])
def test_match_options_name_the_field(field, value, message):
    with pytest.raises(ValueError, match=message):
        MatchOptions.from_dict({field: value})


def test_match_options_unknown_key():
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['deadline'\]"):
        MatchOptions.from_dict({"deadline": 10})


def test_tls_and_auth_pass_through_to_zenoh():
    settings = ZenohSettings.from_dict({"auth": {"user": "alice", "password": "pw"},
                                        "tls": {"root_ca_certificate": "ca.pem"}})
    config = settings.zenoh_config()
    assert '"alice"' in config.get_json("transport/auth/usrpwd/user")
    assert "ca.pem" in config.get_json("transport/link/tls/root_ca_certificate")


def test_access_settings_name_the_key():
    with pytest.raises(ValueError, match=r"access.roles.alice: 'root' is not one of \['admin', 'player', 'spectator'\]"):
        AccessSettings.from_dict({"users_file": "u.txt", "roles": {"alice": "root"}})
    with pytest.raises(ValueError, match="'server' is the match server's own user"):
        AccessSettings.from_dict({"users_file": "u.txt", "roles": {"server": "admin"}})
    with pytest.raises(ValueError, match="'members' is the Zenoh user the server's members share"):
        AccessSettings.from_dict({"roles": {"members": "player"}})
    # roles alone: authenticated, the passwords in <key_dir>/users.txt
    assert AccessSettings.from_dict({"roles": {"alice": "player"}}).enabled
    with pytest.raises(ValueError, match="access.create"):
        AccessSettings.from_dict({"create": "anyone"})
    with pytest.raises(ValueError, match="access.roles user"):
        AccessSettings.from_dict({"users_file": "u.txt", "roles": {"a/b": "player"}})
    access = AccessSettings.from_dict({"users_file": "u.txt", "roles": {"alice": "player", "ops": "admin"}})
    assert access.role("alice") == "player" and access.role("mallory") is None
    assert AccessSettings().role("anyone") == "player"  # no authentication: everyone plays, nobody is admin


def test_limits_bound_what_the_lobby_accepts():
    limits = Limits()
    assert limits.check_config_name("matches/2v2.yaml") == "matches/2v2.yaml"
    for bad in ("/proc/self/environ", "../matches/1v1.yaml", "matches/../../etc/passwd.yaml", "policies/x.yaml",
                "matches/1v1", {"mode": "match"}, "matches\\1v1.yaml"):
        with pytest.raises(ValueError, match=r"config: expected a config name like 'matches/2v2.yaml'"):
            limits.check_config_name(bad)
    base = MatchOptions()
    limits.check_options(base)
    limits.check_options(MatchOptions.from_dict({"overrides": {"arena_shape": "game"}}))  # a match creator's choice
    for changes, message in [({"deadline_ms": 1e9}, "deadline_ms"), ({"deadline_ms": 0.0}, "deadline_ms"),
                             ({"ready_timeout_s": 1e12}, "ready_timeout_s"),
                             ({"fill": "checkpoint:/etc/passwd"}, "fill: 'checkpoint:/etc/passwd' is not allowed"),
                             ({"overrides": {"team_size": 50}}, r"overrides: \['team_size'\] may not be changed")]:
        with pytest.raises(ValueError, match=message):
            limits.check_options(MatchOptions.from_dict(changes))
    limits.check_game({"clock_s": 300.0, "overtime_limit_s": 300.0, "kickoff_countdown_s": 3.0})
    for config, message in [({"clock_s": 1e9}, "clock_s"), ({"overtime_limit_s": None}, "overtime_limit_s: must be set"),
                            ({"overtime_limit_s": 1e6}, "overtime_limit_s"), ({"kickoff_countdown_s": 1e4}, "kickoff"),
                            ({"timeout_s": 10.0, "rounds": 1000}, "rounds x timeout_s")]:
        with pytest.raises(ValueError, match=message):
            limits.check_game(config)
    with pytest.raises(ValueError, match="limits.max_matches: expected an integer >= 0"):
        Limits.from_dict({"max_matches": 2.5})
    with pytest.raises(ValueError, match="limits.configs: expected a list of names"):
        Limits.from_dict({"configs": "matches"})
    with pytest.raises(ValueError, match=r"limits: unknown key\(s\) \['max_match'\]"):
        Limits.from_dict({"max_match": 3})


def test_client_settings_connect_as_clients_and_name_their_user():
    with pytest.raises(ValueError, match="connects as a client"):
        ClientSettings.from_dict({"zenoh": {"mode": "peer"}})
    with pytest.raises(ValueError, match="differs from zenoh.auth.user"):
        ClientSettings.from_dict({"user": "bob", "zenoh": {"mode": "client", "connect": ["tcp/127.0.0.1:1"],
                                                           "auth": {"user": "alice", "password": "x"}}})
    with pytest.raises(ValueError, match="server_key: expected 'ed25519:"):
        ClientSettings.from_dict({"server_key": "abc"})
    assert ClientSettings().user_name == "guest" and str(ClientSettings(server="lab").keys_path) == "runs/server/lab"


def test_generated_acl_denies_by_default_and_gives_each_user_its_own_prefix():
    acl = acl_config("lab", {"alice": "player", "ops": "admin", "web": "spectator"}, router=True)
    assert acl["enabled"] and acl["default_permission"] == "deny"
    rules = {r["id"]: r for r in acl["rules"]}
    assert rules["own_alice"]["key_exprs"] == ["rocketdrl/lab/u/alice/**"]
    # one deny rule: members (users the server manages) never reach the prefixes of the users Zenoh knows
    assert [r["id"] for r in acl["rules"] if r["permission"] != "allow"] == ["members_not_users"]
    assert set(rules["members_not_users"]["key_exprs"]) == {f"rocketdrl/lab/u/{u}/**" for u in
                                                            ("alice", "ops", "web", "server", "members")}
    assert rules["members_own"]["key_exprs"] == ["rocketdrl/lab/u/*/**"]
    policies = {p["subjects"][0]: set(p["rules"]) for p in acl["policies"]}
    assert "own_ops" not in policies["user_alice"] and "invite_query" in policies["user_ops"]
    assert "invite_query" not in policies["user_alice"] and policies["user_server"] == {"match_server"}
    # nobody but the server may put state or declare the server's token
    assert rules["public_data"]["flows"] == ["egress"] and rules["alive_token"]["flows"] == ["egress"]
