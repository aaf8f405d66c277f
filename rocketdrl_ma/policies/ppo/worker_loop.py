"""The lean rollout loop: a worker steps its games (``rollout.WorkerGames``) with the rollout policy on numpy arrays
and writes each decision straight into shared-memory buffers, with no ``TensorDict`` and no spec check per step.

torchrl's collector around ``RolloutEnv`` builds, checks and moves a tensordict between root and ``next`` every
step, a large share of a cheap game's step (docs/experiments/engineering.md); this loop does what it did with the
same calls in the same order, so one seed gives the very batch torchrl's in-process collector gives
(``tests/policies/test_worker_loop.py``). The learner side keeps torchrl's GAE, loss and the rest.

``LeanCollector`` has the face ``workers.Rollouts`` expects of a collector (iterate for batches,
``update_policy_weights_``, ``shutdown``, ``procs``):

- ``n_workers`` 0: the loop runs in the trainer's process with the learner's policy itself;
- N workers: N spawned processes, each with its ``WorkerGames`` and the acting policy, whose parameters and
  buffers live in shared memory: the learner copies new weights into them between batches (never while the
  workers collect), so a weight push is a memory copy and a check that every worker is alive;
- a batch is every worker's ``[T, rows]`` buffers, concatenated over rows and turned ``[rows, T]``; a key that
  is a ``("next", key)`` of torchrl's batch is in ``"next"`` here too.

A worker that dies (a crash, ``kill -9``) ends the wait for its batch with ``EOFError`` (its pipe closes) or is
found dead by the weight push (``WorkerLost``); ``Rollouts`` then rebuilds the collector.
"""
from __future__ import annotations

import signal
import time
import traceback
from multiprocessing import connection

import numpy as np
import torch
from tensordict import TensorDict

from .config import TrainConfig
from .rollout import WorkerGames
from .rollout_policy import RolloutPolicy
from .weight_push import WorkerLost, _gone

#: what a decision records before it is played (the policy's inputs and outputs the learner reads)
ROOT_KEYS = ("observation", "teacher_action", "action", "action_log_prob", "policy_version")
#: the policy's inputs in self-play, besides the observation
SELFPLAY_INPUTS = ("opponent_observation", "opponent_id", "episode_start", "opponent_draw")
#: what a step returns that a batch does not carry under ``next`` (the next decision's inputs, recorded with it)
NOT_RECORDED = SELFPLAY_INPUTS + ("teacher_action",)


