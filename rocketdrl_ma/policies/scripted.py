"""Scripted bots: a ball-chaser, a stronger flip-chaser and a goalie, opponents and baselines for learned policies.

They see the game the way the team-relative observation shows it to an agent (own car, ball, goals,
all in the agent's team frame) and answer with ``CarControls``; nothing they use is hidden from a
learning agent with the full-state observation.
"""
from __future__ import annotations

import math
from abc import abstractmethod
from typing import Any, ClassVar

import numpy as np

from rocketdrl_ma.physics import CarControls, CarState
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.frames import rot_to_team_frame, to_team_frame
from rocketdrl_ma.rules.state import GameState, agent_team
from rocketdrl_ma.validation import check_name

from .base import Policy
from . import rotation, saves
from .rotation import Role
from .rotator_tuning import RotatorTuning, shipped_tuning

ATTACK_GOAL = np.array([0.0, C.ARENA_EXTENT_Y + 200.0, 0.0])  # in the team frame: always +y
OWN_GOAL = np.array([0.0, -C.ARENA_EXTENT_Y, 0.0])
# drive_to's rules, also the flip-chaser's: reverse to a target behind and near, boost at one ahead and far,
# powerslide through the turns between
REVERSE_ANGLE_RAD, REVERSE_WITHIN_UU = 2.2, 1500.0
BOOST_ANGLE_RAD, BOOST_BEYOND_UU = 0.25, 800.0
SLIDE_ANGLE_RAD = 1.3


def team_frame(agent: str, vec: np.ndarray) -> np.ndarray:
    """Orange sees the field turned half a circle (x -> -x, y -> -y) so every bot attacks +y."""
    return to_team_frame(agent_team(agent), vec)


def drive_to(car_pos: np.ndarray, car_rot: np.ndarray, target: np.ndarray, speed_up: bool = True,
             arrive_uu: float = 0.0) -> CarControls:
    """Steer at ``target`` on the floor; boost when facing it and far; powerslide through sharp turns."""
    angle, distance = _angle_distance(car_pos, car_rot, target)
    steer = float(np.clip(3.0 * angle, -1.0, 1.0))
    if distance < arrive_uu:
        return CarControls(throttle=0.0, steer=steer)
    throttle = 1.0 if abs(angle) < REVERSE_ANGLE_RAD or distance > REVERSE_WITHIN_UU else -1.0
    if throttle < 0.0:
        steer = -steer
    return CarControls(throttle=throttle, steer=steer,
                       boost=speed_up and abs(angle) < BOOST_ANGLE_RAD and distance > BOOST_BEYOND_UU,
                       handbrake=SLIDE_ANGLE_RAD < abs(angle) < REVERSE_ANGLE_RAD)


#: every scripted bot class by its ``bot_name``: a subclass of ``ScriptedBot`` that sets ``bot_name`` registers
#: itself as it is defined, wherever it lives. The package imports every module of shipped bots
#: (``policies/__init__.py``), so all of them are here whichever module of the package was imported first.
SCRIPTED_BOTS: dict[str, type[ScriptedBot]] = {}


class ScriptedBot(Policy):
    """A hand-written policy; ``bot_name`` is what ``scripted:<bot_name>`` names it by. Defining a subclass with
    its own ``bot_name`` registers it (``SCRIPTED_BOTS``): ``load_policy("scripted:<bot_name>")``, leagues,
    self-play pools and teachers find it by that name."""

    bot_name: ClassVar[str] = "scripted"

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "bot_name" not in cls.__dict__:  # a base for other bots, or a variant of one: not a bot of its own
            return
        check_name("bot_name", cls.bot_name)
        taken = SCRIPTED_BOTS.get(cls.bot_name)
        if taken is not None and (taken.__module__, taken.__qualname__) != (cls.__module__, cls.__qualname__):
            raise ValueError(f"bot_name: {cls.bot_name!r} is taken by {taken.__module__}.{taken.__qualname__}")
        SCRIPTED_BOTS[cls.bot_name] = cls  # the same class defined again (a module reloaded) replaces itself

    @property
    def name(self) -> str:
        return f"scripted:{self.bot_name}"

    @abstractmethod
    def controls(self, agent: str, state: GameState) -> CarControls:
        """Controls for ``agent`` this decision."""


