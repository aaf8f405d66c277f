"""Game logic over the physics: the base rule class, state mutators, the full match (and minigames)."""
from .base import Rules, ball_heading_into_goal
from .match import Match
from .minigames import Aerial, Barrier, Penalty, PenaltyDuel
from .mutators import FixedStateMutator, KickoffMutator, RandomStateMutator, StateMutator
from .state import GameState, Obstacle, agent_names, agent_number, agent_team

#: game modes a config may name with ``mode:``
GAME_MODES: dict[str, type[Rules]] = {"match": Match, "penalty": Penalty, "barrier": Barrier, "aerial": Aerial,
                                     "penalty_duel": PenaltyDuel}

__all__ = ["FixedStateMutator", "GAME_MODES", "GameState", "KickoffMutator", "Match", "Obstacle",
           "RandomStateMutator", "Rules", "StateMutator", "agent_names", "agent_number", "agent_team",
           "ball_heading_into_goal"]
