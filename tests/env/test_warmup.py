"""`rocketdrl-ma warmup` leaves nothing to compile, and a process that does compile says so once (stderr).

Each check runs in a fresh process: numba compiles or loads a kernel once per process, so only a new process shows
what its cache holds."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from rocketdrl_ma.physics.arena_shape import ARENA_SHAPES
from rocketdrl_ma.physics.compile_notice import compiling_line

REPO = Path(__file__).resolve().parents[2]

# A 2v2 VectorEnv and a ParallelEnv stepped in the arena shape named by the first argument; then numba's own count of kernels it could not load from its cache.
FRESH_PROCESS = """
import sys
import numpy as np
from numba.core.registry import CPUDispatcher
import rocketdrl_ma
from rocketdrl_ma.env.vector_env import VectorEnv
from rocketdrl_ma.physics.compile_notice import kernels_compiled

vector = VectorEnv("matches/2v2.yaml", n_games=2, arena_shape=sys.argv[1])
vector.reset(seed=5)
for _ in range(3):
    vector.step(np.stack([np.stack([vector.action_space.sample() for _ in range(vector.n_agents)])
                          for _ in range(2)]))
env = rocketdrl_ma.parallel_env("matches/2v2.yaml", arena_shape=sys.argv[1])
env.reset(seed=6)
env.step({agent: env.action_space(agent).sample() for agent in env.agents})
modules = [m for m in list(sys.modules.values()) if getattr(m, "__name__", "").startswith("rocketdrl_ma")]
kernels = [value for module in modules for value in vars(module).values() if isinstance(value, CPUDispatcher)]
print("kernels", len(kernels), "cache_misses", sum(sum(k.stats.cache_misses.values()) for k in kernels),
      "compiled", len(kernels_compiled()))
"""

# Two functions compiled as if they were package kernels, one of another package: the line comes once.
PROBE = """
import numba
from rocketdrl_ma.physics.compile_notice import kernels_compiled

def plus_one(x):
    return x + 1

def times_two(x):
    return x * 2

def elsewhere(x):
    return x - 1

plus_one.__module__ = times_two.__module__ = "rocketdrl_ma.probe"
elsewhere.__module__ = "another_package"
for f in (elsewhere, plus_one, times_two):
    numba.njit(f)(3)
print(kernels_compiled())
"""


def _run(argv: list[str], cache_dir: Path) -> subprocess.CompletedProcess:
    # a cache of its own: other test processes compiling beside it may rewrite a shared cache index meanwhile
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])),
               NUMBA_CACHE_DIR=str(cache_dir))
    done = subprocess.run([sys.executable, *argv], cwd=REPO, env=env, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, f"{argv} exited {done.returncode}:\n{done.stdout}\n{done.stderr}"
    return done


def test_after_warmup_a_fresh_process_compiles_no_kernel(tmp_path):
    warm = _run(["-m", "rocketdrl_ma.cli", "warmup"], tmp_path)
    assert "physics kernels ready:" in warm.stdout
    for arena_shape in ARENA_SHAPES:
        fresh = _run(["-c", FRESH_PROCESS, arena_shape], tmp_path)
        _, kernels, _, misses, _, compiled = fresh.stdout.split()
        assert int(kernels) >= 5  # the entry kernels were found, so the count below means something
        assert (misses, compiled) == ("0", "0"), arena_shape
        assert compiling_line() not in fresh.stderr


def test_the_first_compile_of_a_process_prints_the_line_once(tmp_path):
    probe = _run(["-c", PROBE], tmp_path)
    assert probe.stderr.count(compiling_line()) == 1
    assert "rocketdrl_ma.probe.plus_one(int64,)" in probe.stdout and "times_two" in probe.stdout
    assert "elsewhere" not in probe.stdout
