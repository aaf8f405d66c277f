"""Reward shaping the trainer adds to the env's reward: the ``shaping:`` section of a training YAML.

Shaping terms are reward terms like the env's (``rules/rewards.py``), each a ``PotentialDifference`` of a
potential, ``phi(s') - phi(s)`` per decision; the env's reward is left alone (evaluation, success rates and
logged returns use it). Potentials, in units of 1000 uu:

- ``car_to_ball``: minus the distance from the agent's car to the ball;
- ``ball_to_goal``: minus the distance from the ball to the centre of the goal the agent attacks.
"""
from __future__ import annotations

from rocketdrl_ma.rules.rewards import (BallToGoalDistance, CarToBallDistance, CombinedReward, PotentialDifference,
                                        TermMakers, check_weights)

SHAPING_TERMS: TermMakers = {"car_to_ball": lambda: PotentialDifference(CarToBallDistance()),
                             "ball_to_goal": lambda: PotentialDifference(BallToGoalDistance())}


def check_shaping(shaping: object) -> dict[str, float]:
    return check_weights(SHAPING_TERMS, shaping, "shaping")


def make_shaping(weights: dict[str, float]) -> CombinedReward:
    """The shaping reward of one env copy (its terms remember each agent's last potential)."""
    return CombinedReward.from_weights(SHAPING_TERMS, weights, "shaping")
