"""Reward shaping computed by the trainer from the game state: differences of a potential.

The env's reward is left alone (evaluation, success rates and logged returns use it); the trainer adds
``phi(s') - phi(s)`` per decision. Over an episode that sums to ``phi(end) - phi(start)``: it pays for
progress (the car closing in on the ball, the ball closing in on the goal) and nothing for merely lasting.
(Ng, Harada and Russell's ``gamma * phi(s') - phi(s)`` with a negative potential would pay
``(1 - gamma) * |phi|`` per decision for staying in the episode, which taught our first Penalty runs to
run the clock down.) Potentials, each weighted by ``shaping:`` in the training YAML, in units of 1000 uu:

- ``car_to_ball``: minus the distance from the agent's car to the ball;
- ``ball_to_goal``: minus the distance from the ball to the centre of the goal the agent attacks.
"""
from __future__ import annotations

import numpy as np

from rocketdrl_ma.rules.state import ATTACKED_GOAL_CENTER, GameState, agent_team

SHAPING_TERMS = ("car_to_ball", "ball_to_goal")
DISTANCE_SCALE_UU = 1000.0


def check_shaping(shaping: object) -> dict[str, float]:
    if not isinstance(shaping, dict):
        raise ValueError(f"shaping: expected a mapping of term to weight, got {shaping!r}")
    for term, weight in shaping.items():
        if term not in SHAPING_TERMS:
            raise ValueError(f"shaping: unknown term {term!r}; allowed: {list(SHAPING_TERMS)}")
        if isinstance(weight, bool) or not isinstance(weight, (int, float)):
            raise ValueError(f"shaping.{term}: expected a number, got {weight!r}")
    return {term: float(weight) for term, weight in shaping.items()}


def potential(agent: str, state: GameState, weights: dict[str, float]) -> float:
    """phi(state) for ``agent``; 0 when no term has a weight."""
    value = 0.0
    car = state.cars.get(agent)
    if weights.get("car_to_ball") and car is not None:
        value -= weights["car_to_ball"] * np.linalg.norm(state.ball.pos - car.pos) / DISTANCE_SCALE_UU
    if weights.get("ball_to_goal"):
        goal = ATTACKED_GOAL_CENTER[agent_team(agent)]
        value -= weights["ball_to_goal"] * np.linalg.norm(goal - state.ball.pos) / DISTANCE_SCALE_UU
    return float(value)
