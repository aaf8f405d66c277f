"""PyBullet soccar physics with Rocket League's car model, in Rocket League units (uu, uu/s, rad; z up).

Imports nothing else of the package: rules, env, server and policies build on this, never the reverse.
"""
import hashlib
from pathlib import Path


def _drop_stale_kernel_caches() -> None:
    """Numba keys a cached kernel on its own source file, but the kernels compile in functions and constants of
    the other physics modules: after any of them changes, a cache could run the old code. A stamp of all of
    them decides when the caches go."""
    here = Path(__file__).parent
    stamp = hashlib.sha256(b"".join(p.read_bytes() for p in sorted(here.glob("*.py")))).hexdigest()
    cache = here / "__pycache__"
    marker = cache / "kernels.stamp"
    try:
        if marker.read_text() == stamp:
            return
    except OSError:
        pass
    try:
        for f in cache.glob("*.nb[ci]"):
            f.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        marker.write_text(stamp)
    except OSError:  # a read-only install: numba cannot cache there either
        pass


_drop_stale_kernel_caches()

from . import compile_notice  # noqa: F401  (before any kernel runs: the first compile of a process says so)
from .arena import Arena, Ball, BoostPad, Car
from .batch import ArenaBatch
from .arena_shape import ARENA_SHAPES, DEFAULT_ARENA_SHAPE
from .car_config import PRESETS, CarConfig, get_preset
from .events import (BallTouch, BoostPadTaken, BumperHit, CarBumped, CarDemolished, PhysicsEvent, PhysicsEventKind,
                     renamed)
from .mutators import DemoMode, MutatorConfig
from .state import BallHitInfo, BallState, BoostPadState, CarControls, CarExtraState, CarState, yaw_rot_mat
from .world import BatchArrays, PhysicsWorld

__all__ = ["ARENA_SHAPES", "Arena", "ArenaBatch", "Ball", "BallHitInfo", "BallState", "BallTouch", "BatchArrays",
           "BoostPad", "BoostPadState", "BoostPadTaken", "BumperHit", "Car", "CarBumped", "CarConfig", "CarControls",
           "CarDemolished", "CarExtraState", "CarState", "DEFAULT_ARENA_SHAPE", "DemoMode", "MutatorConfig", "PRESETS",
           "PhysicsEvent", "PhysicsEventKind", "PhysicsWorld", "get_preset", "yaw_rot_mat"]


def __getattr__(name: str) -> type:
    """The physics events' old names (``events.RENAMED``) still import, with a DeprecationWarning."""
    return renamed(__name__, name)
