"""Fixtures of the match server tests (helpers live in ``server_helpers.py``)."""
from __future__ import annotations

import pytest
from server_helpers import Procs, Running

@pytest.fixture
def running(tmp_path):
    r = Running(tmp_path)
    yield r
    r.close()


@pytest.fixture
def procs():
    p = Procs()
    yield p
    p.kill_all()
