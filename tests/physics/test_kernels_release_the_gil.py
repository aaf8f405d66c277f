"""Every numba kernel of the package runs without the GIL (``nogil=True``), so a match server's other threads (other
matches, the lobby) keep running while one builds a costly observation or steps its physics."""
from __future__ import annotations

import importlib
import pkgutil

from numba.core.registry import CPUDispatcher

import rocketdrl_ma


def _package_kernels() -> dict[str, CPUDispatcher]:
    kernels = {}
    for info in pkgutil.walk_packages(rocketdrl_ma.__path__, "rocketdrl_ma."):
        if info.name.startswith(("rocketdrl_ma.web", "rocketdrl_ma.integrations")):
            continue  # no kernels there, and optional dependencies
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == info.name:
                kernels[f"{info.name}.{name}"] = value
    return kernels


def test_every_kernel_releases_the_gil():
    kernels = _package_kernels()
    assert len(kernels) >= 20  # the physics, arena and ray kernels were found
    holding = sorted(name for name, kernel in kernels.items() if not kernel.targetoptions.get("nogil"))
    assert holding == []
