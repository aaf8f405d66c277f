"""Two worker processes for a test whose independent matches, kickoffs or training runs would otherwise run one after
another: the suite runs serially in one pytest process on 2 cores, so during such a test the second core is idle."""
from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor


def _one_torch_thread() -> None:
    """Two workers with torch's default of a thread per core oversubscribe the 2 cores: the league's 2v2 matches took
    43 s instead of 29 s. One thread is what the trainer uses for these small networks too."""
    import torch
    torch.set_num_threads(1)


def two_processes() -> ProcessPoolExecutor:
    """Spawned, not forked: the test process has torch and pybullet loaded. What a worker runs must be importable
    (a module-level function of a test module is: the children get the test process's ``sys.path``)."""
    return ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_one_torch_thread)