class BallChaser(ScriptedBot):
    """Drives through the ball towards the opponent goal, jumps at balls in reach above the car."""

    bot_name = "ball_chaser"

    def controls(self, agent: str, state: GameState) -> CarControls:
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

    bot_name = "goalie"

    def controls(self, agent: str, state: GameState) -> CarControls:
        car = state.cars[agent]
        if car.is_demoed:
            return CarControls()
        pos, rot = team_frame(agent, car.pos), _team_rot(agent, car.rot_mat)
        ball = team_frame(agent, state.ball.pos)
        if ball[1] < -C.ARENA_EXTENT_Y / 3:
            return BallChaser().controls(agent, state)
        post = np.array([np.clip(ball[0] * 0.4, -700.0, 700.0), OWN_GOAL[1] + 250.0, 0.0])
        controls = drive_to(pos, rot, post, speed_up=np.linalg.norm(post - pos) > 2500.0, arrive_uu=120.0)
        if np.linalg.norm(post - pos) < 250.0:  # in position: turn to face the ball
            local = rot.T @ (ball - pos)
            controls = CarControls(throttle=0.0, steer=float(np.clip(2.0 * math.atan2(local[1], local[0]), -1, 1)))
        return controls


class FlipChaser(ScriptedBot):
    """The ball-chaser's game with its losing habits fixed, so it beats the ball-chaser, also through the lookup
    table (the matches: docs/experiments/rotator-tuning.md).

    - **Kickoff**: full boost straight at the ball and a forward dodge 0.2 s before contact, so it gets there
      first and faster (the ball-chaser stops boosting 800 uu short of the ball).
    - **From the wrong side** (nearer the opponent's goal than the ball) the ball-chaser aims 400 uu behind the
      ball, through it and at its own goal; this bot aims 250 uu further to the ball's inner side (the field's
      centre, or its own side for a central ball), so a touch on the way back knocks the ball wide.
    - **No jumps at bouncing balls**: the ball-chaser's jump, with a dodge after it, lost matches when tried.
    - **Lookup-table controls**: full steer or none, yaw with steer, throttle with boost, so every control is
      a row of RLGym's 90-row table (``LookupTableActions``); the bot plays the same through it, and a lookup
      clone can copy it exactly.
    - **Never stuck**: it backs off a goal mouth's floor step and the back of a net and leaves a goal mouth
      along y first (the step is the wall ramp's cut face at the posts' line), and jumps off a wall it lies
      against on its side; cars driven by the ball-chaser's rules stood in both places for minutes.

    Stateless: the dodge is sequenced from the car's own jump state (jump held, then released, then pressed
    again with pitch), so one instance plays any number of cars and needs no reset.
    """

    bot_name = "flip_chaser"
    KICKOFF_DODGE_S = 0.2       # time to contact (uu to the ball's surface / speed) at which the kickoff jump starts
    CONTACT_UU = 160.0          # car centre to ball centre at a front touch
    STEER_DEADBAND_RAD = 0.05   # target within this angle: drive straight
    DEFLECT_SIDE_UU, DEFLECT_BACK_UU = 250.0, 400.0

    def controls(self, agent: str, state: GameState) -> CarControls:
        car = state.cars[agent]
        if car.is_demoed:
            return CarControls()
        pos, rot = team_frame(agent, car.pos), _team_rot(agent, car.rot_mat)
        vel = team_frame(agent, car.vel)
        ball, ball_vel = team_frame(agent, state.ball.pos), team_frame(agent, state.ball.vel)
        speed = float(vel @ rot[:, 0])
        kickoff = abs(ball[0]) < 1.0 and abs(ball[1]) < 1.0 and float(np.linalg.norm(ball_vel)) < 1.0
        if _on_its_side_against_a_wall(car):
            return _air_row(jump=True)
        if kickoff and not car.on_ground and car.has_jumped and not car.has_flipped:
            # the dodge needs a fresh press: release the held jump first, then press it with pitch
            return _ground_row(1.0, 0.0) if car.is_jumping else _air_row(pitch=-1.0, jump=True)
        if kickoff:
            return self.kickoff_run(pos, rot, speed, ball)
        lead = ball + ball_vel * min(float(np.linalg.norm(ball - pos)) / 2000.0, 0.6)
        if pos[1] > ball[1] + 150.0:
            inner = math.copysign(1.0, lead[0]) if abs(lead[0]) > 150.0 else -math.copysign(1.0, pos[0] - lead[0])
            target = lead + np.array([-inner * self.DEFLECT_SIDE_UU, -self.DEFLECT_BACK_UU, 0.0])
        else:
            to_goal = ATTACK_GOAL - lead
            target = lead - to_goal / np.linalg.norm(to_goal) * 110.0  # the ball-chaser's shot approach
        return self._drive(pos, rot, _out_of_goal_mouth(pos, target), speed)

    def kickoff_run(self, pos: np.ndarray, rot: np.ndarray, speed: float, aim: np.ndarray) -> CarControls:
        """Full boost at ``aim`` (the ball, or a point beside it), and the jump that starts the dodge into it."""
        angle, distance = _angle_distance(pos, rot, aim)
        if speed > 1200.0 and (distance - self.CONTACT_UU) / speed < self.KICKOFF_DODGE_S:
            return _air_row(jump=True, boost=True)
        return _ground_row(1.0, self._steer(angle), boost=True)

    def _steer(self, angle: float) -> float:
        return 0.0 if abs(angle) < self.STEER_DEADBAND_RAD else math.copysign(1.0, angle)

    def _drive(self, pos: np.ndarray, rot: np.ndarray, target: np.ndarray, speed: float) -> CarControls:
        """``drive_to``'s rules in lookup-table rows; reverses off a step or net it is nosing into."""
        angle, distance = _angle_distance(pos, rot, target)
        steer = self._steer(angle)
        behind_and_near = abs(angle) > REVERSE_ANGLE_RAD and distance < REVERSE_WITHIN_UU
        if (speed < 300.0 and _nose_blocked(pos, rot)) or behind_and_near:
            return _ground_row(-1.0, -steer)
        return _ground_row(1.0, steer, boost=abs(angle) < BOOST_ANGLE_RAD and distance > BOOST_BEYOND_UU,
                           handbrake=SLIDE_ANGLE_RAD < abs(angle) < REVERSE_ANGLE_RAD)


