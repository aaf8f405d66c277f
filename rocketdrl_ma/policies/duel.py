"""Two learners trained in turn against each other: the penalty duel's shooter and keeper (docs/penalty_duel.md).

Each learner is an ordinary self-play run (``selfplay.side`` fixes its team) whose snapshot slots hold the *other*
learner's newest snapshots (``selfplay.opponent_runs``). A cycle trains every learner for ``phase_steps`` agent
steps in turn, each phase a ``train`` of that learner resumed from its last checkpoint, so PPO itself is
unchanged and every phase can be inspected, evaluated or resumed on its own. The first learner's first phase meets
only its scripted opponents (no snapshot of the other exists yet). A phase's ``max_steps`` is where that phase
ends, so a duel learner wants ``learning_rate_schedule: constant`` (linear would fall to zero in every phase).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from rocketdrl_ma.policies.ppo.checkpoint import read_meta
from rocketdrl_ma.policies.ppo.config import TrainConfig
from rocketdrl_ma.policies.ppo.trainer import train
from rocketdrl_ma.policies.ppo.workers import WorkerPlan


@dataclass
class Phase:
    cycle: int         # from 1
    learner: str       # the learner's name (its run directory under the duel's root)
    agent_steps: int   # that learner's agent steps after the phase
    checkpoint: Path
    stopped: bool = False  # a Ctrl-C or SIGTERM ended the phase early, and with it the duel


def check_learners(learners: dict[str, TrainConfig]) -> None:
    """Every learner is a self-play config on its own fixed side."""
    if len(learners) < 2:
        raise ValueError(f"duel: expected two learners or more, got {list(learners)}")
    sides = {}
    for name, cfg in learners.items():
        side = cfg.selfplay.side if cfg.selfplay else None
        if side not in ("blue", "orange"):
            raise ValueError(f"{name}: selfplay.side: a duel learner plays one fixed team, 'blue' or 'orange', "
                             f"got {side!r}")
        if side in sides.values():
            raise ValueError(f"{name}: selfplay.side: {side!r} is already {next(n for n, s in sides.items() if s == side)}'s")
        sides[name] = side


def duel(learners: dict[str, TrainConfig], root: str | Path, cycles: int, phase_steps: int,
         workers: WorkerPlan | None = None, progress: bool = False) -> list[Phase]:
    """``cycles`` rounds of ``phase_steps`` agent steps for each learner, in the order given; learner ``name``
    runs in ``root/name`` (TensorBoard logs, ``final.pt``, ``snapshots/``), which a later call resumes. A Ctrl-C
    or SIGTERM ends the phase it arrives in (its checkpoint written, as ``train`` does) and the duel with it: the
    next learner's phase does not start."""
    check_learners(learners)
    if cycles < 1 or phase_steps < 1:
        raise ValueError(f"duel: cycles and phase_steps must be >= 1, got {cycles} and {phase_steps}")
    root = Path(root)
    run_dirs = {name: root / name for name in learners}
    phases: list[Phase] = []
    for cycle in range(1, cycles + 1):
        for name, cfg in learners.items():
            run_dir = run_dirs[name]
            final = run_dir / "final.pt"
            done = int(read_meta(final)["agent_steps"]) if final.is_file() else 0
            others = [str(run_dirs[other]) for other in learners if other != name]
            phase_cfg = replace(cfg, max_steps=done + phase_steps,
                                selfplay=replace(cfg.selfplay, opponent_runs=tuple(others)))
            result = train(phase_cfg, final, run_dir, resume=final if final.is_file() else None, progress=progress,
                           workers=workers)
            phases.append(Phase(cycle, name, result.agent_steps, result.checkpoint, result.stopped))
            if result.stopped:
                return phases
    return phases
