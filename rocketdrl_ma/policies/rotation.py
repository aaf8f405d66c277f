"""Team rotation as Rocket League players play it: who challenges, who supports, who covers the goal, and where
the cars that are not on the ball go. Pure functions of the game state and the searched settings (a
``RotatorTuning``: how many cars rotate, the kickoff tables, ...; the shipped ones are
``rotator_tuning.shipped_tuning()``), in a team's frame (the team attacks +y).

Every car of a team works the roles out from the same state, so they agree without talking to each other. Outside
kickoffs two cars rotate, the two lowest-numbered live ones (a demoed car's place passes to the next); in 3v3 and
4v4 the others press:

- **first man**: the rotating car that reaches the ball soonest from its own side of it (a car upfield of the ball
  has to come back around it first, and pays for that); the last toucher keeps the role while it is near the
  ball, so two cars at about the same distance do not swap it every decision.
- **follow-up**: one more rotating car goes for the ball: of the others, the one that would reach it soonest, when
  it is goal-side of the ball (it comes at the ball from behind, facing the opponents' goal) and not a last man
  who stays back (below). It arrives just after the first man and takes the 50-50 or the loose ball he
  leaves: one car on the ball against two chasers loses most challenges, two staggered cars win them. A car
  upfield of the ball never follows up; it rotates back instead.
- **last man**: of the other rotating cars, the one nearest its own goal; it stands on the line from its goal's
  centre to the ball, in the net when the ball is in its third, further out while the ball is away. With three or
  more rotating it never follows up. With pressers on the team (3v3, 4v4) it holds the halfway line: it goes no
  further up the field and follows up only while the ball is in its own half, so a cleared ball does not find every
  car of the team upfield of it.
- **second man** (rotating cars between, at a 4v4 kickoff): behind the ball towards the middle.
- **presser**: plays the ball wherever it is, the flip-chaser's game with the shot dodge: against three
  flip-chasers, pressure on the ball wins more than a third rotating car (docs/experiments/rotator-tuning.md).

A car that is not first and has to come back (its spot is behind it) takes an active boost pad on the way when it
is short of boost and the pad costs little of a detour: the boost collected on the way back.

At a kickoff the two nearest cars go (only the nearest from some layouts: ``KickoffTable.alone``). The
second one aims beside the ball, how far depending on the kickoff layout (``kickoff_aim``): it meets the ball just
after the collision at the centre and sends it on towards the opponents' goal, which chasers who all went for the
ball have left empty.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.frames import team_axis_sign
from rocketdrl_ma.rules.state import GameState, agent_number, agent_team

from .rotator_tuning import KickoffLane, RotatorTuning

OWN_GOAL_Y = -C.ARENA_EXTENT_Y
#: the speed (uu/s) the arrival-time estimate assumes, and what a car upfield of the ball pays per uu it must come
#: back (its fixed cost of turning round is ``RotatorTuning.wrong_side_cost_s``)
ESTIMATE_SPEED_UU_S = 1600.0
#: the last toucher keeps the first man's role while within this of the ball
KEEP_ROLE_WITHIN_UU = 900.0
KICKOFF_TAKERS = 2  # cars that go for the ball at a kickoff
#: the second man's spot: this far behind the ball, its x pulled this much towards the middle
SUPPORT_BACK_UU, SUPPORT_X_SHARE = 1900.0, 0.5
#: the last man stays this far behind the ball on its way to goal with more than one other rotating car (the cars
#: that do not take a 3v3 or 4v4 kickoff); with one, ``RotatorTuning.last_behind_pair_uu``
LAST_BEHIND_UU = 2600.0
GOAL_LINE_STAND_UU = 180.0  # how far in front of the goal line the last man stands at most


class Role(IntEnum):
    FIRST = 0
    SECOND = 1
    LAST = 2
    PRESSER = 3


#: bearings (deg off the long axis) that separate the kickoff lanes
DIAGONAL_BEARING_DEG, OFF_CENTRE_BEARING_DEG = 20.0, 1.0


@dataclass(frozen=True)
class TeamView:
    """One car's team in its team frame: positions and velocities of the live team-mates (the car itself included)."""
    agents: tuple[str, ...]
    pos: dict[str, np.ndarray]
    vel: dict[str, np.ndarray]
    ball_pos: np.ndarray
    ball_vel: np.ndarray


