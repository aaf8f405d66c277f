"""A dropped env gives its PyBullet world back at once. The spaces used to be cached with ``functools.lru_cache``
on the methods (as PettingZoo's docs show), a cache keyed on the env itself: every env ever asked for a space
stayed alive, with its world, until the process ended."""
from __future__ import annotations

import gc
import weakref

import pybullet as pb

import rocketdrl_ma


def _stepped_env():
    env = rocketdrl_ma.parallel_env("matches/2v2.yaml")
    env.reset(seed=0)
    env.step({a: env.action_space(a).sample() for a in env.agents})
    return env


def test_a_dropped_env_that_was_stepped_disconnects_its_world_at_once():
    _stepped_env()  # the kernels' first compilation leaves frames in cycles that would hold the measured env
    gc.collect()
    gc.disable()
    try:
        env = _stepped_env()
        assert env.observation_space("blue_0") is env.observation_space("orange_1")
        world, client = weakref.ref(env.rules.arena.batch), env.rules.arena.batch.client
        env_ref = weakref.ref(env)
        del env
        assert env_ref() is None and world() is None and not pb.isConnected(client)
    finally:
        gc.enable()
