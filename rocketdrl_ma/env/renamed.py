"""Names that were renamed: configs, checkpoints and code that still use an old one keep working, with a warning
that names the new one.

The old sensor and action names came from the predecessor project this one started from ("the seed"); they said where
the sensors and actions came from, the new ones say what they are. A game of a ``VectorEnv`` was an arena or a lane;
it is a game everywhere now.
"""
from __future__ import annotations

import logging
import warnings

log = logging.getLogger(__name__)

#: observation builder names (each part of an ``a+b`` spec)
OBSERVATION_NAMES = {"seed_sensors": "general_sensors", "seed_barrier": "barrier_sensors",
                     "seed_aerial": "aerial_sensors"}
#: action parser names
ACTION_NAMES = {"seed": "drive"}
#: Python classes, by the module that exports them
CLASS_NAMES = {"SeedSensors": "GeneralSensors", "SeedBarrierSensors": "BarrierSensors",
               "SeedAerialSensors": "AerialSensors", "SeedActions": "DriveActions"}

_logged: set[tuple[str, str]] = set()


def current_name(field: str, name: str, renamed: dict[str, str]) -> str:
    """``name`` of config field ``field`` (``observation``, ``action``) as it is called now; an old name is logged
    once per process, naming the new one."""
    new = renamed.get(name)
    if new is None:
        return name
    if (field, name) not in _logged:
        _logged.add((field, name))
        log.warning("%s: %r is now called %r; the old name still works, but update the config", field, name, new)
    return new


def renamed_class(module: str, name: str, namespace: dict) -> type:
    """A class asked for by its old name (``CLASS_NAMES``) from ``module``, with a DeprecationWarning naming the
    new one; any other missing name is the usual AttributeError."""
    new = CLASS_NAMES.get(name)
    if new is None or new not in namespace:
        raise AttributeError(f"module {module!r} has no attribute {name!r}")
    warnings.warn(f"{module}.{name} is now {new}", DeprecationWarning, stacklevel=3)
    return namespace[new]


def renamed_keyword(owner: str, given: dict, old: str, new: str, value):
    """``value`` of keyword ``new``, or of ``old`` if the caller passed the old name (popped from ``given``, with a
    DeprecationWarning naming the new one)."""
    if old not in given:
        return value
    warnings.warn(f"{owner}({old}=...) is now {owner}({new}=...)", DeprecationWarning, stacklevel=3)
    return given.pop(old)


def renamed_attribute(owner: str, old: str, new: str) -> property:
    """A read-only alias ``old`` of attribute (or method) ``new`` of class ``owner``: each use warns."""
    def alias(self):
        warnings.warn(f"{owner}.{old} is now {owner}.{new}", DeprecationWarning, stacklevel=2)
        return getattr(self, new)
    alias.__doc__ = f"Deprecated: {new}."
    return property(alias)