class Rotator(ScriptedBot):
    """A team player that rotates (``rotation.py``): of the two rotating cars, the first man plays the flip-chaser's
    game on the ball, the other follows up (goal-side of the ball, it comes in behind him for the 50-50 and the
    loose ball) or covers the goal; in 3v3 and 4v4 the other cars press, playing the ball as the first man does.
    Roles are worked out afresh from positions every decision, identically by every team-mate. A car on the ball
    dodges into a ground ball it is lined up to shoot (the flip-chaser dodges only at kickoffs): the harder hit
    wins the challenge. A car of any role in the path of a ball heading into its goal that would pass over its roof
    jumps into it (``saves.py``). Cars coming back take boost on the way. Alone on its team (1v1, or team-mates
    demoed) it is the flip-chaser with that dodge. A car of any role standing on its side against a wall jumps off
    it. At a kickoff the second car aims beside the ball, by the kickoff layout (``rotation.kickoff_aim``).
    Stateless, lookup-table rows only (a lookup clone can copy it), one instance plays any number of cars.
    ``tuning``: the searched settings it plays by (default: the shipped ones, ``rotator_tuning.py``).
    """

    bot_name = "rotator"
    ARRIVE_UU = 250.0       # within this of its spot a car stops and turns to face the ball
    BALL_CLEARANCE_UU = 450.0  # a car off the ball keeps its path this far from the ball
    #: the shot dodge: jump when the ball's surface is this many seconds away at the closing speed, which must be
    #: at least this; the ball on the ground, straight ahead, and the car behind it towards the opponents' goal
    DODGE_LEAD_S, DODGE_MIN_CLOSING_UU_S = 0.22, 500.0
    DODGE_MAX_BALL_Z_UU, DODGE_AIM_RAD, DODGE_MIN_SHOT_COS = 160.0, 0.35, 0.5
    #: a car in any role on its side against a wall and slower than this jumps off it (on the ball, the flip-chaser's
    #: rule jumps below 200 uu/s): a covering car that slows on a side wall on its way back drives on down
    STANDING_UU_S = 30.0

    def __init__(self, tuning: RotatorTuning | None = None) -> None:
        self.chaser = FlipChaser()
        self.tuning = shipped_tuning() if tuning is None else tuning

    def controls(self, agent: str, state: GameState) -> CarControls:
        car = state.cars[agent]
        if car.is_demoed:
            return CarControls()
        if _on_its_side_against_a_wall(car, self.STANDING_UU_S):  # every role: no other rule gets a car off there
            return _air_row(jump=True)
        view = rotation.team_view(agent, state)
        if saves.jump_to_save(car.on_ground, car.is_jumping, float(car.rot_mat[2, 2]), view.pos[agent], view.vel[agent],
                              view.ball_pos, view.ball_vel):
            return _air_row(jump=True)
        roles = rotation.assign_roles(view, state.last_touch, self.tuning)
        role = roles.get(agent, Role.FIRST)
        if role is Role.FIRST and car.on_ground and rotation.is_kickoff(view):
            rot = _team_rot(agent, car.rot_mat)
            return self.chaser.kickoff_run(view.pos[agent], rot, float(view.vel[agent] @ rot[:, 0]),
                                           rotation.kickoff_aim(view, agent, self.tuning))
        if role in (Role.FIRST, Role.PRESSER) or rotation.follow_up(view, roles, self.tuning) == agent:
            dodge = self._finish_dodge(agent, state, view) or self._shot_dodge(agent, state, view)
            return dodge or self.chaser.controls(agent, state)
        pos, rot = team_frame(agent, car.pos), _team_rot(agent, car.rot_mat)
        ball = rotation.ball_ahead(view)
        if role is Role.LAST:
            spot = rotation.last_man_spot(ball, roles, self.tuning)
        else:
            rank = sum(1 for a, r in roles.items() if r is Role.SECOND and a != agent and view.pos[a][1] > pos[1])
            spot = rotation.support_spot(ball, rank=1 + rank)
        pads = team_frame(agent, C.BOOST_PAD_POSITIONS)
        team_size = sum(1 for a in state.cars if agent_team(a) == agent_team(agent))
        target = rotation.boost_on_the_way(pos, spot, car.boost, state.pad_timers, pads, team_size, self.tuning)
        if target is None:
            target = spot
        target = _around_ball(pos, target, view.ball_pos, self.BALL_CLEARANCE_UU)
        speed = float(team_frame(agent, car.vel) @ rot[:, 0])
        if target is spot and float(np.hypot(*(spot - pos)[:2])) < self.ARRIVE_UU:
            angle, _ = _angle_distance(pos, rot, view.ball_pos)
            return _ground_row(0.0, self.chaser._steer(angle))
        return self.chaser._drive(pos, rot, _out_of_goal_mouth(pos, target), speed)

    def _shot_dodge(self, agent: str, state: GameState, view: rotation.TeamView) -> CarControls | None:
        """The jump that starts a dodge into the ball (None: no dodge now); outside kickoffs, which the flip-chaser
        plays with its own dodge."""
        car = state.cars[agent]
        if rotation.is_kickoff(view) or not car.on_ground or view.ball_pos[2] > self.DODGE_MAX_BALL_Z_UU:
            return None
        pos, rot, vel = view.pos[agent], _team_rot(agent, car.rot_mat), view.vel[agent]
        if rot[2, 2] < saves.UPRIGHT_UP_Z:  # on a wall or a ramp: a dodge from there does not go at the ball
            return None
        to_ball = (view.ball_pos - pos)[:2]
        distance = float(np.hypot(*to_ball))
        closing = float((vel[:2] - view.ball_vel[:2]) @ to_ball) / max(distance, 1.0)
        to_goal = ATTACK_GOAL[:2] - view.ball_pos[:2]
        shot_cos = float(to_ball @ to_goal) / max(distance * float(np.hypot(*to_goal)), 1.0)
        angle, _ = _angle_distance(pos, rot, view.ball_pos)
        if (closing > self.DODGE_MIN_CLOSING_UU_S and abs(angle) < self.DODGE_AIM_RAD and shot_cos > self.DODGE_MIN_SHOT_COS
                and (distance - FlipChaser.CONTACT_UU) / closing < self.DODGE_LEAD_S):
            return _air_row(jump=True, boost=car.boost > 0.0)
        return None

    @staticmethod
    def _finish_dodge(agent: str, state: GameState, view: rotation.TeamView) -> CarControls | None:
        """A car on the ball low in the air after a jump of its own, upright and not yet dodged, dodges forward
        (release the jump, then press it with pitch): the second half of the shot dodge, sequenced from the car's
        jump state."""
        car = state.cars[agent]
        if (rotation.is_kickoff(view) or car.on_ground or not car.has_jumped or car.has_flipped
                or _team_rot(agent, car.rot_mat)[2, 2] <= 0.7 or car.pos[2] >= 300.0):
            return None
        return _ground_row(1.0, 0.0) if car.is_jumping else _air_row(pitch=-1.0, jump=True)


