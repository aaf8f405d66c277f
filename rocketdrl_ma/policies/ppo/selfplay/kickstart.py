"""Kickstarting (Schmitt et al., 2018): PPO's loss plus a distillation term towards a scripted teacher,
on the states the learner itself visits, with a weight that falls to zero as training goes on.

A warm start (``imitation.py``) fits the policy to the bot once; afterwards nothing holds the learner near
the teacher where PPO's early, noisy updates push it away, and the clone never sees the states it drives
into after the last DAgger round. Kickstarting is DAgger that never stops: every decision the learner's
cars take, the teacher is asked what it would have done there, and each PPO minibatch adds
``weight * imitation_loss`` (cross-entropy on the lookup row, squared error for Box actions). The weight
goes linearly from ``weight`` at agent step 0 to 0 at ``decay_steps`` (counted over the whole run, so a
resumed run continues the schedule; ``null`` keeps it constant, like AlphaStar's KL towards its
supervised policy). As it fades, the returns alone decide where the learner departs from the teacher.
"""
from __future__ import annotations

from .config import KickstartConfig


def teacher_weight(spec: KickstartConfig | None, agent_steps: int) -> float:
    """The distillation term's weight at ``agent_steps``; 0 without a teacher or once the decay is over."""
    if spec is None:
        return 0.0
    if spec.decay_steps is None:
        return spec.weight
    return spec.weight * max(0.0, 1.0 - agent_steps / spec.decay_steps)
