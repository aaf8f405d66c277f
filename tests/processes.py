"""Two worker processes for a test whose independent matches, kickoffs or training runs would otherwise run one after
another on one core (pytest runs a test in one process; `make test` runs two pytest workers, so a heavy test played
in two processes keeps both cores busy even when the other worker is between tests)."""
from __future__ import annotations

import multiprocessing
import os
import sys
from concurrent.futures import ProcessPoolExecutor


def _one_torch_thread() -> None:
    """Two workers with torch's default of a thread per core oversubscribe the 2 cores: the league's 2v2 matches took
    43 s instead of 29 s. One thread is what the trainer uses for these small networks too. Set for torch to read
    when it is imported, so workers that play scripted bots do not import it (1.8 s each)."""
    os.environ["OMP_NUM_THREADS"] = "1"
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(1)


def two_processes() -> ProcessPoolExecutor:
    """Spawned, not forked: the test process has torch and pybullet loaded. What a worker runs must be importable
    (a module-level function of a test module is: the children get the test process's ``sys.path``)."""
    return ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_one_torch_thread)
