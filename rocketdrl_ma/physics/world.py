"""Many soccar arenas in one PyBullet world, stepped together: the machinery under ``Arena`` and ``ArenaBatch``.

Each arena sits at its own origin on a grid far enough apart that nothing crosses over; the floor
and ceiling planes are shared. PyBullet holds the cars (their hitboxes against the arena, the
minigames' boxes and each other); the balls live in arrays and move in ``ball_kernel``, which
solves their contacts as RocketSim does. Every per-tick quantity is held as arrays over all cars
and balls of all arenas, so the car and ball models run as compiled kernels and a lone ``Arena``
is simply a batch of one. Rocket League units (uu) everywhere outside the PyBullet calls, which use metres.

``PhysicsWorld`` puts together its jobs, one module each: the PyBullet client and its bodies (``bullet``), the
arrays (``state_arrays``), the tick (``tick``) with the car-car rules (``car_contacts``); here is what is left:
making a world, its mutators, its events and its lifetime.
"""
from __future__ import annotations

import weakref

import numpy as np

from . import constants as C
from .arena_shape import DEFAULT_ARENA_SHAPE, GAME, arena_shape_index
from .bullet import M_PER_UU, BulletWorld, box_vector
from .car_kernel import CS_IS_DEMOED
from .events import PhysicsEvent
from .mutators import MutatorConfig
from .state_arrays import BatchArrays
from .tick import WorldTick

ARENA_SPACING_UU = 20000.0  # arenas are ~8200 x 12000 uu; the gap keeps every body in its own arena
ARENA_GRID_COLUMNS = 8

__all__ = ["ARENA_GRID_COLUMNS", "ARENA_SPACING_UU", "BatchArrays", "M_PER_UU", "PhysicsWorld", "box_vector"]


