"""Policies by name: ``scripted:ball_chaser`` or ``checkpoint:PATH.pt`` (see ``policies.base`` for the interface).

A training config's teacher (``imitate.bot``, ``kickstart.bot``, ``imitate.opponent``) is a scripted bot's bare
name, as it always was, or any such spec: a trained checkpoint teaches through its own sensors and actions
(``load_teacher``; the config checks the name with ``policies.ppo.selfplay.config.check_teacher``).
"""
from __future__ import annotations

from typing import Callable

from .base import Policy
from .scripted import SCRIPTED_BOTS, make_scripted


def _load_checkpoint(path: str) -> Policy:
    # torch is imported only when a checkpoint is actually loaded
    from .ppo.checkpoint import load_checkpoint_policy
    return load_checkpoint_policy(path)


#: kind -> loader of the text after ``kind:``
POLICY_KINDS: dict[str, Callable[[str], Policy]] = {"scripted": make_scripted, "checkpoint": _load_checkpoint}


def load_policy(spec: str) -> Policy:
    """``scripted:<bot>`` or ``checkpoint:<path>``."""
    kind, sep, argument = spec.partition(":")
    if not sep or kind not in POLICY_KINDS:
        raise ValueError(f"policy: {spec!r} is not '<kind>:<argument>' with kind in {sorted(POLICY_KINDS)} "
                         f"(scripted bots: {sorted(SCRIPTED_BOTS)})")
    return POLICY_KINDS[kind](argument)


def load_teacher(name: str) -> Policy:
    """A teacher named in a training config: a scripted bot's bare name (``goalie``) or a policy spec."""
    return load_policy(name if ":" in name else f"scripted:{name}")