def frame_sign(agent: str) -> np.ndarray:
    """Orange's team frame is the field turned half a circle: x -> -x, y -> -y."""
    return team_axis_sign(agent_team(agent))


def team_view(agent: str, state: GameState) -> TeamView:
    """``agent``'s live team-mates (demoed cars are out of play) and the ball, in ``agent``'s team frame."""
    team, sign = agent_team(agent), frame_sign(agent)
    mates = tuple(sorted(a for a, car in state.cars.items() if agent_team(a) == team and not car.is_demoed))
    return TeamView(mates, {a: state.cars[a].pos * sign for a in mates}, {a: state.cars[a].vel * sign for a in mates},
                    state.ball.pos * sign, state.ball.vel * sign)


def arrival_s(pos: np.ndarray, vel: np.ndarray, ball: np.ndarray, tuning: RotatorTuning) -> float:
    """Rough seconds for a car to get to the ball from its own side: distance over a typical speed, less the speed it
    already carries towards the ball, plus the way round for a car upfield of the ball."""
    to_ball = ball[:2] - pos[:2]
    distance = float(np.hypot(*to_ball))
    closing = float(vel[:2] @ to_ball) / max(distance, 1.0)
    t = distance / max(ESTIMATE_SPEED_UU_S, ESTIMATE_SPEED_UU_S + 0.5 * closing)
    upfield = pos[1] - ball[1]
    if upfield > 0.0:
        t += tuning.wrong_side_cost_s + upfield / ESTIMATE_SPEED_UU_S
    return t


def is_kickoff(view: TeamView) -> bool:
    """The ball waits on the centre spot."""
    return abs(view.ball_pos[0]) < 1.0 and abs(view.ball_pos[1]) < 1.0 and float(np.linalg.norm(view.ball_vel)) < 1.0


def kickoff_takers(view: TeamView, tuning: RotatorTuning) -> list[str]:
    """The team's cars in the order they reach the centre spot (ties to the lower name); the first
    ``KICKOFF_TAKERS`` go for the ball at a kickoff."""
    times = {a: arrival_s(view.pos[a], view.vel[a], view.ball_pos, tuning) for a in view.agents}
    return sorted(view.agents, key=lambda a: (times[a], a))


def kickoff_lane(pos: np.ndarray) -> KickoffLane:
    """The lane a car at ``pos`` (team frame) drives in towards the centre spot."""
    bearing_deg = math.degrees(math.atan2(abs(pos[0]), abs(pos[1])))
    if bearing_deg > DIAGONAL_BEARING_DEG:
        return KickoffLane.DIAGONAL
    return KickoffLane.OFF_CENTRE if bearing_deg > OFF_CENTRE_BEARING_DEG else KickoffLane.BACK


def kickoff_layout(view: TeamView, order: list[str]) -> tuple[int, tuple[KickoffLane, KickoffLane]]:
    """Which kickoff table applies and where in it (``RotatorTuning.kickoff``) for a team of two or more cars
    (``order``: ``kickoff_takers(view, ...)``): its team size (2, 3 or 4) and the lanes of its two nearest cars, read
    from their positions now."""
    return len(order), (kickoff_lane(view.pos[order[0]]), kickoff_lane(view.pos[order[1]]))


def kickoff_taker_count(view: TeamView, order: list[str], tuning: RotatorTuning) -> int:
    """How many of the team's cars (``order``: ``kickoff_takers(view, tuning)``) take this kickoff:
    ``KICKOFF_TAKERS``, or one in a layout of its table's ``alone``."""
    if len(order) < 2:
        return len(order)
    size, lanes = kickoff_layout(view, order)
    return 1 if lanes in tuning.kickoff[size].alone else KICKOFF_TAKERS


