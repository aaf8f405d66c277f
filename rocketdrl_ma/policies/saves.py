"""The save jump: a car in the path of a ball on its way into the car's own goal, which would pass over the
car's roof but within what a jump reaches, jumps into it.

A ball on its way in often passes over the roof of a car on its goal line but within reach of a jump (the goal
histories that showed it: docs/experiments/rotator-tuning.md). Everything here is in a team's frame (the own goal at
-y) and assumes a straight flight under gravity, so a bounce or a touch on the way voids the prediction.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rocketdrl_ma.physics import constants as C

from .rotation import OWN_GOAL_Y

ROOF_ABOVE_CENTRE_UU = 35.0  # the car's roof over its centre: hitbox half height plus its offset, rounded up
#: the ball passes within this of the car's centre across its path (uu): the half width of a car facing the ball
#: plus the ball's radius is 133 uu; the rest is slack for the prediction's error and the car turning in its jump
SAVE_HALF_WIDTH_UU = 160.0
#: jump at most this long before the ball arrives (s); the prediction goes bad further ahead
SAVE_LEAD_S = 0.5
#: the ball must be coming at the car's goal at least this fast (uu/s), and aimed within this of a post (uu)
MIN_INCOMING_UU_S, POST_MARGIN_UU = 300.0, 200.0
UPRIGHT_UP_Z = 0.9  # the car's roof points this much up: on the floor, not a wall or ramp


def roof_height_uu(after_s: float) -> float:
    """The roof's height (uu) ``after_s`` into a jump from the floor with the button held: the jump's impulse, its
    hold force for ``JUMP_MAX_TIME`` and gravity (within 10 uu of the simulated car for the first 0.4 s)."""
    hold_s = min(after_s, C.JUMP_MAX_TIME)
    lift = C.JUMP_ACCEL + C.GRAVITY_Z
    z = C.CAR_SPAWN_REST_Z + C.JUMP_IMMEDIATE_VEL * hold_s + 0.5 * lift * hold_s ** 2
    free_s = after_s - hold_s
    if free_s > 0.0:
        z += (C.JUMP_IMMEDIATE_VEL + lift * hold_s) * free_s + 0.5 * C.GRAVITY_Z * free_s ** 2
    return z + ROOF_ABOVE_CENTRE_UU


@dataclass(frozen=True)
class Passing:
    """Where an incoming ball crosses the car's line across the field: how soon (s), how far to the side of the car's
    centre (uu) and how high (its centre, uu)."""
    in_s: float
    aside_uu: float
    height_uu: float


def passing(car_pos: np.ndarray, car_vel: np.ndarray, ball_pos: np.ndarray, ball_vel: np.ndarray) -> Passing | None:
    """When and where the ball crosses the car's y on its way towards the own goal (None: it is not coming at it),
    in the car's moving frame across the field, the ball's height under gravity."""
    closing_uu_s = float(ball_vel[1] - car_vel[1])
    if ball_pos[1] <= car_pos[1] or closing_uu_s > -1.0:
        return None
    in_s = float(car_pos[1] - ball_pos[1]) / closing_uu_s
    aside = float(ball_pos[0] + (ball_vel[0] - car_vel[0]) * in_s - car_pos[0])
    height = float(ball_pos[2] + ball_vel[2] * in_s + 0.5 * C.GRAVITY_Z * in_s ** 2)
    return Passing(in_s, aside, height)


def heading_into_goal(ball_pos: np.ndarray, ball_vel: np.ndarray) -> bool:
    """The ball comes at the own goal at ``MIN_INCOMING_UU_S`` or more, its straight line within ``POST_MARGIN_UU``
    of the posts where it crosses the goal line."""
    if ball_vel[1] > -MIN_INCOMING_UU_S:
        return False
    to_line_s = float(OWN_GOAL_Y - ball_pos[1]) / float(ball_vel[1])
    return abs(float(ball_pos[0] + ball_vel[0] * to_line_s)) < C.GOAL_HALF_WIDTH + POST_MARGIN_UU


def jump_to_save(on_ground: bool, is_jumping: bool, up_z: float, car_pos: np.ndarray, car_vel: np.ndarray,
                 ball_pos: np.ndarray, ball_vel: np.ndarray) -> bool:
    """Whether the car presses jump to meet a ball that heads into its goal: on its wheels and upright, the ball due
    within ``SAVE_LEAD_S``, within ``SAVE_HALF_WIDTH_UU`` of the car's centre across its path, over the roof of a car
    on its wheels and under the roof of a jump by then. In a jump's hold it keeps holding while such a ball is still
    to come, its bottom over the car's centre (the roof is too strict: the car rises too little before the hold ends
    and the ball goes over it); a jump at a lower ball (the shot dodge's, into a rolling one) goes on as begun."""
    if not (on_ground or is_jumping) or (on_ground and up_z < UPRIGHT_UP_Z):
        return False
    if not heading_into_goal(ball_pos, ball_vel):
        return False
    crossing = passing(car_pos, car_vel, ball_pos, ball_vel)
    if crossing is None or crossing.in_s > SAVE_LEAD_S or abs(crossing.aside_uu) > SAVE_HALF_WIDTH_UU:
        return False
    bottom_uu = crossing.height_uu - C.BALL_RADIUS
    if not on_ground:
        return bottom_uu > car_pos[2]
    return roof_height_uu(0.0) < bottom_uu < roof_height_uu(crossing.in_s)
