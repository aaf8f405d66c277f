"""Scripted shooters for the minigames: teachers for imitation and kickstarting, and baselines for learned policies.

``BarrierShooter`` plays the Barrier free kick. A chip over the standing 300 uu wall is out of reach of a
single touch on a ball at rest (the search that showed it: docs/experiments/index.md). So the shooter plays the
ball *under* a lifted barrier (a soft ground shot, so it stays below the bottom edge) and *around* a standing one (it dribbles the ball to a point beside the nearer end, then shoots
from there). It works out from the state alone, every decision, which of these it is doing, so one instance
plays any number of cars and episodes (as a kickstart teacher must).

It drives with throttle, steer, boost and handbrake only: the five ``drive`` actions express all of it,
as do RLGym's continuous controls. It reads the car's and the ball's positions and velocities and the
barrier's box: all in the ``barrier_sensors+team_relative`` observation (the general sensors lack the ball's
velocity).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import GameState, Obstacle

from .scripted import ScriptedBot, team_frame

GOAL_LINE_Y = C.ARENA_EXTENT_Y
#: a car's centre is this far behind the ball's centre when its nose touches it
CONTACT_UU = 160.0
#: the half width of a car, with room for error: how far a car's path keeps from a barrier's end
CAR_CLEARANCE_UU = 150.0
#: how hard the car can slow down (uu/s^2, braking is ~3500): plans its speed into the touch
PLAN_DECEL_UU_S2 = 1800.0
#: approach geometry (``approach``): the merge cone (how far behind the contact point anything goes, and how
#: wide it opens), the merge field's length scale and steepest angle, on the line (offset and angle), how wide
#: of the ball's line a car ahead of it stays, and how far ahead along the field the car steers
MERGE_BACK_UU = 800.0
MERGE_SLOPE = 0.8
MERGE_LENGTH_UU = 300.0
MERGE_ANGLE_RAD = 1.05
ON_LINE_UU = 40.0
LINED_UP_RAD = 0.3
CLEAR_UU = 400.0
LOOK_AHEAD_UU = 300.0
MAX_SPEED_UU_S = 2300.0
#: a car's tightest turn (curvature, 1/uu) at each forward speed (uu/s): Rocket League's steering table
TURN_SPEEDS_UU_S = np.array([0.0, 500.0, 1000.0, 1500.0, 1750.0, 2300.0])
TURN_CURVATURES = np.array([0.0069, 0.00398, 0.00235, 0.001375, 0.0011, 0.00088])


def turning_speed(radius_uu: float) -> float:
    """The highest speed (uu/s) at which a car can still turn on a circle of ``radius_uu``."""
    return float(np.interp(1.0 / max(radius_uu, 1e-6), TURN_CURVATURES[::-1], TURN_SPEEDS_UU_S[::-1]))


def heading_error(pos: np.ndarray, rot: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """The angle (rad; the sign of the steer that turns towards it) and distance (uu) from the car to the floor
    point ``target``, in the car's own frame."""
    local = rot.T @ (np.array([target[0], target[1], pos[2]]) - pos)
    return math.atan2(local[1], local[0]), float(math.hypot(local[0], local[1]))


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-9 else np.array([0.0, 1.0])


def _team_rot(agent: str, rot: np.ndarray) -> np.ndarray:
    return team_frame(agent, np.eye(3)) @ rot


@dataclass(frozen=True, eq=False)
class CarView:
    """One car and the ball in the car's team frame (every bot attacks +y): positions and velocities (uu,
    uu/s), the car's rotation matrix and its forward speed."""
    pos: np.ndarray
    rot: np.ndarray
    speed: float
    ball: np.ndarray
    ball_vel: np.ndarray

    @staticmethod
    def of(agent: str, state: GameState) -> CarView | None:
        """``agent``'s view; None while its car is demolished."""
        car = state.cars[agent]
        if car.is_demoed:
            return None
        rot = _team_rot(agent, car.rot_mat)
        return CarView(team_frame(agent, car.pos), rot, float(team_frame(agent, car.vel) @ rot[:, 0]),
                        team_frame(agent, state.ball.pos), team_frame(agent, state.ball.vel))


def _barrier(agent: str, state: GameState) -> Obstacle | None:
    """The first obstacle in the agent's team frame (its centre mirrored; boxes are axis-aligned)."""
    if not state.obstacles:
        return None
    box = state.obstacles[0]
    return Obstacle(center=team_frame(agent, np.asarray(box.center, float)), half_extents=np.asarray(box.half_extents))


