"""A dropped arena gives its PyBullet world (about 10 MB of C++ memory) back at once, not when Python's cyclic
collector happens to run: that collector does not see the memory, and 240 3v3 matches made and dropped one after
another in one process once held 8 GB."""
from __future__ import annotations

import copy
import gc
import pickle
import tracemalloc
import weakref

import numpy as np
import pybullet as pb

from rocketdrl_ma.physics import Arena, ArenaBatch
from rocketdrl_ma.engine import GameEngine
from rocketdrl_ma.rules import Match


def _freed_when_dropped(make) -> bool:
    """The arena ``make`` builds, once dropped, has disconnected its world, checked before the cyclic collector can
    run (once enabled, the collector frees a young cycle within a few hundred allocations). One arena is made and
    dropped first: the kernels' first compilation leaves frames in cycles that would hold the measured one."""
    make()
    gc.collect()
    gc.disable()
    try:
        arena = make()
        world, client = weakref.ref(arena.batch), arena.batch.client
        del arena
        return world() is None and not pb.isConnected(client)
    finally:
        gc.enable()


def test_a_dropped_arena_disconnects_its_world_at_once():
    def make():
        arena = Arena(seed=1)
        for team in (0, 0, 1, 1):
            arena.add_car(team=team)
        arena.step(8)
        return arena

    assert _freed_when_dropped(make)


def test_a_dropped_match_disconnects_its_world_at_once():
    def make():
        match = Match(team_size=3, kickoff_countdown_s=0.0)
        engine = GameEngine([match])
        engine.reset_game(0, 0)
        engine.step([{}], 8)
        return match.arena

    assert _freed_when_dropped(make)


def test_arenas_made_and_dropped_leave_no_python_memory_behind():
    """PyBullet keeps a reference to every vertex row of a mesh it is given: with fresh lists for every world, each
    arena left about 1.45 MB of Python floats behind."""
    Arena(seed=0)  # the mesh lists and the kernels are made once per process
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for seed in range(20):
            Arena(seed=seed).add_car(team=seed % 2)
        gc.collect()
        grown_bytes = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert grown_bytes < 200_000, grown_bytes


def test_a_lone_arena_is_its_worlds_one_view_in_copies_too():
    arena = Arena(seed=2)
    arena.add_car(team=0)
    assert arena.batch.arenas == [arena] and arena.batch.arenas[0] is arena
    for twin in (copy.deepcopy(arena), pickle.loads(pickle.dumps(arena))):
        assert twin.batch is not arena.batch and twin.batch.arenas[0] is twin
        twin.step(4)
    batch = ArenaBatch(3)
    assert [a.index for a in batch.arenas] == [0, 1, 2] and all(a.batch is batch for a in batch.arenas)