def kickoff_aim(view: TeamView, agent: str, tuning: RotatorTuning) -> np.ndarray:
    """Where ``agent``, a kickoff taker, drives at: the ball for the first, for the second beside it by
    ``second_aim_uu`` of its team size's table and its layout (towards its own side of the field's long axis when
    positive; a car on the axis counts as on the +x side). The lanes are read from the cars' positions each
    decision."""
    order = kickoff_takers(view, tuning)
    if len(order) < 2 or agent != order[1]:
        return view.ball_pos
    pos = view.pos[agent]
    size, lanes = kickoff_layout(view, order)
    aside_uu = tuning.kickoff[size].second_aim_uu.get(lanes, 0.0)
    side = math.copysign(1.0, pos[0]) if abs(pos[0]) > 1.0 else 1.0
    return view.ball_pos + np.array([side * aside_uu, 0.0, 0.0])


def assign_roles(view: TeamView, last_touch: str | None, tuning: RotatorTuning) -> dict[str, Role]:
    """Every live team-mate's role; ties go to the lower agent name, so all team-mates reach the same answer.
    At a kickoff the two nearest cars go: the nearer takes it, the other arrives just after it (``kickoff_aim``);
    in a layout of the table's ``alone`` only the nearer goes. Of the others the deepest is the last man. Outside
    kickoffs the ``tuning.rotating_cars`` lowest-numbered cars rotate (first man, last man, second men between) and
    the others are pressers."""
    if not view.agents:
        return {}
    if is_kickoff(view):
        by_time = kickoff_takers(view, tuning)
        count = kickoff_taker_count(view, by_time, tuning)
        takers = by_time[:count]
        others = sorted(by_time[count:], key=lambda a: (view.pos[a][1], a))
        return {**{a: Role.FIRST for a in takers},
                **{a: Role.LAST if k == 0 else Role.SECOND for k, a in enumerate(others)}}
    by_number = sorted(view.agents, key=agent_number)
    rotating = by_number[:tuning.rotating_cars]
    times = {a: arrival_s(view.pos[a], view.vel[a], view.ball_pos, tuning) for a in rotating}
    if last_touch in times and float(np.linalg.norm(view.pos[last_touch] - view.ball_pos)) < KEEP_ROLE_WITHIN_UU:
        times[last_touch] -= tuning.keep_role_bonus_s
    first = min(rotating, key=lambda a: (times[a], a))
    others = sorted((a for a in rotating if a != first), key=lambda a: (view.pos[a][1], a))
    roles = {first: Role.FIRST}
    for k, a in enumerate(others):
        roles[a] = Role.LAST if k == 0 else Role.SECOND
    return {**roles, **{a: Role.PRESSER for a in by_number[tuning.rotating_cars:]}}


def rotating_count(roles: dict[str, Role]) -> int:
    """How many cars rotate (every car but the pressers)."""
    return sum(1 for r in roles.values() if r is not Role.PRESSER)


def has_pressers(roles: dict[str, Role]) -> bool:
    """Whether some of the team's cars press: outside kickoffs, while the team has more live cars than rotate (a
    demo in 3v3 leaves two, who both rotate)."""
    return any(r is Role.PRESSER for r in roles.values())


def follow_up(view: TeamView, roles: dict[str, Role], tuning: RotatorTuning) -> str | None:
    """The car that goes for the ball after the first man (None: no car does): of the rotating cars not first, the
    one that would reach the ball soonest, if it is goal-side of the ball by ``tuning.follow_up_goal_side_uu``. The
    last man is no candidate with three or more rotating (he keeps covering the goal), nor with pressers on the team
    while the ball is beyond ``tuning.last_man_line_y_uu`` (he holds that line). Every team-mate reaches the same
    answer."""
    last_may_go = rotating_count(roles) <= 2 and not (has_pressers(roles)
                                                      and view.ball_pos[1] > tuning.last_man_line_y_uu)
    candidates = [a for a, r in roles.items()
                  if r not in (Role.FIRST, Role.PRESSER) and (last_may_go or r is not Role.LAST)]
    if not candidates or is_kickoff(view):
        return None
    car = min(candidates, key=lambda a: (arrival_s(view.pos[a], view.vel[a], view.ball_pos, tuning), a))
    return car if view.pos[car][1] < view.ball_pos[1] - tuning.follow_up_goal_side_uu else None


