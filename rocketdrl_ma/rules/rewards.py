"""Rewards as named terms: small classes that read a decision's ``GameState``, combined with weights.

A term gives its unweighted value for one agent (``get``); ``CombinedReward`` holds terms under names with a
weight each (the ``rewards:`` section of a match or minigame YAML, the ``shaping:`` section of a training
YAML) and returns the total and each weighted term, which the env reports in ``infos["reward_terms"]``.
Terms read only the state, its events included, never a game mode's internals, so a term written for one
mode works in any mode that emits the events it counts. A game mode names the terms it offers in
``Rules.REWARD_TERMS`` (name -> term class) and their default weights in ``DEFAULT_REWARD_WEIGHTS``.

``PotentialDifference`` turns a potential (a term whose value is a function of the state alone) into the
shaping term ``phi(s') - phi(s)``: over an episode it sums to ``phi(end) - phi(start)``, so it pays for
progress and nothing for lasting (Ng, Harada and Russell's ``gamma * phi(s') - phi(s)`` with a negative
potential would pay ``(1 - gamma) * |phi|`` per decision for staying in the episode).
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping

import numpy as np

from rocketdrl_ma.physics import constants as C

from . import events as game_events
from .state import ATTACKED_GOAL_CENTER, BLUE, TEAM_NAMES, GameState, agent_team

#: distances in shaping potentials are in units of this many uu
DISTANCE_SCALE_UU = 1000.0


def _norm(v: np.ndarray) -> float:
    """``np.linalg.norm`` of a 3-vector, the same arithmetic (sqrt of ``v.dot(v)``) without its overhead."""
    return math.sqrt(v.dot(v))


class RewardTerm(ABC):
    """One reward term for every agent of a game."""

    def reset(self, agents: list[str], state: GameState) -> None:
        """An episode starts in ``state`` (stateful terms remember what they need here)."""

    @abstractmethod
    def get(self, agent: str, state: GameState) -> float:
        """The term's unweighted value for ``agent`` after this decision."""


# ------------------------------------------------------------------------------------------------- events
def _events(state: GameState, kind: type[game_events.GameEvent]) -> list:
    return [event for event in state.events if isinstance(event, kind)]


class GoalScored(RewardTerm):
    """+1 for every goal the agent's team scored this decision, -1 for every goal against it."""

    def get(self, agent: str, state: GameState) -> float:
        team = TEAM_NAMES[agent_team(agent)]
        return float(sum(1.0 if event.team == team else -1.0 for event in _events(state, game_events.Goal)))


class BallTouched(RewardTerm):
    """1 if the agent's car started a touch of the ball this decision."""

    def get(self, agent: str, state: GameState) -> float:
        return float(any(event.agent == agent for event in _events(state, game_events.Touch)))


class AerialTouched(RewardTerm):
    """The agent's aerial touches this decision (Aerial's ``aerial_touch`` events)."""

    def get(self, agent: str, state: GameState) -> float:
        return float(sum(event.agent == agent for event in _events(state, game_events.AerialTouch)))


class RoundMissed(RewardTerm):
    """Rounds of a shooting minigame that ended in a miss this decision."""

    def get(self, agent: str, state: GameState) -> float:
        return float(len(_events(state, game_events.Miss)))


class DecisionPassed(RewardTerm):
    """1 every decision: weighted negative, a cost of time."""

    def get(self, agent: str, state: GameState) -> float:
        return 1.0


class ShooterSide(RewardTerm):
    """A term seen from the shooting team (blue): the other team gets it negated, so the game is zero-sum."""

    def __init__(self, term: RewardTerm):
        self.term = term

    def reset(self, agents: list[str], state: GameState) -> None:
        self.term.reset(agents, state)

    def get(self, agent: str, state: GameState) -> float:
        value = self.term.get(agent, state)
        return value if agent_team(agent) == BLUE else -value


def _touched(agent: str, state: GameState) -> bool:
    return any(event.agent == agent for event in _events(state, game_events.Touch))


class TouchSpeed(RewardTerm):
    """On the agent's touch this decision, the ball's speed after it over the ball's top speed: hard hits pay."""

    def get(self, agent: str, state: GameState) -> float:
        return _norm(state.ball.vel) / C.BALL_MAX_SPEED if _touched(agent, state) else 0.0


class TouchHeight(RewardTerm):
    """On the agent's touch this decision, the ball's height above its resting height over the room up to the
    ceiling: 0 on the ground, 1 at the ceiling, so aerial touches pay."""

    def get(self, agent: str, state: GameState) -> float:
        if not _touched(agent, state):
            return 0.0
        return min(1.0, max(0.0, (state.ball.pos[2] - C.BALL_REST_Z) / (C.ARENA_HEIGHT - 2.0 * C.BALL_REST_Z)))


# ------------------------------------------------------------------------------------------------- state
class FaceBall(RewardTerm):
    """The cosine between the agent's car's nose and the direction to the ball: 1 facing it, -1 away."""

    def get(self, agent: str, state: GameState) -> float:
        car = state.cars[agent]
        to_ball = state.ball.pos - car.pos
        distance = _norm(to_ball)
        return float(car.rot_mat[:, 0] @ to_ball / distance) if distance > 1e-6 else 0.0


