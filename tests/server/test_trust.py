"""Which server key a client trusts: a pin, the server's own key dir on this machine, the key remembered
in the known-servers file, or the one key announced on first use; and what happens when it no longer
matches. The ``Spectator`` API built on it: verified, typed, in order."""
from __future__ import annotations

import pytest
from server_helpers import SHORT, Running

from rocketdrl_ma.server import PolicyBot, ServerGone, Spectator
from rocketdrl_ma.server.client import LobbyClient, trusted_server_key
from rocketdrl_ma.server.crypto import ServerIdentity
from rocketdrl_ma.server.spectator import EventsUpdate, MatchEnd, StateUpdate


def test_key_sources_in_order_and_trust_on_first_use_is_remembered(tmp_path, known_servers):
    first = Running(tmp_path / "a")
    real = first.lobby.server_key
    try:
        elsewhere = dict(key_dir=str(tmp_path / "nowhere"))
        assert trusted_server_key(first.session, first.client_settings)[0] == real  # its key dir
        assert trusted_server_key(first.session, first.client(server_key=real.text, **elsewhere)) == (real, "pinned")
        with pytest.raises(ValueError, match="no key pinned for server 'test'"):
            trusted_server_key(first.session, first.client(trust_on_first_use=False, **elsewhere))
        key, source = trusted_server_key(first.session, first.client(**elsewhere))  # first use: announced
        assert key == real and source.startswith("trusted on first use")
        assert f"test {first.endpoint} {real.text}" in known_servers.read_text()
        key, source = trusted_server_key(first.session, first.client(**elsewhere))
        assert key == real and source.startswith("remembered in")
        # a pinned key that is not the server's: nothing it says is accepted
        wrong = LobbyClient(first.session, first.client(server_key=ServerIdentity.generate().public_text, **elsewhere))
        with pytest.raises(ServerGone, match="no reply signed by server 'test'.*pinned.*1 unverified"):
            wrong.list()
    finally:
        first.close()
    # another server (another key) later answers as 'test' on the same endpoint: the remembered key refuses it
    second = Running(tmp_path / "b", endpoint=first.endpoint)
    try:
        assert second.lobby.server_key != real
        lobby = LobbyClient(second.session, second.client(key_dir=str(tmp_path / "nowhere")))
        with pytest.raises(ServerGone, match="no reply signed by server 'test'.*remove that line"):
            lobby.list()
    finally:
        second.close()


def test_spectator_yields_verified_typed_updates_in_order(running):
    running.lobby.create("matches/1v1.yaml", "spec", overrides=SHORT, ready_timeout_s=2, seed=3)
    with Spectator("spec", client=running.client_settings) as spectator:
        assert spectator.info["status"] == "waiting" and spectator.poll(0.1) is None
        report = PolicyBot("scripted:ball_chaser").run("spec", "blue_0", client=running.client_settings)
        updates = list(spectator.updates(timeout_s=60))
    states = [u for u in updates if isinstance(u, StateUpdate)]
    events = [u for u in updates if isinstance(u, EventsUpdate)]
    end = updates[-1]
    assert isinstance(end, MatchEnd) and end.status == "finished" and end.summary == report.summary
    assert end.result_key == running.lobby.inspect("spec")["result_key"]
    assert [s.seq for s in states] == sorted(s.seq for s in states) and len({s.seq for s in states}) == len(states)
    assert [s.decision for s in states] == list(range(states[0].decision, states[-1].decision + 1))
    assert states[-1].done and not states[0].done and states[0].state.tick < states[-1].state.tick
    assert any(e.kind == "touch" for u in events for e in u.events)
    assert spectator.dropped == {} and spectator.poll(0.1) is None  # after the end: nothing more
