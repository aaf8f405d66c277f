"""Fixtures of the match server tests (helpers live in ``server_helpers.py``)."""
from __future__ import annotations

import os

import pytest
from server_helpers import Procs, Running


@pytest.fixture(autouse=True, scope="session")
def known_servers(tmp_path_factory):
    """Clients that trust a server on first use remember its key: never in the real home folder during
    tests (subprocesses inherit the variable)."""
    path = tmp_path_factory.mktemp("known") / "known_servers"
    old = os.environ.get("ROCKETDRL_MA_KNOWN_SERVERS")
    os.environ["ROCKETDRL_MA_KNOWN_SERVERS"] = str(path)
    yield path
    if old is None:
        del os.environ["ROCKETDRL_MA_KNOWN_SERVERS"]
    else:
        os.environ["ROCKETDRL_MA_KNOWN_SERVERS"] = old


@pytest.fixture
def running(tmp_path):
    r = Running(tmp_path)
    yield r
    r.close()


@pytest.fixture
def authed(tmp_path):
    """A loopback server with Zenoh users and access control (local: admin; alice, bob: players), as
    server/local.yaml runs: the passwords in its folder, where its clients find them."""
    r = Running(tmp_path, access={"roles": {"local": "admin", "alice": "player", "bob": "player"}})
    yield r
    r.close()


@pytest.fixture
def procs():
    p = Procs()
    yield p
    p.kill_all()