class BallVelocityToGoal(RewardTerm):
    """The ball's velocity towards the centre of the goal the agent attacks, over the ball's top speed."""

    def get(self, agent: str, state: GameState) -> float:
        to_goal = ATTACKED_GOAL_CENTER[agent_team(agent)] - state.ball.pos
        return float(state.ball.vel @ to_goal / (_norm(to_goal) * C.BALL_MAX_SPEED))


class PlayerVelocityToBall(RewardTerm):
    """The agent's car velocity towards the ball, over the car's top speed."""

    def get(self, agent: str, state: GameState) -> float:
        car = state.cars[agent]
        to_ball = state.ball.pos - car.pos
        distance = _norm(to_ball)
        return float(car.vel @ to_ball / (distance * C.CAR_MAX_SPEED)) if distance > 1e-6 else 0.0


class BoostAmount(RewardTerm):
    """sqrt(boost / 100): boost is worth more when little is left."""

    def get(self, agent: str, state: GameState) -> float:
        return math.sqrt(state.cars[agent].boost / C.BOOST_MAX)


class CarToBallDistance(RewardTerm):
    """Potential: minus the distance from the agent's car to the ball, in 1000 uu (0 for a car not in play)."""

    def get(self, agent: str, state: GameState) -> float:
        car = state.cars.get(agent)
        return 0.0 if car is None else -float(np.linalg.norm(state.ball.pos - car.pos)) / DISTANCE_SCALE_UU


class BallToGoalDistance(RewardTerm):
    """Potential: minus the distance from the ball to the centre of the goal the agent attacks, in 1000 uu."""

    def get(self, agent: str, state: GameState) -> float:
        goal = ATTACKED_GOAL_CENTER[agent_team(agent)]
        return -float(np.linalg.norm(goal - state.ball.pos)) / DISTANCE_SCALE_UU


class PotentialDifference(RewardTerm):
    """``phi(s') - phi(s)`` of a potential term between consecutive decisions of an episode."""

    def __init__(self, potential: RewardTerm):
        self.potential = potential
        self.last: dict[str, float] = {}

    def reset(self, agents: list[str], state: GameState) -> None:
        self.potential.reset(agents, state)
        self.last = {agent: self.potential.get(agent, state) for agent in agents}

    def get(self, agent: str, state: GameState) -> float:
        phi = self.potential.get(agent, state)
        before, self.last[agent] = self.last.get(agent, phi), phi
        return phi - before


# ------------------------------------------------------------------------------------------------- combining
#: what a game mode or the trainer offers: term name -> a maker of a fresh term
TermMakers = Mapping[str, Callable[[], RewardTerm]]


def check_weights(available: TermMakers, weights: object, section: str = "rewards") -> dict[str, float]:
    """``weights`` as {term: float}; a non-mapping, an unknown term or a weight that is not a finite number is an
    error naming ``section`` and the allowed terms."""
    if not isinstance(weights, Mapping):
        raise ValueError(f"{section}: expected a mapping of term to weight, got {weights!r}")
    for name, weight in weights.items():
        if name not in available:
            raise ValueError(f"{section}: unknown term {name!r}; allowed: {list(available)}")
        if isinstance(weight, bool) or not isinstance(weight, (int, float)) or not math.isfinite(weight):
            raise ValueError(f"{section}.{name}: expected a finite number, got {weight!r}")
    return {name: float(weight) for name, weight in weights.items()}


def share_within_teams(rewards: Mapping[str, float], team_spirit: float) -> dict[str, float]:
    """OpenAI Five's team spirit: each agent gets ``(1 - team_spirit)`` of its own reward plus ``team_spirit`` of
    its team's mean, so at 1 team-mates share every reward and no one is paid for taking a team-mate's touch."""
    if team_spirit == 0.0:
        return dict(rewards)
    teams: dict[int, list[float]] = {}
    for agent, value in rewards.items():
        teams.setdefault(agent_team(agent), []).append(value)
    means = {team: sum(values) / len(values) for team, values in teams.items()}
    return {agent: (1.0 - team_spirit) * value + team_spirit * means[agent_team(agent)]
            for agent, value in rewards.items()}


class CombinedReward:
    """Named terms, each with a weight; terms of weight 0 are reported (as 0) but not computed."""

    def __init__(self, terms: Mapping[str, tuple[RewardTerm, float]]):
        self.terms = dict(terms)
        self._active = {name: (term, weight) for name, (term, weight) in self.terms.items() if weight != 0.0}

    @classmethod
    def from_weights(cls, available: TermMakers, weights: object, section: str = "rewards") -> CombinedReward:
        """Every term of ``available`` with its weight from ``weights`` (0 if absent), checked by ``check_weights``."""
        weights = check_weights(available, weights, section)
        return cls({name: (make(), weights.get(name, 0.0)) for name, make in available.items()})

    @property
    def names(self) -> list[str]:
        return list(self.terms)

    def reset(self, agents: list[str], state: GameState) -> None:
        for term, _ in self._active.values():
            term.reset(agents, state)

    def get(self, agent: str, state: GameState) -> tuple[float, dict[str, float]]:
        """The agent's reward and each term's weighted value."""
        weighted = dict.fromkeys(self.terms, 0.0)
        for name, (term, weight) in self._active.items():
            weighted[name] = weight * float(term.get(agent, state))
        return float(sum(weighted.values())), weighted
