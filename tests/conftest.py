"""Puts this folder on ``sys.path`` (pytest's rootdir conftest), so every test folder can import the shared
helpers kept here (``ray_cluster.py``, ``processes.py``), and marks the tests that need the machine to themselves."""
from __future__ import annotations

from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
#: Tests whose outcome depends on wall-clock time: match servers with lockstep deadlines and real-time ticks, bots
#: that must answer in time, a browser that must draw the live match at its rate. `make test` runs them in one
#: process at normal priority, beside the rest at the lowest priority on two pytest-xdist workers: beside a test of
#: the same priority they missed deadlines. (The wheel's tests serve a match too, but only wait for it to finish.)
WALL_CLOCK_TESTS = ("server", "web", "league/test_remote.py", "engine/test_every_face_plays_the_same_game.py")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "wall_clock: depends on wall-clock time (WALL_CLOCK_TESTS); `make test` runs "
                                       "these at normal priority, the rest niced")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        where = item.path.relative_to(TESTS).as_posix()
        if any(where == path or where.startswith(path + "/") for path in WALL_CLOCK_TESTS):
            item.add_marker(pytest.mark.wall_clock)