def ball_ahead(view: TeamView, seconds: float = 0.8) -> np.ndarray:
    """Where the ball is heading, ``seconds`` on in a straight line (kept inside the field): the cover spots follow
    it, so a car covering is back before a cleared or shot ball passes it."""
    ahead = view.ball_pos + view.ball_vel * seconds
    return np.array([np.clip(ahead[0], -C.ARENA_EXTENT_X, C.ARENA_EXTENT_X),
                     np.clip(ahead[1], OWN_GOAL_Y, C.ARENA_EXTENT_Y), ahead[2]])


def cover_spot(ball: np.ndarray, behind_uu: float) -> np.ndarray:
    """On the line from the ball to the own goal's centre, ``behind_uu`` from the ball, never behind the goal line:
    the path the ball takes to the goal, so a car here meets a ball the opponents win."""
    goal = np.array([0.0, OWN_GOAL_Y, 0.0])
    to_goal = goal[:2] - ball[:2]
    distance = float(np.hypot(*to_goal))
    back = min(behind_uu, max(distance - GOAL_LINE_STAND_UU, 0.0))
    xy = ball[:2] + to_goal / max(distance, 1.0) * back
    return np.array([xy[0], max(xy[1], OWN_GOAL_Y + GOAL_LINE_STAND_UU), 0.0])


def last_man_spot(ball: np.ndarray, roles: dict[str, Role], tuning: RotatorTuning) -> np.ndarray:
    """The last man's spot for the ball at ``ball``: ``cover_spot`` at ``tuning.last_behind_pair_uu`` behind it
    with two rotating cars, ``LAST_BEHIND_UU`` with more, and with pressers on the team no further up than
    ``tuning.last_man_line_y_uu``."""
    spot = cover_spot(ball, tuning.last_behind_pair_uu if rotating_count(roles) <= 2 else LAST_BEHIND_UU)
    if has_pressers(roles):
        spot[1] = min(spot[1], tuning.last_man_line_y_uu)
    return spot


def support_spot(ball: np.ndarray, rank: int = 1) -> np.ndarray:
    """Behind the ball, towards the middle; a deeper supporter (``rank`` 2, 4v4) further back."""
    y = float(np.clip(ball[1] - SUPPORT_BACK_UU * rank, OWN_GOAL_Y + 900.0, C.ARENA_EXTENT_Y - 1500.0))
    x = float(np.clip(ball[0] * SUPPORT_X_SHARE, -C.ARENA_EXTENT_X + 900.0, C.ARENA_EXTENT_X - 900.0))
    return np.array([x, y, 0.0])


def boost_on_the_way(pos: np.ndarray, spot: np.ndarray, boost: float, pad_timers: np.ndarray,
                     pads_team_frame: np.ndarray, team_size: int, tuning: RotatorTuning) -> np.ndarray | None:
    """The active pad worth a detour on the way from ``pos`` back to ``spot`` (None: drive straight there): only when
    short of boost (``tuning.low_boost``) and coming back (the pad not upfield of the car), the one with the least
    detour, within ``tuning.detour_for`` the match's ``team_size`` (cars a side, demoed ones too)."""
    if boost >= tuning.low_boost:
        return None
    small_uu, big_uu = tuning.detour_for(team_size)
    direct = float(np.hypot(*(spot - pos)[:2]))
    best, best_cost = None, np.inf
    for k in np.flatnonzero(pad_timers <= 0.0):
        pad = pads_team_frame[k]
        if pad[1] > pos[1] + 200.0:
            continue
        detour = float(np.hypot(*(pad - pos)[:2]) + np.hypot(*(spot - pad)[:2])) - direct
        allowed = big_uu if C.BOOST_PAD_IS_BIG[k] else small_uu
        cost = detour - (600.0 if C.BOOST_PAD_IS_BIG[k] else 0.0)
        if detour < allowed and cost < best_cost:
            best, best_cost = pad, cost
    return None if best is None else np.array([best[0], best[1], 0.0])
