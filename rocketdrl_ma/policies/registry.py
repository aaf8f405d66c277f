"""Policies by name: ``scripted:ball_chaser`` or ``checkpoint:PATH.pt`` (see ``policies.base`` for the interface).

A training config's teacher (``imitate.bot``, ``kickstart.bot``, ``imitate.opponent``) is a scripted bot's bare
name, as it always was, or any such spec: a trained checkpoint teaches through its own sensors and actions.
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


def check_teacher(field: str, name: object) -> str:
    """``name`` if ``load_teacher`` can load it (a checkpoint's JSON is read now, so a wrong path fails at config
    load, not in a rollout worker); else ValueError naming ``field`` and what is allowed."""
    kind, sep, argument = name.partition(":") if isinstance(name, str) else ("", "", "")
    if isinstance(name, str) and not sep:
        kind, argument = "scripted", name
    if kind == "scripted" and argument in SCRIPTED_BOTS:
        return name
    if kind == "checkpoint":
        from .ppo.checkpoint import read_meta
        try:
            read_meta(argument)
        except (OSError, ValueError) as error:
            raise ValueError(f"{field}: {name!r}: {error}") from None
        return name
    raise ValueError(f"{field}: {name!r} is not one of the scripted bots {sorted(SCRIPTED_BOTS)} (bare or "
                     "'scripted:NAME') nor 'checkpoint:PATH'")
