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

from typing import Any

from rocketdrl_ma.config import optional_section

KICKSTART_KEYS: dict[str, Any] = {"bot": "ball_chaser", "weight": 1.0, "decay_steps": 5_000_000}


def check_kickstart(section: object, name: str = "selfplay.kickstart") -> dict[str, Any]:
    """The ``kickstart`` mapping (``selfplay.kickstart``, or a single-team game's top-level ``kickstart``, as
    ``name`` says) with defaults; empty: no teacher."""
    from rocketdrl_ma.policies.scripted import SCRIPTED_BOTS

    out = optional_section(name, section, KICKSTART_KEYS)
    if not out:
        return out
    if out["bot"] not in SCRIPTED_BOTS:
        raise ValueError(f"{name}.bot: {out['bot']!r} is not one of {sorted(SCRIPTED_BOTS)}")
    weight = out["weight"]
    if isinstance(weight, bool) or not isinstance(weight, (int, float)) or weight <= 0.0:
        raise ValueError(f"{name}.weight: expected a number > 0, got {weight!r}")
    out["weight"] = float(weight)
    decay = out["decay_steps"]
    if decay is not None and (isinstance(decay, bool) or not isinstance(decay, int) or decay < 1):
        raise ValueError(f"{name}.decay_steps: expected an int >= 1 or null, got {decay!r}")
    return out


def teacher_weight(spec: dict[str, Any], agent_steps: int) -> float:
    """The distillation term's weight at ``agent_steps``; 0 without a teacher or once the decay is over."""
    if not spec:
        return 0.0
    if spec["decay_steps"] is None:
        return spec["weight"]
    return spec["weight"] * max(0.0, 1.0 - agent_steps / spec["decay_steps"])
