"""The one policy interface: ``controls(agent, state)`` each decision, ``reset(state)`` at each episode.

Scripted bots, PPO checkpoints and whatever a user writes all implement it, so the league, the Zenoh bot SDK,
``play`` and the trainer's teachers and opponents drive every kind of policy the same way. A learned policy owns
the observation builder and action parser it was trained with (``ObservingPolicy``), so entrants trained with
different sensors can share a match.
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from rocketdrl_ma.env.actions import ActionParser
from rocketdrl_ma.env.observations import ObsBuilder
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.rules.state import GameState


class Policy(ABC):
    """Plays agents of a game from the game state."""

    name: str = "policy"

    def reset(self, state: GameState) -> None:
        """A new episode begins (stateful policies clear their memory here)."""

    @abstractmethod
    def controls(self, agent: str, state: GameState) -> CarControls:
        """What ``agent`` does this decision."""


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
