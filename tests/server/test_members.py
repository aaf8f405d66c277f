"""Members added while the server runs (``rocketdrl-ma users add``): the running ``serve server/local.yaml``
process accepts them at once, by their keys, while Zenoh still authenticates every connection."""
from __future__ import annotations

import signal
import subprocess

import pytest
from server_helpers import SHORT, client_settings, cli

from rocketdrl_ma.server import PolicyBot, ServerError
from rocketdrl_ma.server.client import LobbyClient
from rocketdrl_ma.server.members import MEMBERS_FILE, add_member, read_members, remove_member
from rocketdrl_ma.server.settings import MEMBERS_USER, ZenohSettings


def users(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(cli("users", *args), capture_output=True, text=True, timeout=120)


def test_a_member_added_while_the_server_runs_creates_a_match_and_plays_its_seat(procs, tmp_path):
    served = procs.serve(tmp_path)
    local_session = served.client_settings.zenoh.open()
    try:
        local = LobbyClient(local_session, served.client_settings)
        assert local.list() == []
        added = users("add", "carol", "--role", "admin", "--key-dir", str(served.key_dir))
        assert added.returncode == 0, added.stderr
        key_file = served.key_dir / "members" / "carol.key"
        assert key_file.stat().st_mode & 0o077 == 0 and "carol" in read_members(served.key_dir / MEMBERS_FILE)

        carol = client_settings(served.endpoint, served.name, served.key_dir, user="carol")
        assert carol.zenoh.auth["user"] == MEMBERS_USER and carol.user_key_path == key_file
        carol_session = carol.zenoh.open()
        try:
            created = LobbyClient(carol_session, carol).create(
                "matches/1v1.yaml", "carols", overrides=SHORT, fill="scripted:ball_chaser", ready_timeout_s=60,
                seats={"blue_0": "carol"})
            assert created["creator"] == "carol"
        finally:
            carol_session.close()
        report = PolicyBot("scripted:ball_chaser").run("carols", "blue_0", client=carol)
        assert report.reason == "finished" and report.decisions > 0
        info = local.inspect("carols")
        assert info["status"] == "finished" and info["slot_status"]["blue_0"]["user"] == "carol"

        # the users Zenoh knew from the start keep working
        local.create("matches/1v1.yaml", "locals", fill="idle", ready_timeout_s=60)
        assert {m["id"] for m in local.list()} == {"carols", "locals"}
        # a wrong password or an unknown user never connects
        for auth in ({"user": MEMBERS_USER, "password": "wrong"}, {"user": "dave", "password": "x"}):
            with pytest.raises(ValueError, match="cannot open a client session"):
                ZenohSettings(mode="client", connect=(served.endpoint,), auth=auth).open()
        # a removed member's key is refused from its next request on, still without a restart
        removed = users("remove", "carol", "--key-dir", str(served.key_dir))
        assert removed.returncode == 0, removed.stderr
        carol_session = carol.zenoh.open()
        try:
            with pytest.raises(ServerError, match="has no role on this server"):
                LobbyClient(carol_session, carol).create("matches/1v1.yaml", "again", fill="idle")
        finally:
            carol_session.close()
    finally:
        local_session.close()
    served.proc.popen.send_signal(signal.SIGTERM)
    assert served.proc.popen.wait(30) == 0


def test_member_names_are_checked_and_never_taken_twice(tmp_path):
    add_member(tmp_path, "erin", "player")
    with pytest.raises(ValueError, match="already exists"):
        add_member(tmp_path, "erin", "admin")
    with pytest.raises(ValueError, match="already exists"):
        add_member(tmp_path, "local", "player", reserved=("local",))
    with pytest.raises(ValueError, match="already exists"):
        add_member(tmp_path, MEMBERS_USER, "player")
    with pytest.raises(ValueError, match="role: expected one of"):
        add_member(tmp_path, "frank", "root")
    with pytest.raises(ValueError, match="no member 'frank'"):
        remove_member(tmp_path, "frank")
    remove_member(tmp_path, "erin")
    assert read_members(tmp_path / MEMBERS_FILE) == {}
