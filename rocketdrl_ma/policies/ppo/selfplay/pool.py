"""The learner's side of self-play: the opponent table, PFSP over it, and the learner's snapshots.

Opponents are numbered once for a run: 0 is the learner itself, ``1..S`` the scripted bots of ``scripted:``,
``S+1..S+K`` the ``pool_size`` snapshot slots. A snapshot slot holds a frozen copy of the learner's network
(``slot_models``, part of the rollout policy, so the weights travel to every rollout worker with the
learner's); when a new snapshot replaces the oldest one its slot's generation goes up, so results of
episodes begun against the old occupant are not booked to the new one. The opponent of each new episode is
drawn from ``probabilities()``: the learner itself with probability ``self_play``, else prioritised
fictitious self-play (``pfsp.py``) over the scripted bots and the snapshots present. With ``opponent_runs`` (the
penalty duel's other learner, ``policies/duel.py``) the slots hold the newest snapshots of those runs instead, re-read at
every snapshot interval; the learner's own snapshots are still written, for the other learner.
"""
from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import torch
from torch import nn

from rocketdrl_ma.policies.ppo.checkpoint import checkpoint_meta, load_model, save_checkpoint
from rocketdrl_ma.policies.ppo.config import TrainConfig
from rocketdrl_ma.policies.ppo.model import PPOModel

from .games import SELF
from .pfsp import PFSP


