"""``ArenaBatch``: many arenas in one PyBullet world, each with the single-arena API (``batch.arenas[i]``)."""
from __future__ import annotations

from . import constants as C
from .arena import Arena
from .arena_shape import DEFAULT_ARENA_SHAPE
from .world import PhysicsWorld


class ArenaBatch(PhysicsWorld):
    """``n_arenas`` independent soccar arenas in one PyBullet client, stepped by one ``stepSimulation``.

    ``batch.arenas[i]`` are ``Arena`` views with the single-arena API; ``batch.step(ticks)`` advances all, and the
    batch-wide calls (``controls``, ``arrays()``, ``drain_events()``, ``set_mutator_config``) serve code that
    handles every arena at once.
    """

    def __init__(self, n_arenas: int = 1, tick_rate: int = C.TICK_RATE_HZ, seed: int | None = None,
                 arena_shape: str = DEFAULT_ARENA_SHAPE):
        super().__init__(n_arenas, tick_rate=tick_rate, seed=seed, arena_shape=arena_shape)
        self._arena_views = [Arena._view(self, k) for k in range(n_arenas)]
