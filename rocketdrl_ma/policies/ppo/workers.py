"""The rollout workers of a training run.

``n_workers`` 0 steps the env copies in the trainer's own process; N >= 1 gives N worker processes, each owning
``ceil(n_envs / N)`` copies (``rollout.py``) and a copy of the ``RolloutPolicy``. Synchronous collection (the
default) runs the lean loop of ``worker_loop.py`` (numpy and shared memory, no TensorDict per step); ``async`` keeps
torchrl's ``MultiAsyncCollector`` and ``ray`` its ``RayCollector`` (over ``RolloutEnv``). Whatever the backend, a
batch comes back as one ``TensorDict`` ``[rows, T]`` (rows first, then decisions), and ``update_weights`` ships the
policy (learner, opponents and the learner's decisions: ``rollout_policy.py``) to every worker.

Overlap (``WorkerPlan.overlap``, synchronous local workers): ``collect_ahead`` sends the workers on to the next
batch as soon as one arrives, and a thread waits for it while the learner updates; the weights are pushed only
between batches, before the workers set off, so each batch is collected with exactly the weights of one update
before and the run is the same whatever the timing.

Faults: a worker that dies (a crash, an OOM kill, ``kill -9``) makes the collector raise while it collects, or the
weight push raise (``WorkerLost``) between batches; the batch being collected is dropped, the collector
is rebuilt with fresh workers, and collection goes on. A run whose workers keep dying (``MAX_RESTARTS`` in a row
without a batch in between) stops with the error.
"""
from __future__ import annotations

import copy
import logging
import os
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, replace
from pathlib import Path

from tensordict import TensorDictBase

from .config import TrainConfig
from .rollout import RolloutEnvFactory, worker_copies
from .rollout_policy import RolloutPolicy
from .worker_loop import LeanCollector

log = logging.getLogger(__name__)
MAX_RESTARTS = 5


WORKER_FAULTS = (RuntimeError, EOFError, BrokenPipeError, ConnectionError, OSError, ValueError)


def is_worker_fault(error: Exception) -> bool:
    """Whether a collector's error means a worker failed. A ``ValueError`` does only as what multiprocessing raises
    when torchrl, having found a dead worker, terminates the others and closes them 0.1 s later while one is still
    exiting (a loaded machine)."""
    if isinstance(error, ValueError):
        return "Cannot close a process while it is still running" in str(error)
    return isinstance(error, WORKER_FAULTS)