def segment_hits_box(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """Does the floor segment a -> b (xy) cross the rectangle [lo, hi] (xy)? Slab test."""
    t0, t1 = 0.0, 1.0
    d = b - a
    for k in range(2):
        if abs(d[k]) < 1e-9:
            if not lo[k] <= a[k] <= hi[k]:
                return False
            continue
        u0, u1 = (lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]
        t0, t1 = max(t0, min(u0, u1)), min(t1, max(u0, u1))
        if t0 > t1:
            return False
    return True


def _rotate(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


@dataclass(frozen=True, eq=False)
class Approach:
    """Where to drive now to meet the ball square, and how fast at most: ``waypoint`` (floor xy),
    ``speed_cap`` (uu/s) and ``on_line`` (the car is on the shot's line, facing along it)."""
    waypoint: np.ndarray
    speed_cap: float
    on_line: bool


def approach(car_xy: np.ndarray, facing: np.ndarray, speed: float, ball_xy: np.ndarray,
             direction: np.ndarray) -> Approach:
    """A heading field onto the shot's line (through the ball's centre along the unit floor vector
    ``direction``) that meets the ball square, whatever side the car comes from.

    In the *merge cone* behind the contact point (``MERGE_BACK_UU`` behind it, or within ``MERGE_SLOPE`` times
    the distance behind it of the line) the field points along the line turned towards it by
    ``atan(offset / MERGE_LENGTH_UU)``, at most ``MERGE_ANGLE_RAD``: a car following it runs onto the line and
    along it into the ball. Level with or ahead of the ball and within ``CLEAR_UU`` of its line, the field
    points out sideways (the car's own side); wider of the ball's line the car drives to the cone's far end.
    The car follows the field by steering at a point ahead along it; on the line and facing along it there is
    no speed limit but the touch's, elsewhere the limit is the speed at which it can turn on a circle of
    ``MERGE_LENGTH_UU``.
    """
    normal = np.array([direction[1], -direction[0]])  # the line's right-hand side
    rel = car_xy - (ball_xy - direction * CONTACT_UU)
    along, lateral = float(rel @ direction), float(rel @ normal)
    side = 1.0 if lateral >= 0.0 else -1.0
    if along < -MERGE_BACK_UU or (along < 0.0 and abs(lateral) < ON_LINE_UU + MERGE_SLOPE * -along):
        turn = float(np.clip(math.atan(lateral / MERGE_LENGTH_UU), -MERGE_ANGLE_RAD, MERGE_ANGLE_RAD))
        heading = _rotate(direction, turn)
        on_line = abs(lateral) < ON_LINE_UU and facing @ direction > math.cos(LINED_UP_RAD)
        # the field's paths curve with a radius of about MERGE_LENGTH_UU near the line, straighter further out;
        # facing far off the field, the car must turn hard onto it first
        off_field = math.acos(float(np.clip(facing @ heading, -1.0, 1.0)))
        radius = MERGE_LENGTH_UU + abs(lateral) if off_field < 0.5 else LOOK_AHEAD_UU / (2.0 * math.sin(min(off_field, 1.57)))
        cap = MAX_SPEED_UU_S if on_line else turning_speed(radius)
        return Approach(car_xy + heading * LOOK_AHEAD_UU, cap, on_line)
    if abs(lateral) < CLEAR_UU and along > -CONTACT_UU:  # by the ball or ahead of it: out to the side first
        heading = _unit(normal * side - direction * (0.0 if along > 0.0 else 1.0))
    else:  # wide of the ball's line: to the cone's far end
        return Approach(ball_xy - direction * (CONTACT_UU + MERGE_BACK_UU), MAX_SPEED_UU_S, False)
    return Approach(car_xy + heading * LOOK_AHEAD_UU, MAX_SPEED_UU_S, False)


class ShotKind(Enum):
    GOAL = "goal"          # at the goal (nothing in the way, or a line beside the barrier)
    UNDER = "under"        # at the goal under a lifted barrier: a soft touch keeps the ball on the floor
    DRIBBLE = "dribble"    # to the point beside a standing barrier's end, pushed a little faster than it rolls


@dataclass(frozen=True, eq=False)
class Shot:
    """Where to send the ball (floor xy), the car's speed at the touch (uu/s) and what kind of shot it is."""
    target: np.ndarray
    touch_speed_uu_s: float
    kind: ShotKind


class BarrierShooter(ScriptedBot):
    """Scores the Barrier free kick: under a lifted barrier with a soft ground shot, around a standing one.

    Each decision it picks a **shot** (``shot``) for where it will meet the ball (``intercept``: the first
    point of the ball's rolling path the car can reach in time):

    - the ball is beyond the barrier: at the goal (full speed, softer near the goal so the ball stays under the
      crossbar);
    - the barrier is lifted above a rolling ball (bottom edge more than ``LIFT_MARGIN_UU`` above it): at the
      goal with the car at ``UNDER_SPEED_UU_S`` at the touch, so the ball hops no higher than ~10 uu;
    - a line to some point of the goal mouth passes beside the barrier: along it, at full speed;
    - else: a dribble to the point ``PASS_CLEARANCE_UU`` out from the barrier end that makes the shorter way to
      the goal, starting at ``DRIBBLE_SPEED_UU_S`` and pushing ``DRIBBLE_PUSH_UU_S`` faster than the ball rolls;
      beside the end, the line to the goal is clear and the third rule shoots.

    The car meets a ball at rest (or slow) square on the shot's line (``approach``), slowing in time to touch
    it at the shot's speed; a rolling ball it chases straight, aiming the touch so the ball leaves along the
    shot's line; a standing barrier in the way it drives round by the nearer end, and backs off it when stuck.
    """

    bot_name = "barrier_shooter"
    UNDER_SPEED_UU_S = 700.0
    DRIBBLE_SPEED_UU_S = 600.0     # the car's speed at the touch that starts a dribble round a standing barrier,
    DRIBBLE_PUSH_UU_S = 200.0      # then this much faster than the ball rolls,
    DRIBBLE_MAX_UU_S = 800.0       # up to this
    FULL_SPEED_UU_S = 2300.0
    NEAR_GOAL_UU = 1500.0          # nearer the goal line than this, shots are softer
    NEAR_GOAL_SPEED_UU_S = 1400.0
    LIFT_MARGIN_UU = 20.0
    PASS_CLEARANCE_UU = 200.0      # ball centre to the barrier's end, as it passes
    GOAL_AIM_X_UU = (0.0, -350.0, 350.0, -600.0, 600.0)  # goal-line points tried, first clear one wins
    CAR_PASSES_UNDER_UU = 100.0    # a barrier lifted this high lets the car drive under it
    INTERCEPT_HORIZON_S = 3.0      # how far ahead the car plans to meet a rolling ball
    INTERCEPT_SPEED_UU_S = 1200.0  # the car's average speed on the way to the ball, for that plan
    ROLL_DECEL_UU_S2 = 20.0        # a rolling ball slows by about this much (after its first bounces)
    SHOT_SPEED_UU_S = 1800.0       # about how fast a shot at a rolling ball leaves
    ROLLING_UU_S = 300.0           # a ball rolling faster than this is chased straight at, not approached round
    MIN_SPEED_UU_S = 300.0         # the turn-speed limit never stops the car
    SETTLE_UU = 300.0              # the car is at the touch speed this far before the touch

    def controls(self, agent: str, state: GameState) -> CarControls:
        view = CarView.of(agent, state)
        if view is None:
            return CarControls()
        pos, rot, speed, ball, ball_vel = view.pos, view.rot, view.speed, view.ball, view.ball_vel
        barrier = _barrier(agent, state)
        if self.blocked(pos, rot, speed, barrier):  # nose against a standing barrier: back off it
            return CarControls(throttle=-1.0)
        lead, shot = self.intercept(pos[:2], ball[:2], ball_vel[:2], barrier)
        ball_distance = float(np.linalg.norm(lead - pos[:2]))
        direction = _unit(shot.target - lead)
        touch_speed = shot.touch_speed_uu_s
        if shot.kind is ShotKind.DRIBBLE:  # keep pushing a rolling ball: a little faster than it rolls
            touch_speed = min(max(float(ball_vel[:2] @ direction) + self.DRIBBLE_PUSH_UU_S, touch_speed),
                              self.DRIBBLE_MAX_UU_S)
        elif float(np.linalg.norm(ball_vel[:2])) > self.ROLLING_UU_S:
            # a rolling ball: chase the contact point straight (as the flip-chaser does); there is no time to go
            # round into the merge cone before it rolls away
            near = ball[:2] + ball_vel[:2] * min(float(np.linalg.norm(ball[:2] - pos[:2])) / 2000.0, 0.6)
            shot = self.shot(near, barrier)
            # the touch adds velocity along its normal: aim it at the velocity the ball should have minus the one
            # it has, so a ball rolling across the shot's line leaves along it
            impulse = _unit(_unit(shot.target - near) * self.SHOT_SPEED_UU_S - ball_vel[:2])
            waypoint = self.detour(pos[:2], near - impulse * CONTACT_UU * 0.7, barrier)
            return self.drive(pos, rot, speed, waypoint, ball_distance, shot.touch_speed_uu_s, MAX_SPEED_UU_S)
        if self.walled_off(pos[:2], lead, barrier):
            waypoint = self.detour(pos[:2], lead - direction * (CONTACT_UU + MERGE_BACK_UU), barrier)
            cap = MAX_SPEED_UU_S
        else:
            plan = approach(pos[:2], _unit(rot[:2, 0]), speed, lead, direction)
            waypoint, cap = self.detour(pos[:2], plan.waypoint, barrier), plan.speed_cap
        return self.drive(pos, rot, speed, waypoint, ball_distance, touch_speed, cap)

    def intercept(self, car_xy: np.ndarray, ball_xy: np.ndarray, ball_vel: np.ndarray,
                  barrier: Obstacle | None) -> tuple[np.ndarray, Shot]:
        """Where the car meets the ball, and the shot from there: the first point of the ball's rolling path
        (straight on, slowing by ``ROLL_DECEL_UU_S2``) whose contact point the car reaches by then at
        ``INTERCEPT_SPEED_UU_S`` on average (the ball itself, when it is at rest)."""
        speed = float(np.linalg.norm(ball_vel))
        if speed <= 1.0:
            return ball_xy, self.shot(ball_xy, barrier)
        heading = ball_vel / speed
        stop_distance = min(speed ** 2 / (2.0 * self.ROLL_DECEL_UU_S2), speed * self.INTERCEPT_HORIZON_S)
        for t in np.arange(0.0, self.INTERCEPT_HORIZON_S, 0.05):
            travelled = min(max(speed * t - 0.5 * self.ROLL_DECEL_UU_S2 * t * t, 0.0), stop_distance)
            point = np.clip(ball_xy + heading * travelled,
                            [-C.ARENA_EXTENT_X + C.BALL_RADIUS, -C.ARENA_EXTENT_Y + C.BALL_RADIUS],
                            [C.ARENA_EXTENT_X - C.BALL_RADIUS, C.ARENA_EXTENT_Y - C.BALL_RADIUS])
            shot = self.shot(point, barrier)
            contact = point - _unit(shot.target - point) * CONTACT_UU
            if float(np.linalg.norm(contact - car_xy)) / self.INTERCEPT_SPEED_UU_S <= t:
                break
        return point, shot

    def walled_off(self, car_xy: np.ndarray, ball_xy: np.ndarray, barrier: Obstacle | None) -> bool:
        """A standing barrier stands between the car and the ball."""
        if barrier is None:
            return False
        lo, hi = barrier.center - barrier.half_extents, barrier.center + barrier.half_extents
        return lo[2] <= self.CAR_PASSES_UNDER_UU and segment_hits_box(car_xy, ball_xy, lo[:2] - 60.0, hi[:2] + 60.0)

    def blocked(self, pos: np.ndarray, rot: np.ndarray, speed: float, barrier: Obstacle | None) -> bool:
        """Nearly stopped with the nose against a standing barrier."""
        if barrier is None or abs(speed) > 150.0:
            return False
        lo, hi = barrier.center - barrier.half_extents, barrier.center + barrier.half_extents
        nose = pos[:2] + rot[:2, 0] * 110.0
        return lo[2] <= self.CAR_PASSES_UNDER_UU and bool(np.all(nose > lo[:2] - 40.0) and np.all(nose < hi[:2] + 40.0))

    # ------------------------------------------------------------------ what to do with the ball
    def shot(self, ball_xy: np.ndarray, barrier: Obstacle | None) -> Shot:
        """What to do with a ball at ``ball_xy`` (the rules in the class docstring, in order)."""
        goal = np.array([0.0, GOAL_LINE_Y + 200.0])
        if barrier is None:
            return Shot(goal, self.final_speed(ball_xy), ShotKind.GOAL)
        lo, hi = barrier.center - barrier.half_extents, barrier.center + barrier.half_extents
        if ball_xy[1] - C.BALL_RADIUS > hi[1]:
            return Shot(goal, self.final_speed(ball_xy), ShotKind.GOAL)
        if lo[2] > 2.0 * C.BALL_RADIUS + self.LIFT_MARGIN_UU:
            return Shot(goal, self.UNDER_SPEED_UU_S, ShotKind.UNDER)
        grown_lo, grown_hi = lo[:2] - C.BALL_RADIUS - 40.0, hi[:2] + C.BALL_RADIUS + 40.0
        for x in self.GOAL_AIM_X_UU:
            aim = np.array([x, GOAL_LINE_Y + 200.0])
            if not segment_hits_box(ball_xy, aim, grown_lo, grown_hi):
                return Shot(aim, self.FULL_SPEED_UU_S, ShotKind.GOAL)
        return Shot(self.corner(ball_xy, lo, hi, goal), self.DRIBBLE_SPEED_UU_S, ShotKind.DRIBBLE)

    def corner(self, ball_xy: np.ndarray, lo: np.ndarray, hi: np.ndarray, goal: np.ndarray) -> np.ndarray:
        """The point beside the barrier's near face, ``PASS_CLEARANCE_UU`` out from an end, to dribble the ball to
        (from there the way to the goal is clear): the end that makes the shorter way from the ball to the goal."""
        corners = [np.array([hi[0] + self.PASS_CLEARANCE_UU, lo[1]]), np.array([lo[0] - self.PASS_CLEARANCE_UU, lo[1]])]
        corners = [c for c in corners if abs(c[0]) < C.ARENA_EXTENT_X - 500.0] or corners
        return min(corners, key=lambda c: float(np.linalg.norm(c - ball_xy) + np.linalg.norm(goal - c)))

    def final_speed(self, ball_xy: np.ndarray) -> float:
        """The touch speed of a shot at the goal: full speed from afar; near the goal a full-speed hit lifts the
        ball over the crossbar."""
        return self.FULL_SPEED_UU_S if GOAL_LINE_Y - ball_xy[1] > self.NEAR_GOAL_UU else self.NEAR_GOAL_SPEED_UU_S

    # ------------------------------------------------------------------ how the car gets there
    def detour(self, car_xy: np.ndarray, waypoint: np.ndarray, barrier: Obstacle | None) -> np.ndarray:
        """A standing barrier between the car and its waypoint: round its end nearer the two, by the corner on
        the car's side first, then (once the car is out beside the end) the corner on the far side."""
        if barrier is None:
            return waypoint
        lo, hi = barrier.center - barrier.half_extents, barrier.center + barrier.half_extents
        if lo[2] > self.CAR_PASSES_UNDER_UU:
            return waypoint
        margin = CAR_CLEARANCE_UU
        if not segment_hits_box(car_xy, waypoint, lo[:2] - margin + 30.0, hi[:2] + margin - 30.0):
            return waypoint
        ends = {1.0: hi[0] + margin + 60.0, -1.0: lo[0] - margin - 60.0}
        side = min(ends, key=lambda s: abs(ends[s] - car_xy[0]) + abs(ends[s] - waypoint[0]))
        below = car_xy[1] < barrier.center[1]
        near_y, far_y = (lo[1] - margin, hi[1] + margin) if below else (hi[1] + margin, lo[1] - margin)
        beside = side * (car_xy[0] - ends[side]) > -60.0  # out beyond that end already
        return np.array([ends[side], far_y if beside else near_y])

    def drive(self, pos: np.ndarray, rot: np.ndarray, speed: float, waypoint: np.ndarray, ball_distance: float,
              touch_speed: float, speed_cap: float) -> CarControls:
        """Steer at ``waypoint``; throttle, boost and brake so the car is at ``touch_speed`` ``SETTLE_UU`` before
        the ball, and never faster than ``speed_cap`` (at least ``MIN_SPEED_UU_S``)."""
        angle, _ = heading_error(pos, rot, waypoint)
        steer = float(np.clip(3.0 * angle, -1.0, 1.0))
        # reach the touch speed SETTLE_UU before the touch and hold it there: braking into the ball pitches the
        # nose down, and a nose-down car lifts the ball more
        allowed = math.sqrt(touch_speed ** 2 + 2.0 * PLAN_DECEL_UU_S2 *
                            max(ball_distance - CONTACT_UU - self.SETTLE_UU, 0.0))
        allowed = min(allowed, max(speed_cap, self.MIN_SPEED_UU_S))
        if speed > allowed + (300.0 if ball_distance < CONTACT_UU + self.SETTLE_UU else 100.0):
            throttle = -1.0 if speed > 0.0 else 0.0
        elif speed > allowed - 30.0:
            throttle = 0.0
        else:
            throttle = 1.0
        boost = throttle > 0.0 and abs(angle) < 0.25 and speed < allowed - 250.0 and speed < 2200.0
        handbrake = 1.3 < abs(angle) < 2.4 and speed > 400.0
        return CarControls(throttle=throttle, steer=steer, boost=boost, handbrake=handbrake)