class OpponentPool:
    def __init__(self, cfg: TrainConfig, run_dir: str | Path, obs_dim: int):
        self.cfg, self.sp = cfg, cfg.selfplay
        self.obs_dim = obs_dim
        self.snapshot_dir = Path(run_dir) / "snapshots"
        self.opponent_runs = [Path(run) for run in self.sp.opponent_runs]
        self.pfsp = PFSP(self.sp.weighting, self.sp.p, self.sp.window)
        self.scripted = [f"scripted:{bot}" for bot in self.sp.scripted]
        for name in self.scripted:
            self.pfsp.add_opponent(name)
        self.n_slots = self.sp.pool_size
        self.slot_names: list[str | None] = [None] * self.n_slots
        self.slot_generation = [0] * self.n_slots
        self.slot_models: nn.ModuleList | None = None
        self.next_snapshot = self.sp.snapshot_interval
        self.picks: dict[str, int] = {}
        self.imitation: dict[str, list] = {}  # the warm start's report (imitation.warm_start)

    @property
    def n_opponents(self) -> int:
        return 1 + len(self.scripted) + self.n_slots

    def name_of(self, index: int) -> str | None:
        if index == SELF:
            return "self"
        if index <= len(self.scripted):
            return self.scripted[index - 1]
        return self.slot_names[index - 1 - len(self.scripted)]

    @property
    def opponents(self) -> list[str]:
        """The names PFSP chooses among: the scripted bots and the snapshots present."""
        return list(self.pfsp.results)

    # ------------------------------------------------------------------ the learner and its snapshots
    def attach(self, model: PPOModel, agent_steps: int) -> None:
        """Snapshot slots shaped like the learner; a fresh run clones the ``imitate`` bot into the learner, a
        resumed one reloads its newest snapshots."""
        self.slot_models = nn.ModuleList(copy.deepcopy(model).requires_grad_(False) for _ in range(self.n_slots))
        if agent_steps == 0 and self.sp.imitate:
            from .imitation import warm_start
            self.imitation = warm_start(model, self.cfg, log=print)
        interval = self.sp.snapshot_interval
        self.next_snapshot = (agent_steps // interval + 1) * interval
        self._fill_slots()

    def snapshots(self) -> list[Path]:
        """Snapshot files of this run, oldest first."""
        return _snapshot_files(self.snapshot_dir)

    def opponent_snapshots(self) -> list[Path]:
        """What the slots choose from, oldest first: this run's snapshots, or those of ``opponent_runs``."""
        if not self.opponent_runs:
            return self.snapshots()
        found = [p for run in self.opponent_runs for p in _snapshot_files(run / "snapshots")]
        return sorted(found, key=lambda p: (_step(p), str(p)))

    def _fill_slots(self) -> None:
        for path in self.opponent_snapshots()[-self.n_slots:]:
            self._load_into_slot(path)

    def snapshot(self, model: PPOModel, agent_steps: int, train_seconds: float | None = None) -> Path:
        """Save the learner as a playable checkpoint and put a frozen copy into the oldest slot; ``train_seconds``
        (the run's wall time so far, over all its sessions) goes into its metrics for rating curves."""
        metrics = {"snapshot": True} if train_seconds is None else {"snapshot": True, "train_seconds": train_seconds}
        meta = checkpoint_meta(self.cfg, model, self.obs_dim, agent_steps, metrics)
        path = save_checkpoint(self.snapshot_dir / f"step_{agent_steps}.pt", model, meta)
        if self.opponent_runs:  # the other learner's newest snapshots, which may have come since the last look
            self._fill_slots()
        else:
            self._load_into_slot(path)
        return path

    def _load_into_slot(self, path: Path) -> None:
        # another run's snapshot is named after its run: "keeper/snapshot:250000"
        run = f"{path.parent.parent.name}/" if self.opponent_runs else ""
        name = f"{run}snapshot:{_step(path)}"
        if name in self.slot_names:
            return
        present = [(int(n.rpartition(":")[2]), k) for k, n in enumerate(self.slot_names) if n is not None]
        empty = [k for k, n in enumerate(self.slot_names) if n is None]
        slot = empty[0] if empty else min(present)[1]
        model, _ = load_model(path)
        try:
            self.slot_models[slot].load_state_dict(model.state_dict())
        except RuntimeError as error:  # another run's network: a different observation, action or size
            raise ValueError(f"selfplay.opponent_runs: {path} is not shaped like this learner's network "
                             f"(observation, action, hidden_units, num_layers and features must match): {error}"
                             ) from error
        old = self.slot_names[slot]
        if old is not None:
            self.pfsp.remove_opponent(old)
        self.slot_names[slot] = name
        self.slot_generation[slot] += 1
        self.pfsp.add_opponent(name)

    def on_update(self, model: PPOModel, agent_steps: int, writer, train_seconds: float | None = None) -> None:
        """After each PPO update: snapshot the learner when due; log the pool's win rates."""
        if agent_steps >= self.next_snapshot:
            self.snapshot(model, agent_steps, train_seconds)
            self.next_snapshot = (agent_steps // self.sp.snapshot_interval + 1) * self.sp.snapshot_interval
        if writer is not None:
            for name, weight in self.pfsp.weights().items():
                writer.add_scalar(f"selfplay/pfsp_weight/{name}", weight, agent_steps)
                writer.add_scalar(f"selfplay/win_rate/{name}", self.pfsp.win_rate(name), agent_steps)
            writer.add_scalar("selfplay/pool_size", len(self.pfsp.results), agent_steps)

    # ------------------------------------------------------------------ choosing and booking opponents
    def probabilities(self) -> np.ndarray:
        """[n_opponents]: the chance of each opponent index for a new episode."""
        probs = np.zeros(self.n_opponents)
        weights = self.pfsp.weights() if self.pfsp.results else {}
        if not weights:
            probs[SELF] = 1.0
            return probs
        probs[SELF] = self.sp.self_play
        index = {self.name_of(i): i for i in range(1, self.n_opponents) if self.name_of(i) is not None}
        for name, weight in weights.items():
            probs[index[name]] = (1.0 - self.sp.self_play) * weight
        return probs

    def generations(self) -> np.ndarray:
        """[n_opponents]: each index's slot generation (0 for the learner and the scripted bots)."""
        return np.array([0] * (1 + len(self.scripted)) + self.slot_generation, np.int64)

    def record(self, opponent: int, generation: int, points: float) -> None:
        """The learner's result of an episode against ``opponent`` (begun at that slot ``generation``)."""
        name = self.name_of(opponent)
        if name is None or int(generation) != int(self.generations()[opponent]):
            return  # the slot changed hands during the episode
        self.picks[name] = self.picks.get(name, 0) + 1
        if opponent != SELF:
            self.pfsp.record(name, points)

    def state_tensors(self) -> tuple[torch.Tensor, torch.Tensor]:
        return torch.as_tensor(self.probabilities(), dtype=torch.float32), torch.as_tensor(self.generations())


def _step(snapshot: Path) -> int:
    return int(snapshot.stem.split("_")[1])


def _snapshot_files(folder: Path) -> list[Path]:
    return sorted(folder.glob("step_*[0-9].pt"), key=_step)
