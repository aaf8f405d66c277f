"""Pushing the learner's weights to local rollout workers without waiting on a dead one.

torchrl's default for a multi-process collector, ``SharedMemWeightSyncScheme``, writes the weights into shared
memory, tells each worker to take them, and waits for every worker's acknowledgement with no time limit. A worker
that died between two batches (an OOM kill, ``kill -9``) never acknowledges, and the run hung there for good: the
collector only looks for dead workers while it collects. ``WatchedSharedMemPush`` is the same scheme whose wait
(``_wait_for_ack``, the hook torchrl's ``WeightSyncScheme`` leaves to subclasses) looks at the worker processes
while it waits and raises ``WorkerLost`` when one has died, which ``workers.Rollouts`` handles like any other
worker fault.
"""
from __future__ import annotations

import queue
from collections.abc import Sequence
from multiprocessing import connection
from multiprocessing.process import BaseProcess

from torchrl.weight_update import SharedMemWeightSyncScheme

ACK_POLL_S = 0.5  # how often a wait for an acknowledgement looks at the workers


class WorkerLost(RuntimeError):
    """A rollout worker died before it took the new weights."""


def _gone(process: BaseProcess) -> bool:
    """Whether the process has ended. Its sentinel says so even when someone else reaped it (then ``is_alive``
    would say True for ever); a closed ``Process`` was ended by the collector."""
    try:
        return bool(connection.wait([process.sentinel], timeout=0))
    except ValueError:
        return True


class WatchedSharedMemPush(SharedMemWeightSyncScheme):
    """``SharedMemWeightSyncScheme`` whose wait for the workers' acknowledgements ends with ``WorkerLost`` when a
    worker process is gone. ``watch(processes)`` names them once they are started (worker ``i`` is
    ``processes[i]``); before that the wait is torchrl's own."""

    def __init__(self) -> None:
        super().__init__()
        self._watched: Sequence[BaseProcess] = ()

    def watch(self, processes: Sequence[BaseProcess]) -> None:
        self._watched = processes

    def __getstate__(self) -> dict:
        # the scheme travels to spawned workers; process handles cannot, and only the sender waits
        return {**super().__getstate__(), "_watched": ()}

    def _wait_for_ack(self, worker_ids: int | list[int] | None = None, timeout: float | None = None) -> None:
        if not self._watched or timeout is not None:
            super()._wait_for_ack(worker_ids, timeout)
            return
        targets = list(self._ack_queues) if worker_ids is None else (
            [worker_ids] if isinstance(worker_ids, int) else list(worker_ids))
        for worker in targets:
            while True:
                try:
                    self._ack_queues[worker].get(timeout=ACK_POLL_S)
                    break
                except queue.Empty:
                    if _gone(self._watched[worker]):
                        raise WorkerLost(f"rollout worker {worker} died before it took the new weights") from None