def default_workers() -> int:
    """The machine's usable cores (the CPU affinity of this process where the OS has one)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS, Windows
        return max(1, os.cpu_count() or 1)


@dataclass
class WorkerPlan:
    """How a run's env copies are spread: ``n_workers`` (0: in-process) and where (``ray``: an address or
    ``auto``; None: local processes); ``overlap``: synchronous local workers collect the next batch while the
    learner updates (``collect_ahead``)."""

    n_workers: int
    asynchronous: bool = False
    ray: str | None = None
    overlap: bool = True

    @property
    def overlapping(self) -> bool:
        return self.overlap and self.n_workers > 0 and self.ray is None and not self.asynchronous

    @property
    def processes(self) -> int:
        return max(1, self.n_workers)


class Rollouts:
    def __init__(self, cfg: TrainConfig, policy: RolloutPolicy, plan: WorkerPlan, rows_per_copy: int):
        self.cfg, self.policy, self.plan = cfg, policy, plan
        # What the workers act with: torchrl shares the collector's policy tensors with the worker processes, so
        # a copy of the learner's keeps them from seeing the learner's in-place updates while they collect ahead.
        self.acting = copy.deepcopy(policy) if plan.n_workers > 0 and policy is not None else policy
        self.copies = worker_copies(cfg.n_envs, plan.processes)
        self.rows_per_worker = self.copies * rows_per_copy
        self.rows = self.rows_per_worker * plan.processes
        if plan.asynchronous:  # every worker's batch is one update's buffer
            self.horizon = max(1, cfg.buffer_size // self.rows_per_worker)
        else:
            self.horizon = max(1, cfg.buffer_size // self.rows)
        self.restarts = 0
        self._consecutive_faults = 0
        self._collector = None
        self._iterator: Iterator | None = None
        self._ahead: Future | None = None
        self._waiter = ThreadPoolExecutor(max_workers=1, thread_name_prefix="collect-ahead")

    # ------------------------------------------------------------------ building the collector
    def _factories(self) -> list[RolloutEnvFactory]:
        in_worker = self.plan.n_workers > 0
        return [RolloutEnvFactory(self.cfg, self.copies, w, seed_torch=in_worker) for w in range(self.plan.processes)]

    def _build(self):
        from torchrl.collectors import Collector, MultiAsyncCollector

        from .weight_push import WatchedSharedMemPush

        per_worker = self.rows_per_worker * self.horizon
        if self.plan.ray is not None:
            return self._build_ray(per_worker)
        if not self.plan.asynchronous:  # the lean loop: torchrl's collector cost a third of a Penalty worker
            return LeanCollector(self.cfg, self.acting, self.plan.n_workers, self.copies, self.horizon)
        if self.plan.n_workers == 0:
            return Collector(self._factories()[0](), self.acting, frames_per_batch=per_worker, total_frames=-1,
                             auto_register_policy_transforms=False)
        push = WatchedSharedMemPush()
        collector = MultiAsyncCollector(self._factories(), self.acting, frames_per_batch=per_worker,
                                        total_frames=-1, weight_sync_schemes={"policy": push})
        push.watch(collector.procs)
        return collector

    def _build_ray(self, per_worker: int):
        from torchrl.collectors.distributed import RayCollector

        import rocketdrl_ma

        package = str(Path(rocketdrl_ma.__file__).resolve().parent)
        init = {"address": None if self.plan.ray == "auto" else self.plan.ray,
                # the workers import this very package, shipped by Ray to nodes that lack it
                "runtime_env": {"py_modules": [package], "env_vars": {"RL_WARNINGS": "0"}},
                "log_to_driver": False}
        return RayCollector(self._factories(), self.acting, frames_per_batch=per_worker * self.plan.processes,
                            total_frames=2 ** 62, sync=not self.plan.asynchronous, num_collectors=self.plan.processes,
                            ray_init_config=init,
                            remote_configs={"num_cpus": 1, "num_gpus": 0, "memory": 1024 ** 3})

    # ------------------------------------------------------------------ batches
    def collect_ahead(self) -> None:
        """Send the workers on to the next batch now, with the weights they hold, and return at once; the next
        ``next_batch`` takes it. Without overlap (or before the workers exist) the next batch starts there."""
        if self.plan.overlapping and self._iterator is not None and self._ahead is None:
            self._ahead = self._waiter.submit(next, self._iterator)

    def next_batch(self) -> TensorDictBase:
        """The next batch ``[rows, T]``; a worker fault drops the batch in progress and rebuilds the workers."""
        if self._ahead is not None:
            ahead, self._ahead = self._ahead, None
            try:
                return self._arrived(ahead.result())
            except Exception as error:
                if not is_worker_fault(error):
                    raise
                self._worker_fault(error)
        while True:
            if self._iterator is None:
                self._collector = self._build()
                self.update_weights()  # the workers start from the learner's weights and decisions
                if self._collector is None:  # a worker died before it took them
                    continue
                self._iterator = iter(self._collector)
            try:
                return self._arrived(next(self._iterator))
            except Exception as error:
                if not is_worker_fault(error):
                    raise
                self._worker_fault(error)

    def _arrived(self, batch: TensorDictBase) -> TensorDictBase:
        self._consecutive_faults = 0
        return batch.reshape(-1, batch.shape[-1]) if batch.ndim > 2 else batch

    def update_weights(self) -> None:
        """Ship the policy (weights and buffers) to every worker. A worker found dead drops the collector: the
        next batch comes from fresh workers, which start from these weights."""
        from .weight_push import WorkerLost

        if self._ahead is not None:  # the workers would take them mid-batch
            raise RuntimeError("update_weights: the workers are collecting ahead; take that batch first")
        if self._collector is not None and self.plan.n_workers > 0:
            if self.acting is not self.policy:  # in place: into the tensors the workers share
                self.acting.load_state_dict(self.policy.state_dict())
            try:
                self._collector.update_policy_weights_()
            except WorkerLost as error:
                self._worker_fault(error)

    def _worker_fault(self, error: Exception) -> None:
        """Stop the workers after one of them failed; give up after ``MAX_RESTARTS`` faults without a batch."""
        self.restarts += 1
        self._consecutive_faults += 1
        log.warning("rollout workers failed (%s); restarting them (%d)", error, self.restarts)
        self._shutdown_quietly()
        if self._consecutive_faults > MAX_RESTARTS:
            raise RuntimeError(f"rollout workers failed {self._consecutive_faults} times in a row: {error}") from error

    def set_difficulty(self, level: float | None) -> None:
        """Where a minigame curriculum stands: workers (re)built from now on start their games at this level;
        running ones get it through the policy (``ctl_difficulty``)."""
        if level is not None and self.cfg.env.get("difficulty") != level:
            self.cfg = replace(self.cfg, env={**self.cfg.env, "difficulty": level})

    def describe(self) -> str:
        if self.plan.n_workers == 0:
            return "in-process"
        where = " on Ray" if self.plan.ray is not None else ""
        return f"workers {self.workers_alive()}/{self.plan.processes}{where}"

    def workers_alive(self) -> int:
        if self.plan.n_workers == 0 or self._collector is None:
            return self.plan.processes
        procs = getattr(self._collector, "procs", None)
        if procs is None:  # Ray: its actors are supervised by Ray
            return self.plan.processes
        alive = 0
        for proc in procs:
            try:
                alive += int(proc.is_alive())
            except ValueError:  # closed
                pass
        return alive

    def worker_pids(self) -> list[int]:
        procs = getattr(self._collector, "procs", None) or []
        return [p.pid for p in procs]

    def _shutdown_quietly(self) -> None:
        ahead, self._ahead = self._ahead, None
        if ahead is not None:  # a batch nobody will take: let it arrive (or fail) before the workers stop
            try:
                ahead.result()
            except Exception as error:
                log.debug("the batch collected ahead ended with %s", error)
        collector, self._collector, self._iterator = self._collector, None, None
        if collector is None:
            return
        try:
            collector.shutdown()
        except Exception as error:  # a dead worker's pipes: the rest still gets stopped
            log.warning("while stopping the rollout workers: %s", error)
        for proc in getattr(collector, "procs", None) or []:
            try:
                if proc.is_alive():
                    proc.kill()
                    proc.join(timeout=5)
            except ValueError:  # already closed by the collector's shutdown
                pass

    def close(self) -> None:
        self._shutdown_quietly()
        self._waiter.shutdown()
