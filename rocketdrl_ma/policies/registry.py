"""Policies by name: ``scripted:ball_chaser``, and whatever kinds other modules register (checkpoints).

A ``Policy`` plays one agent from the game state to controls. A learned policy owns the observation
builder and action parser it was trained with, so entrants trained with different sensors can share
a match (the league, the Zenoh bot SDK and ``play`` all drive policies through this one interface).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Callable

import numpy as np

from rocketdrl_ma.env.actions import ActionParser
from rocketdrl_ma.env.observations import ObsBuilder
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.rules.state import GameState

from .scripted import SCRIPTED_BOTS, make_scripted


class Policy(ABC):
    """Plays agents of a game: ``controls(agent, state)`` each decision, ``reset(state)`` at each episode."""

    name: str = "policy"

    def reset(self, state: GameState) -> None:
        """A new episode begins (stateful policies clear their memory here)."""

    @abstractmethod
    def controls(self, agent: str, state: GameState) -> CarControls:
        """What ``agent`` does this decision."""


class ScriptedPolicy(Policy):
    """A scripted bot from ``policies/scripted.py``."""

    def __init__(self, bot_name: str):
        self.bot = make_scripted(bot_name)
        self.name = f"scripted:{bot_name}"

    def controls(self, agent: str, state: GameState) -> CarControls:
        return self.bot.act(agent, state)


class ObservingPolicy(Policy):
    """A policy that acts on its own observation builder's output through its own action parser."""

    def __init__(self, obs_builder: ObsBuilder, action_parser: ActionParser):
        self.obs_builder, self.action_parser = obs_builder, action_parser

    def reset(self, state: GameState) -> None:
        self.obs_builder.reset(state)

    @abstractmethod
    def act(self, obs: np.ndarray) -> np.ndarray | int:
        """An action in the action parser's format for one observation."""

    def controls(self, agent: str, state: GameState) -> CarControls:
        return self.action_parser.parse(agent, self.act(self.obs_builder.build(agent, state)), state)


def _load_checkpoint(path: str) -> Policy:
    # torch is imported only when a checkpoint is actually loaded
    from .ppo.checkpoint import load_checkpoint_policy
    return load_checkpoint_policy(path)


#: kind -> loader of the text after ``kind:``; modules add their kinds with ``register_policy_kind``.
POLICY_KINDS: dict[str, Callable[[str], Policy]] = {"scripted": ScriptedPolicy, "checkpoint": _load_checkpoint}


def register_policy_kind(kind: str, loader: Callable[[str], Policy]) -> None:
    POLICY_KINDS[kind] = loader


def load_policy(spec: str) -> Policy:
    """``scripted:ball_chaser`` or ``<kind>:<argument>`` for any registered kind."""
    kind, sep, argument = spec.partition(":")
    if not sep or kind not in POLICY_KINDS:
        raise ValueError(f"policy: {spec!r} is not '<kind>:<argument>' with kind in {sorted(POLICY_KINDS)} "
                         f"(scripted bots: {sorted(SCRIPTED_BOTS)})")
    return POLICY_KINDS[kind](argument)
