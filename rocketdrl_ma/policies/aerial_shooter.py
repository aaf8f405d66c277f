"""A scripted shooter for the Aerial minigame: it flies into the hanging ball and knocks it at the goal.

The plan is RLBot's boost aerial. Every decision the bot asks: if the car thrusts along one fixed direction from
now on, at which time ``T`` does it meet the contact point ``c(T)`` (the ball's predicted centre, moved back from
the shot's line by the car's reach)? ``p + v T + (g + a) T^2 / 2 = c(T)`` gives the thrust ``a``; the first ``T``
on a grid at which ``|a|`` is within what boost gives is the plan. On the ground the car drives onto the shot's
line (``approach``) and takes off when the plan with the jump's lift is in reach and it faces the contact
point; in the air it points the nose along ``a`` (a PD controller on pitch and yaw, the roof kept up) and boosts
while the nose is on it. Re-planned every decision, the thrust corrects the flight as it goes. The contact point
is behind the ball on its line to the goal, so the car's nose meets the ball from behind and sends it there.

It is stateless and reads only what ``aerial_sensors+team_relative`` shows a learner: the car's and the ball's
positions, velocities, orientation and angular velocity, the car's height and jump state, and the release
countdown (``mode_state``). It needs pitch, yaw and roll, so it plays through the continuous actions (RLGym's
lookup table snaps its stick), not the five ``drive`` actions. Its score at difficulty 1: `rocketdrl-ma eval
scripted:aerial_shooter --env minigames/aerial.yaml --episodes 200` (the figures: docs/experiments/index.md).
"""
from __future__ import annotations

import math

import numpy as np

from rocketdrl_ma.physics import CarControls, CarState
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import GameState

from .minigame_bots import CarView, _unit, approach, heading_error
from .scripted import ScriptedBot, team_frame

GRAVITY = np.array([0.0, 0.0, C.GRAVITY_Z])


