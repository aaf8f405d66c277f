"""Server, Zenoh and match settings: loopback unless the config says otherwise, errors that name keys."""
from __future__ import annotations

import pytest

from rocketdrl_ma.server.settings import (MatchOptions, ServerSettings, ZenohSettings, is_loopback_endpoint,
                                          load_zenoh_settings)
from server_helpers import REPO


def test_shipped_configs_load():
    local = ServerSettings.load(REPO / "server/local.yaml")
    assert local.zenoh.mode == "peer" and local.zenoh.listen_endpoints() == ("tcp/127.0.0.1:7447",)
    assert not local.zenoh.multicast and local.match_defaults.deadline_ms == 50
    remote = ServerSettings.load(REPO / "server/remote-server.yaml")
    assert remote.zenoh.mode == "client" and remote.zenoh.listen_endpoints() == ()
    router = load_zenoh_settings(REPO / "server/router.yaml")
    assert router.mode == "router" and router.allow_remote
    client = load_zenoh_settings(REPO / "server/client.yaml")
    assert client.mode == "client" and client.connect


@pytest.mark.parametrize("endpoint, loopback", [
    ("tcp/127.0.0.1:7447", True), ("tcp/[::1]:7447", True), ("tcp/localhost:7447", True),
    ("udp/127.0.0.5:1", True), ("tcp/0.0.0.0:7447", False), ("tcp/[::]:7447", False),
    ("tcp/192.168.1.4:7447", False), ("tcp/example.org:7447", False)])
def test_loopback_detection(endpoint, loopback):
    assert is_loopback_endpoint(endpoint) is loopback


def test_non_loopback_needs_allow_remote():
    with pytest.raises(ValueError, match=r"zenoh.listen: \['tcp/0.0.0.0:7447'\] is not loopback.*allow_remote"):
        ZenohSettings.from_dict({"listen": ["tcp/0.0.0.0:7447"]})
    with pytest.raises(ValueError, match="zenoh.multicast"):
        ZenohSettings.from_dict({"multicast": True})
    assert ZenohSettings.from_dict({"listen": ["tcp/0.0.0.0:7447"], "allow_remote": True}).allow_remote
    # A peer or router with no listen entry listens on loopback, never on Zenoh's default [::]
    assert ZenohSettings.from_dict({"mode": "router"}).listen_endpoints() == ("tcp/127.0.0.1:7447",)
    with pytest.raises(ValueError, match="not loopback"):
        ZenohSettings().with_overrides(listen=["tcp/10.0.0.1:7447"])


def test_bad_settings_name_the_key():
    with pytest.raises(ValueError, match=r"zenoh: unknown key\(s\) \['lisen'\]"):
        ZenohSettings.from_dict({"lisen": []})
    with pytest.raises(ValueError, match="zenoh.mode"):
        ZenohSettings.from_dict({"mode": "hub"})
    with pytest.raises(ValueError, match="zenoh.connect: client mode"):
        ZenohSettings.from_dict({"mode": "client"})
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
    ("config", 3, "config")])
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
