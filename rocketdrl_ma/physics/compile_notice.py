"""The line a process prints when numba compiles the package's kernels instead of loading them from its cache.

A kernel compiles for each new set of argument types, once per machine: numba keeps the result in its on-disk
cache. From a cold cache (a fresh install, or kernels changed) that takes a minute or two, in whatever command
first steps the physics; this line, printed to stderr at the first compile of the process, says so instead of
sitting silent. ``rocketdrl-ma warmup`` compiles everything ahead (``rocketdrl_ma.env.warmup``).
"""
from __future__ import annotations

import sys

from numba.core import event

#: about what ``rocketdrl-ma warmup`` takes from a cold cache on a 2-core machine
COLD_COMPILE_ESTIMATE_S = 45
PACKAGE_PREFIX = "rocketdrl_ma."


def compiling_line() -> str:
    return f"compiling physics kernels, once: ~{COLD_COMPILE_ESTIMATE_S} s"


class _FirstCompileNotice(event.Listener):
    """Records every compile of a package kernel; prints ``compiling_line`` at the first one."""

    def __init__(self) -> None:
        self.compiled: list[str] = []
        self.announced = False
        self.hint = " (`rocketdrl-ma warmup` compiles them all ahead of time)"

    def on_start(self, ev: event.Event) -> None:
        func = ev.data["dispatcher"].py_func
        if not func.__module__.startswith(PACKAGE_PREFIX):
            return
        self.compiled.append(f"{func.__module__}.{func.__qualname__}{tuple(ev.data['args'])}")
        if not self.announced:
            self.announced = True
            print(compiling_line() + self.hint, file=sys.stderr, flush=True)

    def on_end(self, ev: event.Event) -> None:
        pass


_NOTICE = _FirstCompileNotice()
event.register("numba:compile", _NOTICE)


def kernels_compiled() -> list[str]:
    """Every package kernel signature this process compiled (rather than loaded from the cache), in order."""
    return list(_NOTICE.compiled)


def announce_without_hint() -> None:
    """For ``warmup`` itself: the line, when it comes, without the advice to run warmup."""
    _NOTICE.hint = ""