class AerialShooter(ScriptedBot):
    """Scores the Aerial minigame's hanging ball with a boost aerial (module docstring)."""

    bot_name = "aerial_shooter"
    #: where the shot goes: beyond the goal line's centre, low (the rising car lifts the ball as it hits it)
    AIM = np.array([0.0, C.ARENA_EXTENT_Y + 200.0, 150.0])
    #: car centre to ball centre at the touch (uu)
    REACH_UU = 150.0
    #: the plan's times (s): the grid of candidate ``T``
    PLAN_TIMES_S = np.arange(0.1, 3.0, 1.0 / 60.0)
    #: the thrust the plan may ask for (uu/s^2), below boost's 1058 so the nose has slack to steer it; at take-off
    #: less, as the nose still has to come up
    PLAN_ACCEL_UU_S2, TAKEOFF_ACCEL_UU_S2 = 850.0, 650.0
    #: the vertical speed the jump, its hold and the double jump add, for the take-off plan (uu/s)
    JUMP_LIFT_UU_S = 700.0
    #: take off only this well lined up on the contact point (rad)
    TAKEOFF_ANGLE_RAD = 0.25
    #: the car's height (uu) at which it lets go of the first jump, and presses it again for the double jump
    RELEASE_JUMP_Z_UU, DOUBLE_JUMP_Z_UU = 90.0, 125.0
    #: boost while the nose is within this of the thrust's direction (rad)
    BOOST_ANGLE_RAD = 0.5
    #: the orientation controller's gains: per rad of error, per rad/s of rate (pitch and yaw; roll)
    KP, KD = 4.0, 0.6
    ROLL_KP, ROLL_KD = 2.0, 0.3

    def controls(self, agent: str, state: GameState) -> CarControls:
        view = CarView.of(agent, state)
        if view is None:
            return CarControls()
        car = state.cars[agent]
        frozen = state.mode_state.get("ball_frozen", False)
        release_in_s = float(state.mode_state.get("release_in_s", 0.0)) if frozen else None
        vel = team_frame(agent, car.vel)
        if car.on_ground:
            return self.ground(view, vel, release_in_s)
        return self.air(car, view, vel, release_in_s)

    def contacts(self, view: CarView, times_s: np.ndarray, release_in_s: float | None) -> np.ndarray:
        """The contact point at each of ``times_s`` (rows): the ball hanging until its release (``release_in_s``
        None: already free), then falling (the floor ignored), less the reach along its line to ``AIM``."""
        t = times_s[:, None]
        if release_in_s is not None:
            fall = np.maximum(t - release_in_s, 0.0)
            ball = view.ball + 0.5 * GRAVITY * fall * fall
        else:
            ball = view.ball + view.ball_vel * t + 0.5 * GRAVITY * t * t
        to_aim = self.AIM - ball
        return ball - to_aim / np.linalg.norm(to_aim, axis=1, keepdims=True) * self.REACH_UU

    def plan(self, pos: np.ndarray, vel: np.ndarray, view: CarView, release_in_s: float | None,
             accel_uu_s2: float) -> tuple[float, np.ndarray, bool]:
        """(T, thrust, reachable): the first plan time at which the thrust that meets the contact point is within
        ``accel_uu_s2``; if none is, the time that needs the least thrust, and ``reachable`` False."""
        t = self.PLAN_TIMES_S[:, None]
        thrust = 2.0 * (self.contacts(view, self.PLAN_TIMES_S, release_in_s) - pos - vel * t) / (t * t) - GRAVITY
        norm = np.linalg.norm(thrust, axis=1)
        within = np.flatnonzero(norm <= accel_uu_s2)
        k = int(within[0]) if within.size else int(np.argmin(norm))
        return float(self.PLAN_TIMES_S[k]), thrust[k], bool(within.size)

    def ground(self, view: CarView, vel: np.ndarray, release_in_s: float | None) -> CarControls:
        """Take off when the aerial is in reach and the car faces the contact point; else drive onto the shot's
        line behind it at full speed."""
        lifted = vel + np.array([0.0, 0.0, self.JUMP_LIFT_UU_S])
        t, _, reachable = self.plan(view.pos, lifted, view, release_in_s, self.TAKEOFF_ACCEL_UU_S2)
        contact = self.contacts(view, np.array([t]), release_in_s)[0]
        angle, _ = heading_error(view.pos, view.rot, contact)
        if reachable and abs(angle) < self.TAKEOFF_ANGLE_RAD:
            return CarControls(throttle=1.0, jump=True, boost=True)
        direction = _unit(self.AIM[:2] - contact[:2])
        # approach() lines the car up on a ball at its argument: the contact point is a reach behind the ball
        plan = approach(view.pos[:2], _unit(view.rot[:2, 0]), view.speed, contact[:2] + direction * self.REACH_UU,
                        direction)
        angle, _ = heading_error(view.pos, view.rot, plan.waypoint)
        fast = view.speed < min(plan.speed_cap, 2250.0)
        return CarControls(throttle=1.0 if fast else 0.0, steer=float(np.clip(3.0 * angle, -1.0, 1.0)),
                           boost=fast and abs(angle) < 0.3, handbrake=1.3 < abs(angle) < 2.4 and view.speed > 400.0)

    def air(self, car: CarState, view: CarView, vel: np.ndarray, release_in_s: float | None) -> CarControls:
        """Nose along the plan's thrust, boost while it is on it; the jump's hold and the double jump first."""
        _, thrust, _ = self.plan(view.pos, vel, view, release_in_s, self.PLAN_ACCEL_UU_S2)
        pitch, yaw, roll = self.orient(car, view.rot, thrust)
        boost = float(view.rot[:, 0] @ thrust) > math.cos(self.BOOST_ANGLE_RAD) * float(np.linalg.norm(thrust))
        if car.has_jumped and not car.has_double_jumped and not car.has_flipped:
            # sequenced by the car's height, which a learner sees (the time since the jump it does not): hold the
            # first jump, let go, then press again without stick (with stick the press is a dodge)
            if view.pos[2] >= self.DOUBLE_JUMP_Z_UU:
                return CarControls(jump=True, boost=boost)
            return CarControls(pitch=pitch, yaw=yaw, roll=roll, boost=boost,
                               jump=car.is_jumping and view.pos[2] < self.RELEASE_JUMP_Z_UU)
        return CarControls(pitch=pitch, yaw=yaw, roll=roll, boost=boost)

    def orient(self, car: CarState, rot: np.ndarray, direction: np.ndarray) -> tuple[float, float, float]:
        """Pitch, yaw and roll that turn the nose towards ``direction`` and keep the roof up (``rot``: the car's
        rotation in the team frame). The controls' signs, measured: pitch +1 lifts the nose (the rate about the
        car's second axis goes negative), yaw +1 turns it towards the second axis, roll +1 turns the roof
        towards it (the rate about the forward axis goes negative)."""
        local = rot.T @ direction
        # the team frame is the world turned about z, which leaves the car's own rates as they are
        rates = car.rot_mat.T @ car.ang_vel
        pitch = self.KP * math.atan2(local[2], local[0]) + self.KD * rates[1]
        yaw = self.KP * math.atan2(local[1], local[0]) - self.KD * rates[2]
        roll = self.ROLL_KP * math.atan2(rot[2, 1], rot[2, 2]) + self.ROLL_KD * rates[0]
        return tuple(float(np.clip(x, -1.0, 1.0)) for x in (pitch, yaw, roll))