class TrajectoryLoop:
    """One worker's games and policy: ``collect(T)`` plays T decisions of every row into buffers ``[T, rows, ...]``.
    The games keep going from one batch to the next (an episode spans batches), as with torchrl's collectors."""

    def __init__(self, games: WorkerGames, policy: RolloutPolicy):
        self.games, self.policy = games, policy
        # the env's time per decision on the wall clock (no system call), scaled per batch by the loop's CPU share
        games.env_clock_ns = time.perf_counter_ns
        self.current: dict[str, np.ndarray] | None = None  # the observation keys the next decision acts on
        self.buffers: dict[str, torch.Tensor] = {}

    def _allocate(self, horizon: int, root: dict[str, np.ndarray], acted: dict[str, np.ndarray],
                  step: dict[str, np.ndarray], shared: bool) -> None:
        def buffer(value: np.ndarray) -> torch.Tensor:
            dtype = torch.from_numpy(np.empty(0, value.dtype)).dtype
            tensor = torch.empty((horizon,) + value.shape, dtype=dtype)
            return tensor.share_memory_() if shared else tensor

        self.buffers = {key: buffer(value) for key, value in {**root, **acted}.items() if key in ROOT_KEYS}
        self.buffers.update({("next", key): buffer(value) for key, value in step.items() if key not in NOT_RECORDED})
        self._arrays = {key: tensor.numpy() for key, tensor in self.buffers.items()}

    def collect(self, horizon: int, shared: bool = False) -> dict:
        """T decisions into ``self.buffers`` (allocated at the first call, in shared memory with ``shared``)."""
        games, policy = self.games, self.policy
        if self.current is None:
            self.current = games.reset()
        version = policy.version.numpy()
        cpu_start, wall_start = time.thread_time_ns(), time.perf_counter_ns()
        for t in range(horizon):
            current = self.current
            observation = torch.from_numpy(current["observation"])
            inputs = {key: torch.from_numpy(current[key]) for key in SELFPLAY_INPUTS} if games.selfplay else {}
            acted = {key: value.numpy() for key, value in policy.act(observation, **inputs).items()}
            acted["policy_version"] = np.broadcast_to(version, (games.rows,))
            opponent = {key: acted[key] for key in ("opponent_action", "opponent_id", "opponent_generation")
                        } if games.selfplay else {}
            step = games.step(acted["action"], ctl_difficulty=float(policy.difficulty),
                              ctl_kickstart=bool(policy.kickstart), **opponent)
            if not self.buffers:
                self._allocate(horizon, current, acted, step, shared)
            arrays = self._arrays
            for key in arrays:
                if isinstance(key, tuple):
                    arrays[key][t] = step[key[1]]
                else:
                    arrays[key][t] = acted[key] if key in acted else current[key]
            self.current = self._after(step)
        # CPU, not wall time: a busy machine must not shrink the env's capacity
        cpu_share = (time.thread_time_ns() - cpu_start) / max(time.perf_counter_ns() - wall_start, 1)
        self._arrays[("next", "env_cpu_s")] *= min(cpu_share, 1.0)
        return self.buffers

    def _after(self, step: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The next decision's inputs: the step's observation keys, where a copy ended those of its reset (torchrl's
        partial reset: the rows flagged done take the reset's values)."""
        done = step["done"][:, 0]
        if not done.any():
            return step
        games = self.games
        reset = games.reset(done.reshape(games.copies, games.copy_rows).any(-1))
        return {key: np.where(done.reshape((-1,) + (1,) * (value.ndim - 1)), reset[key], value)
                for key, value in step.items() if key in reset}

    def close(self) -> None:
        self.games.close()


def batch_of(buffers: list[dict]) -> TensorDict:
    """One batch ``[rows, T]`` of the workers' ``[T, rows]`` buffers, rows of worker 0 first (copied: the workers
    may overwrite their buffers with the next batch while the learner reads this one)."""
    root, nxt = {}, {}
    for key in buffers[0]:
        value = torch.cat([b[key] for b in buffers], dim=1).transpose(0, 1).contiguous()
        if isinstance(key, tuple):
            nxt[key[1]] = value
        else:
            root[key] = value
    rows, horizon = root["observation"].shape[:2]
    root["next"] = TensorDict(nxt, batch_size=[rows, horizon])
    return TensorDict(root, batch_size=[rows, horizon])


def seed_worker(cfg: TrainConfig, worker: int) -> None:
    """A worker process's torch: its own seeded generator (the policy's samples) and one thread (one core's work)."""
    torch.set_num_threads(1)
    torch.manual_seed(cfg.seed * 7919 + worker)


def _worker_main(cfg: TrainConfig, copies: int, worker: int, horizon: int, policy: RolloutPolicy,
                 conn: connection.Connection) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the trainer's: it stops the workers itself
    seed_worker(cfg, worker)
    loop = None
    try:
        loop = TrajectoryLoop(WorkerGames(cfg, copies, worker), policy)
        sent = False
        while True:
            command = conn.recv()
            if command == "close":
                break
            buffers = loop.collect(horizon, shared=True)
            conn.send(("buffers", buffers) if not sent else ("done", None))
            sent = True
    except (EOFError, KeyboardInterrupt):  # the trainer has gone
        pass
    except Exception:
        conn.send(("error", traceback.format_exc()))
    finally:
        if loop is not None:
            loop.close()


class LeanCollector:
    """Synchronous batches of ``horizon`` decisions from ``n_workers`` processes (0: in this process)."""

    def __init__(self, cfg: TrainConfig, policy: RolloutPolicy, n_workers: int, copies: int, horizon: int):
        self.horizon = horizon
        self.procs: list = []
        self._conns: list[connection.Connection] = []
        self._buffers: list[dict] | None = None
        self._loop: TrajectoryLoop | None = None
        if n_workers == 0:
            self._loop = TrajectoryLoop(WorkerGames(cfg, copies, 0), policy)
            return
        context = torch.multiprocessing.get_context("spawn")
        policy.share_memory()  # the learner's weight pushes are copies into these tensors
        for worker in range(n_workers):
            mine, theirs = context.Pipe()
            proc = context.Process(target=_worker_main, args=(cfg, copies, worker, horizon, policy, theirs),
                                   name=f"rollout-worker-{worker}", daemon=True)
            proc.start()
            theirs.close()  # a worker's death then closes its pipe: the wait for its batch ends with EOFError
            self.procs.append(proc)
            self._conns.append(mine)

    def __iter__(self):
        return self

    def __next__(self) -> TensorDict:
        if self._loop is not None:
            return batch_of([self._loop.collect(self.horizon)])
        for conn in self._conns:
            conn.send("collect")
        arrived = [self._receive(k) for k in range(len(self._conns))]
        if self._buffers is None:
            self._buffers = arrived
        return batch_of(self._buffers)

    def _receive(self, worker: int) -> dict | None:
        conn, proc = self._conns[worker], self.procs[worker]
        while not conn.poll():
            ready = connection.wait([conn, proc.sentinel])
            if proc.sentinel in ready and not conn.poll():
                raise EOFError(f"rollout worker {worker} died while it collected (exit code {proc.exitcode})")
        kind, payload = conn.recv()
        if kind == "error":
            raise RuntimeError(f"rollout worker {worker} failed:\n{payload}")
        return payload

    def update_policy_weights_(self) -> None:
        """The workers read the shared tensors the learner has just written; only check they are all there."""
        for worker, proc in enumerate(self.procs):
            if _gone(proc):
                raise WorkerLost(f"rollout worker {worker} died before it took the new weights")

    def shutdown(self) -> None:
        if self._loop is not None:
            self._loop.close()
            self._loop = None
        for conn in self._conns:
            try:
                conn.send("close")
            except (OSError, ValueError):  # a dead worker's pipe
                pass
        for proc in self.procs:
            proc.join(timeout=10)
            if proc.is_alive():
                proc.kill()
                proc.join(timeout=5)
        for conn in self._conns:
            conn.close()
        self._conns = []
