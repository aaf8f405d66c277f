"""Scripted bots: a ball-chaser and a goalie, opponents and baselines for learned policies.

They see the game the way the team-relative observation shows it to an agent (own car, ball, goals,
all in the agent's team frame) and answer with ``CarControls``; nothing they use is hidden from a
learning agent with the full-state observation.
"""
from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import GameState, agent_team

ATTACK_GOAL = np.array([0.0, C.ARENA_EXTENT_Y + 200.0, 0.0])  # in the team frame: always +y
OWN_GOAL = np.array([0.0, -C.ARENA_EXTENT_Y, 0.0])


def team_frame(agent: str, vec: np.ndarray) -> np.ndarray:
    """Orange sees the field turned half a circle (x -> -x, y -> -y) so every bot attacks +y."""
    return vec if agent_team(agent) == 0 else vec * np.array([-1.0, -1.0, 1.0])


def drive_to(car_pos: np.ndarray, car_rot: np.ndarray, target: np.ndarray, speed_up: bool = True,
             arrive_uu: float = 0.0) -> CarControls:
    """Steer at ``target``; boost when facing it and far; powerslide through sharp turns."""
    local = car_rot.T @ (target - car_pos)
    angle = math.atan2(local[1], local[0])  # positive: target to the right
    distance = float(np.hypot(local[0], local[1]))
    steer = float(np.clip(3.0 * angle, -1.0, 1.0))
    if distance < arrive_uu:
        return CarControls(throttle=0.0, steer=steer)
    throttle = 1.0 if abs(angle) < 2.2 or distance > 1500.0 else -1.0
    if throttle < 0.0:
        steer = -steer
    return CarControls(throttle=throttle, steer=steer, boost=speed_up and abs(angle) < 0.25 and distance > 800.0,
                       handbrake=1.3 < abs(angle) < 2.2)


class ScriptedBot(ABC):
    name = "scripted"

    @abstractmethod
    def act(self, agent: str, state: GameState) -> CarControls:
        """Controls for ``agent`` this decision."""


class BallChaser(ScriptedBot):
    """Drives through the ball towards the opponent goal, jumps at balls in reach above the car."""

    name = "ball_chaser"

    def act(self, agent: str, state: GameState) -> CarControls:
        car = state.cars[agent]
        if car.is_demoed:
            return CarControls()
        pos, rot = team_frame(agent, car.pos), _team_rot(agent, car.rot_mat)
        ball = team_frame(agent, state.ball.pos)
        ball_vel = team_frame(agent, state.ball.vel)
        lead = ball + ball_vel * min(np.linalg.norm(ball - pos) / 2000.0, 0.6)
        to_goal = ATTACK_GOAL - lead
        approach = lead - to_goal / np.linalg.norm(to_goal) * 110.0  # aim behind the ball, on the goal line
        if pos[1] > ball[1] + 150.0:
            approach = lead + np.array([0.0, -400.0, 0.0])  # get back goal-side of the ball first
        controls = drive_to(pos, rot, np.array([approach[0], approach[1], 0.0]))
        near = np.linalg.norm((ball - pos)[:2]) < 350.0
        if near and 200.0 < ball[2] < 420.0 and car.on_ground:
            controls = CarControls(throttle=controls.throttle, steer=controls.steer, jump=True)
        return controls


class Goalie(ScriptedBot):
    """Keeps between ball and own goal; clears the ball when it comes into the defensive third."""

    name = "goalie"

    def act(self, agent: str, state: GameState) -> CarControls:
        car = state.cars[agent]
        if car.is_demoed:
            return CarControls()
        pos, rot = team_frame(agent, car.pos), _team_rot(agent, car.rot_mat)
        ball = team_frame(agent, state.ball.pos)
        if ball[1] < -C.ARENA_EXTENT_Y / 3:
            return BallChaser().act(agent, state)
        post = np.array([np.clip(ball[0] * 0.4, -700.0, 700.0), OWN_GOAL[1] + 250.0, 0.0])
        controls = drive_to(pos, rot, post, speed_up=np.linalg.norm(post - pos) > 2500.0, arrive_uu=120.0)
        if np.linalg.norm(post - pos) < 250.0:  # in position: turn to face the ball
            local = rot.T @ (ball - pos)
            controls = CarControls(throttle=0.0, steer=float(np.clip(2.0 * math.atan2(local[1], local[0]), -1, 1)))
        return controls


class Idle(ScriptedBot):
    """Does nothing: an empty net for shooting practice."""

    name = "idle"

    def act(self, agent: str, state: GameState) -> CarControls:
        return CarControls()


def _team_rot(agent: str, rot: np.ndarray) -> np.ndarray:
    return rot if agent_team(agent) == 0 else np.diag([-1.0, -1.0, 1.0]) @ rot


SCRIPTED_BOTS: dict[str, type[ScriptedBot]] = {cls.name: cls for cls in (BallChaser, Goalie, Idle)}


def make_scripted(name: str) -> ScriptedBot:
    try:
        return SCRIPTED_BOTS[name]()
    except KeyError:
        raise ValueError(f"bot: unknown scripted bot {name!r}; allowed: {sorted(SCRIPTED_BOTS)}") from None