class PhysicsWorld(WorldTick):
    """``n_arenas`` independent soccar arenas in one PyBullet client, stepped by one ``stepSimulation``.

    ``arenas`` holds the ``Arena`` views of whoever made the world (``ArenaBatch`` makes one per arena; a lone
    ``Arena`` is the view of its own world of one); ``step(ticks)`` advances all.
    """

    def __init__(self, n_arenas: int = 1, tick_rate: int = C.TICK_RATE_HZ, seed: int | None = None,
                 arena_shape: str = DEFAULT_ARENA_SHAPE):
        if not isinstance(n_arenas, int) or n_arenas < 1:
            raise ValueError(f"n_arenas: must be an int >= 1, got {n_arenas!r}")
        if tick_rate != C.TICK_RATE_HZ:
            raise ValueError(f"tick_rate: only {C.TICK_RATE_HZ} Hz is supported (the game's rate), got {tick_rate!r}")
        self._game_shape = arena_shape_index(arena_shape) == GAME  # which compiled kernels step() calls
        self.arena_shape = arena_shape
        self.n_arenas = n_arenas
        self.tick_rate = tick_rate
        self.dt = 1.0 / tick_rate
        self.tick_count = 0
        self._mutators = [MutatorConfig()] * n_arenas
        self.mutator_rows = np.tile(self._mutators[0].as_row(), (n_arenas, 1))
        self.rng = np.random.default_rng(seed)
        # Each arena's own random stream (respawn spots, unseeded kickoffs); all share ``rng`` unless given their
        # own, which makes an arena of a batch draw exactly what a lone Arena with that seed draws.
        self.arena_rngs: list[np.random.Generator] = [self.rng] * n_arenas
        self.origins = np.array([[(k % ARENA_GRID_COLUMNS) * ARENA_SPACING_UU,
                                  (k // ARENA_GRID_COLUMNS) * ARENA_SPACING_UU, 0.0] for k in range(n_arenas)])
        self.bullet = BulletWorld(self.origins, arena_shape, self.dt, self._mutators[0].gravity_z_uu_s2)
        self._init_arrays(n_arenas)
        self._events: list[list[PhysicsEvent]] = [[] for _ in range(n_arenas)]  # per arena, since the last drain
        self._overlap_push: dict[int, np.ndarray] = {}  # car row -> this tick's overlap correction (uu)
        self._arena_views: list = []  # an ArenaBatch's views of its arenas
        self._lone_arena: weakref.ref | None = None  # the Arena whose own world of one this is
        for k in range(n_arenas):
            self.set_ball(k, np.array([0.0, 0.0, C.BALL_REST_Z]), np.zeros(3), np.zeros(3))

    @property
    def client(self) -> int | None:
        """The PyBullet client id of this world (None once closed)."""
        return self.bullet.client

    @property
    def _static_bodies(self) -> list[int]:
        """The floor, the ceiling and each arena's mesh, as PyBullet bodies (in that order)."""
        return self.bullet.static_bodies

    @property
    def arenas(self) -> list:
        """The ``Arena`` views of this world's arenas: an ``ArenaBatch``'s, or a lone ``Arena`` itself."""
        if self._lone_arena is not None:
            arena = self._lone_arena()
            return [] if arena is None else [arena]
        return self._arena_views

    def attach_lone_arena(self, arena: object) -> None:
        """``arena`` (an ``Arena``) is the one view of this world of one, held weakly, so the world goes with the last
        reference to its arena. Held strongly, the arena and its world formed a reference cycle, and a dropped
        arena's PyBullet world (about 10 MB, memory Python's cyclic collector does not see) waited for that
        collector: 240 3v3 matches made and dropped one after another in one process peaked at 8 GB."""
        self._lone_arena = weakref.ref(arena)

    # ------------------------------------------------------------------ copies (copy.deepcopy, pickle)
    def __getstate__(self) -> dict:
        """Everything; the PyBullet world copies as ``BulletWorld`` says (a snapshot), the lone arena strongly."""
        state = self.__dict__.copy()
        state["_lone_arena"] = None if self._lone_arena is None else self._lone_arena()  # a weakref does not copy
        return state

    def __setstate__(self, state: dict) -> None:
        lone = state.pop("_lone_arena", None)
        self.__dict__.update(state)
        self._lone_arena = None if lone is None else weakref.ref(lone)

    def renew_bullet_world(self) -> None:
        """Move onto a new PyBullet world: the same bodies with the same ids, settings and demolitions, the static
        boxes where they are, every car where its arrays say, and none of Bullet's memory of earlier ticks.

        Bullet keeps contact manifolds, the order of their points and a broadphase that prunes stale pairs a few per
        tick from a cursor; a used world carries them into every later tick, so a game played on it drifts apart
        from the same game on a new world after a few hundred decisions. Made for the start of an episode: a car
        put somewhere since the last tick (``set_car``; a reset puts every car) is put there again exactly, and the
        world then plays on exactly as a newly made one with the same cars put the same way. A car that has moved
        on its own since it was put carries over to float rounding (its pose read back from metres)."""
        self._read_state()
        self.bullet.renew()
        for slot in self._slots:
            k = slot.index
            if self.cs[k, CS_IS_DEMOED]:
                self.bullet.take_out_of_play(slot.body)
            self.set_car(slot.car_id, self.car_pos[k], self.car_rot[k], self.car_vel[k], self.car_ang_vel[k])

    # ------------------------------------------------------------------ static boxes (minigame barriers)
    def add_static_box(self, arena: int, center_uu: np.ndarray, half_extents_uu: np.ndarray) -> int:
        """An immovable axis-aligned box in ``arena`` that cars and the ball collide with; returns its id
        (``BulletWorld.add_static_box``)."""
        return self.bullet.add_static_box(arena, center_uu, half_extents_uu)

    def static_box_half_extents(self, box_id: int) -> np.ndarray:
        return self.bullet.static_box_half_extents(box_id)

    def move_static_box(self, box_id: int, center_uu: np.ndarray) -> None:
        """Put a static box's centre at ``center_uu`` (between rounds; it does not sweep through bodies)."""
        self.bullet.move_static_box(box_id, center_uu)

    def remove_static_box(self, box_id: int) -> None:
        self.bullet.remove_static_box(box_id)

    # ------------------------------------------------------------------ mutators and events
    def set_mutator_config(self, config: MutatorConfig, arena: int | None = None) -> None:
        """Play arena ``arena`` (every arena if None) with ``config``. Gravity is PyBullet's one per world, so
        it changes only for every arena at once."""
        if not isinstance(config, MutatorConfig):
            raise ValueError(f"config: expected MutatorConfig, got {type(config).__name__}")
        targets = range(self.n_arenas) if arena is None else [self._arena_index(arena)]
        if len(targets) < self.n_arenas and config.gravity_z_uu_s2 != self._mutators[0].gravity_z_uu_s2:
            raise ValueError(f"gravity_z_uu_s2: the arenas of a batch share one gravity "
                             f"({self._mutators[0].gravity_z_uu_s2:g}); change it with "
                             f"ArenaBatch.set_mutator_config(config) for all arenas, got {config.gravity_z_uu_s2:g}")
        self._read_state()
        if config.gravity_z_uu_s2 != self._mutators[0].gravity_z_uu_s2:
            self.bullet.set_gravity(config.gravity_z_uu_s2)
        for k in targets:
            self._mutators[k] = config
            self.mutator_rows[k] = config.as_row()

    def get_mutator_config(self, arena: int = 0) -> MutatorConfig:
        return self._mutators[self._arena_index(arena)]

    def _arena_index(self, arena: int) -> int:
        if not isinstance(arena, (int, np.integer)) or not 0 <= arena < self.n_arenas:
            raise ValueError(f"arena: must be an index in 0..{self.n_arenas - 1}, got {arena!r}")
        return int(arena)

    def drain_events(self, arena: int | None = None) -> list[PhysicsEvent]:
        """The events of arena ``arena`` (every arena if None, arena by arena) since the last drain, in the order
        the ticks produced them; they are removed."""
        if arena is not None:
            k = self._arena_index(arena)
            events, self._events[k] = self._events[k], []
            return events
        events = [e for per_arena in self._events for e in per_arena]
        self._events = [[] for _ in range(self.n_arenas)]
        return events

    def clear_events(self, arena: int | None = None) -> None:
        """Forget the undrained events of ``arena`` (every arena if None)."""
        self.drain_events(arena)

    # ------------------------------------------------------------------ lifetime
    def close(self) -> None:
        self.bullet.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: pybullet may already be gone
            pass