class Idle(ScriptedBot):
    """Does nothing: an empty net for shooting practice."""

    bot_name = "idle"

    def controls(self, agent: str, state: GameState) -> CarControls:
        return CarControls()


def _team_rot(agent: str, rot: np.ndarray) -> np.ndarray:
    return rot_to_team_frame(agent_team(agent), rot)


def _on_its_side_against_a_wall(car: CarState, below_uu_s: float = 200.0) -> bool:
    """Wheels on a wall (a net's side, the arena's), body level with the floor, slower than ``below_uu_s``: driving
    cannot free a car standing there, a jump off the wall can."""
    return car.on_ground and car.rot_mat[2, 2] < 0.5 and float(np.linalg.norm(car.vel)) < below_uu_s


def _ground_row(throttle: float, steer: float, boost: bool = False, handbrake: bool = False) -> CarControls:
    """Driving controls as a row of the lookup table's ground part: yaw follows steer, boost means full throttle."""
    return CarControls(throttle=1.0 if boost else throttle, steer=steer, yaw=steer, boost=boost, handbrake=handbrake)


def _air_row(pitch: float = 0.0, jump: bool = False, boost: bool = False) -> CarControls:
    """A jump or dodge as a row of the lookup table's air part: throttle follows boost, handbrake held on a dodge."""
    return CarControls(throttle=1.0 if boost else 0.0, pitch=pitch, jump=jump, boost=boost,
                       handbrake=jump and pitch != 0.0)


