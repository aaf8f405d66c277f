"""``rocketdrl-ma warmup``: fill numba's on-disk cache with every kernel signature the product uses.

A kernel compiles once for each set of argument types it meets, so warming up steps briefly what the product
steps: a lone ``Arena`` with a staged bump (the bump's curve lookup runs from Python only when two cars meet), and
every shipped match and minigame config, 1v1 to 4v4, barriers and ray sensors, as a ``RocketDRLParallelEnv`` and as
a ``VectorEnv`` of two games (an ``ArenaBatch``), in every arena shape. Leagues, the match server, training and the page play these same
envs, so afterwards no process compiles a kernel.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from rocketdrl_ma.config import shipped_files
from rocketdrl_ma.physics import Arena, CarBumped, CarControls, CarState, yaw_rot_mat
from rocketdrl_ma.physics.arena_shape import ARENA_SHAPES
from rocketdrl_ma.physics.compile_notice import kernels_compiled

from .parallel_env import RocketDRLParallelEnv
from .vector_env import VectorEnv

GAME_FOLDERS = ("matches", "minigames")
DECISIONS = 4
VECTOR_GAMES = 2
BUMP_MAX_TICKS = 60


def game_configs() -> list[str]:
    """The shipped match and minigame configs (``matches/1v1.yaml`` ...)."""
    return [name for name in shipped_files((".yaml",)) if name.split("/")[0] in GAME_FOLDERS]


def _bump(arena_shape: str) -> None:
    """Two grounded cars, one driving into the other below supersonic speed, until CarBumped."""
    arena = Arena(seed=0, arena_shape=arena_shape)
    try:
        attacker, victim = arena.add_car(team=0), arena.add_car(team=1)
        attacker.set_state(CarState(pos=np.array([0.0, -1500.0, 17.0]), rot_mat=yaw_rot_mat(np.pi / 2),
                                    vel=np.array([0.0, 1400.0, 0.0]), on_ground=True, wheels_in_contact=(True,) * 4))
        victim.set_state(CarState(pos=np.array([0.0, -1250.0, 17.0]), rot_mat=yaw_rot_mat(0.0), on_ground=True,
                                  wheels_in_contact=(True,) * 4))
        attacker.set_controls(CarControls(throttle=1.0))
        for _ in range(BUMP_MAX_TICKS):
            arena.step(1)
            if any(isinstance(e, CarBumped) for e in arena.drain_events()):
                return
        raise RuntimeError("warmup: the staged bump never happened; the bump kernel is not compiled")
    finally:
        arena.close()


def _parallel_env(config: str, arena_shape: str) -> None:
    env = RocketDRLParallelEnv(config, arena_shape=arena_shape)
    try:
        env.reset(seed=0)
        for agent in env.possible_agents:
            env.action_space(agent).seed(0)
        for _ in range(DECISIONS):
            if not env.agents:
                break
            env.step({agent: env.action_space(agent).sample() for agent in env.agents})
    finally:
        env.close()


def _vector_env(config: str, arena_shape: str) -> None:
    env = VectorEnv(config, n_games=VECTOR_GAMES, arena_shape=arena_shape)
    try:
        env.reset(seed=0)
        env.action_space.seed(0)
        for _ in range(DECISIONS):
            env.step(np.stack([np.stack([env.action_space.sample() for _ in range(env.n_agents)])
                               for _ in range(VECTOR_GAMES)]))
    finally:
        env.close()


def warm_up(on_step: Callable[[str], None] | None = None) -> list[str]:
    """Step everything above once; returns the kernel signatures this call compiled (none if the cache was warm).
    ``on_step(name)`` is told each workload before it runs."""
    before = len(kernels_compiled())
    workloads: list[tuple[str, Callable[[], None]]] = []
    for shape in ARENA_SHAPES:  # each arena shape has kernels of its own (``arena_shape.py``)
        workloads += [(f"arena bump ({shape})", lambda s=shape: _bump(s))]
        for config in game_configs():
            workloads += [(f"{config} ParallelEnv ({shape})", lambda c=config, s=shape: _parallel_env(c, s)),
                          (f"{config} VectorEnv ({shape})", lambda c=config, s=shape: _vector_env(c, s))]
    for name, run in workloads:
        if on_step is not None:
            on_step(name)
        run()
    return kernels_compiled()[before:]
