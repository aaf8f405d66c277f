"""rocketdrl-ma: multi-agent car football on PyBullet for reinforcement learning.

``rocketdrl_ma.parallel_env(config="matches/2v2.yaml", render_mode=None, **overrides)`` and
``rocketdrl_ma.env(...)`` (the AEC form) are the PettingZoo entry points.
"""
from __future__ import annotations

from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("rocketdrl-ma")  # pyproject.toml's, as installed (the wheel reports the same)
except _metadata.PackageNotFoundError:  # a source tree on sys.path that was never installed
    __version__ = "0+unknown"

# Import the subpackage before defining ``env()``: a later first import of ``rocketdrl_ma.env`` would
# otherwise rebind the package attribute ``env`` from the function to the subpackage.
import rocketdrl_ma.env as _env_package  # noqa: F401


def parallel_env(config="matches/1v1.yaml", render_mode=None, **overrides):
    """A PettingZoo ParallelEnv of the game the config describes."""
    from rocketdrl_ma.env.parallel_env import RocketDRLParallelEnv
    return RocketDRLParallelEnv(config, render_mode=render_mode, **overrides)


def env(config="matches/1v1.yaml", render_mode=None, **overrides):
    """The same game as an AEC env (PettingZoo's parallel_to_aec)."""
    from pettingzoo.utils.conversions import parallel_to_aec
    return parallel_to_aec(parallel_env(config, render_mode=render_mode, **overrides))