def _angle_distance(pos: np.ndarray, rot: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    """Heading error to ``target`` on the floor (rad, positive: to the right) and the distance to it (uu)."""
    local = rot.T @ (np.array([target[0], target[1], 0.0]) - pos)
    return math.atan2(local[1], local[0]), float(np.hypot(local[0], local[1]))


# The floor is flat through a goal mouth, but beside it (|x| > the goal's half width, within 400 uu of the back
# wall) the wall's ramp begins with a vertical cut face at the posts' line: a step the wheels cannot climb.
_MOUTH_Y = C.ARENA_EXTENT_Y - C.ARENA_FILLET_RADIUS - 70.0


def _nose_blocked(pos: np.ndarray, rot: np.ndarray) -> bool:
    """The car's nose is at a goal mouth's step, a net's side or the back of a net."""
    nose = pos + rot[:, 0] * 120.0
    in_mouth = abs(pos[1]) > _MOUTH_Y and abs(pos[0]) < C.GOAL_HALF_WIDTH
    in_net = abs(pos[1]) > C.ARENA_EXTENT_Y - 50.0
    return ((in_mouth and abs(nose[1]) > _MOUTH_Y + 50.0 and abs(nose[0]) > C.GOAL_HALF_WIDTH - 30.0)
            or (in_net and abs(nose[0]) > C.GOAL_HALF_WIDTH - 30.0)
            or abs(nose[1]) > C.ARENA_EXTENT_Y + C.GOAL_DEPTH - 30.0)


def _around_ball(pos: np.ndarray, target: np.ndarray, ball: np.ndarray, clearance_uu: float) -> np.ndarray:
    """``target``, or a point beside the ball when the straight path to it passes within ``clearance_uu`` of the
    ball (on the ball's side nearer the middle of the path), so a car off the ball does not touch it on its way."""
    path = (target - pos)[:2]
    length = float(np.hypot(*path))
    if length < 1.0 or ball[2] > 300.0:
        return target
    along = float((ball - pos)[:2] @ path) / length
    if not 0.0 < along < length:
        return target
    normal = np.array([-path[1], path[0]]) / length
    offset = float((ball - pos)[:2] @ normal)
    if abs(offset) >= clearance_uu:
        return target
    side = -1.0 if offset >= 0.0 else 1.0
    beside = ball[:2] + normal * side * clearance_uu
    return np.array([beside[0], beside[1], 0.0])


def _out_of_goal_mouth(pos: np.ndarray, target: np.ndarray) -> np.ndarray:
    """A car in a goal mouth bound for a target beside it leaves along y first, clear of the steps."""
    if abs(pos[1]) > 4600.0 and abs(pos[0]) < C.GOAL_HALF_WIDTH + 50.0 and abs(target[0]) > C.GOAL_HALF_WIDTH - 150.0:
        return np.array([np.clip(target[0], -600.0, 600.0), math.copysign(4450.0, pos[1]), 0.0])
    return target


def check_bot(field: str, name: Any) -> str:
    """``name`` if it names a registered scripted bot; else a ValueError naming ``field`` and the bots there are."""
    if not isinstance(name, str) or name not in SCRIPTED_BOTS:
        raise ValueError(f"{field}: {name!r} is not one of {sorted(SCRIPTED_BOTS)}")
    return name


def make_scripted(name: str) -> ScriptedBot:
    try:
        return SCRIPTED_BOTS[name]()
    except (KeyError, TypeError):
        raise ValueError(f"bot: unknown scripted bot {name!r}; allowed: {sorted(SCRIPTED_BOTS)}") from None
