"""Team rotation as Rocket League players play it: who challenges, who supports, who covers the goal, and where
the cars that are not on the ball go. Pure functions of the game state, in a team's frame (the team attacks +y).

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
- **presser**: plays the ball wherever it is, the flip-chaser's game with the shot dodge. With three rotating cars
  a team lost most 3v3 matches to three flip-chasers, whose pressure on the ball beat that of a first man and a
  follow-up; two rotating cars and a presser win most of them (README, "Team play").

A car that is not first and has to come back (its spot is behind it) takes an active boost pad on the way when it
is short of boost and the pad costs little of a detour: the boost collected on the way back.

At a kickoff the two nearest cars go (only the nearest from some layouts: ``KICKOFF_ALONE``). The
second one aims beside the ball, how far depending on the kickoff layout (``kickoff_aim``): it meets the ball just
after the collision at the centre and sends it on towards the opponents' goal, which chasers who all went for the
ball have left empty.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum, IntEnum

import numpy as np

from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import GameState, agent_number, agent_team

OWN_GOAL_Y = -C.ARENA_EXTENT_Y
#: the speed (uu/s) the arrival-time estimate assumes, and what a car upfield of the ball pays per uu it must come
#: back and as a fixed cost of turning round
ESTIMATE_SPEED_UU_S = 1600.0
WRONG_SIDE_COST_S = 0.6
#: the last toucher keeps the first man's role while within this of the ball, at this head start
KEEP_ROLE_WITHIN_UU, KEEP_ROLE_BONUS_S = 900.0, 0.35
KICKOFF_TAKERS = 2  # cars that go for the ball at a kickoff
ROTATING_CARS = 2  # cars that rotate outside kickoffs; the team's others are pressers
FOLLOW_UP_GOAL_SIDE_UU = 300.0  # the follow-up car is at least this much nearer its own goal than the ball
#: the second man's spot: this far behind the ball, its x pulled this much towards the middle
SUPPORT_BACK_UU, SUPPORT_X_SHARE = 1900.0, 0.5
#: the last man stays this far behind the ball on its way to goal: with one other rotating car (open play), with
#: more (the cars that do not take a 3v3 or 4v4 kickoff)
LAST_BEHIND_PAIR_UU, LAST_BEHIND_UU = 1500.0, 2600.0
GOAL_LINE_STAND_UU = 180.0  # how far in front of the goal line the last man stands at most
#: with pressers on the team, the last man's spot is no further up the field than this (team frame y), and he follows
#: up only while the ball is below it: in 3v3 goal histories the last man was upfield of the ball 4 s before 111 of
#: 149 goals conceded (README, "The last man holds the halfway line")
LAST_MAN_LINE_Y_UU = 0.0
#: boost on the way back: below this much boost, a pad within this detour (uu; small pad, big pad) by team size (2; 3
#: and more cars a side). With three or more, small pads further out are worth it: paired rollouts of 3v3 matches
#: gained goals with 800 uu, where 2v2 matches lost with it (README, "Boost on the way back").
LOW_BOOST = 60.0
DETOUR_UU: dict[int, tuple[float, float]] = {2: (500.0, 1300.0), 3: (800.0, 1300.0)}


class Role(IntEnum):
    FIRST = 0
    SECOND = 1
    LAST = 2
    PRESSER = 3


class KickoffLane(Enum):
    """Where a car comes from at a kickoff, by its bearing from the centre spot: a diagonal spot (39 deg off the
    field's long axis), an off-centre spot (4 deg), or straight behind the ball."""
    DIAGONAL = "diagonal"
    OFF_CENTRE = "off_centre"
    BACK = "back"


#: bearings (deg off the long axis) that separate the kickoff lanes
DIAGONAL_BEARING_DEG, OFF_CENTRE_BEARING_DEG = 20.0, 1.0
#: how far beside the ball (uu along x, towards the car's own side when positive) the second kickoff taker aims, by
#: team size (2, 3, 4) and the lanes of the first and second taker; a layout not listed aims at the ball's
#: centre. Searched against flip-chasers with the real 3 s countdown over every kickoff a match can have: each layout
#: from both ends at each of the 8 decision phases a kickoff after a goal can start at, phase 0 (every match's first
#: kickoff) counted at its weight in a match (README, "Team play"). Aiming at the ball's centre as the first taker
#: does, the second car's touch sends the ball towards a corner. With three or more cars the two nearest are never
#: the back spot's. 3v3 and 4v4 each have their own optimum: 4v4 with 3v3's 90 uu lost most of its kickoff goals.
KICKOFF_SECOND_AIM_UU: dict[int, dict[tuple[KickoffLane, KickoffLane], float]] = {
    2: {(KickoffLane.DIAGONAL, KickoffLane.OFF_CENTRE): -80.0,
        (KickoffLane.DIAGONAL, KickoffLane.DIAGONAL): 50.0,
        (KickoffLane.OFF_CENTRE, KickoffLane.BACK): 150.0,
        (KickoffLane.OFF_CENTRE, KickoffLane.OFF_CENTRE): 50.0},
    3: {(KickoffLane.DIAGONAL, KickoffLane.OFF_CENTRE): -90.0,
        (KickoffLane.DIAGONAL, KickoffLane.DIAGONAL): -150.0},
    4: {(KickoffLane.DIAGONAL, KickoffLane.OFF_CENTRE): -120.0,
        (KickoffLane.DIAGONAL, KickoffLane.DIAGONAL): -150.0},
}
_BOTH_OFF_CENTRE = frozenset({(KickoffLane.OFF_CENTRE, KickoffLane.OFF_CENTRE),
                              (KickoffLane.OFF_CENTRE, KickoffLane.BACK), (KickoffLane.BACK, KickoffLane.OFF_CENTRE)})
#: layouts (lanes of the two cars nearest the ball) where, by team size, only the nearest car takes the kickoff and
#: the other stays back, searched with the offsets above: in 2v2 a diagonal spot with the back spot's car (the back
#: car covers as last man), in 3v3 and 4v4 when both come from the off-centre spots (the other waits as second man).
#: The lanes are read each decision, and the car staying back drives into the back lane.
KICKOFF_ALONE: dict[int, frozenset[tuple[KickoffLane, KickoffLane]]] = {
    2: frozenset({(KickoffLane.DIAGONAL, KickoffLane.BACK)}), 3: _BOTH_OFF_CENTRE, 4: _BOTH_OFF_CENTRE}


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
    return np.ones(3) if agent_team(agent) == 0 else np.array([-1.0, -1.0, 1.0])


def team_view(agent: str, state: GameState) -> TeamView:
    """``agent``'s live team-mates (demoed cars are out of play) and the ball, in ``agent``'s team frame."""
    team, sign = agent_team(agent), frame_sign(agent)
    mates = tuple(sorted(a for a, car in state.cars.items() if agent_team(a) == team and not car.is_demoed))
    return TeamView(mates, {a: state.cars[a].pos * sign for a in mates}, {a: state.cars[a].vel * sign for a in mates},
                    state.ball.pos * sign, state.ball.vel * sign)


def arrival_s(pos: np.ndarray, vel: np.ndarray, ball: np.ndarray) -> float:
    """Rough seconds for a car to get to the ball from its own side: distance over a typical speed, less the speed it
    already carries towards the ball, plus the way round for a car upfield of the ball."""
    to_ball = ball[:2] - pos[:2]
    distance = float(np.hypot(*to_ball))
    closing = float(vel[:2] @ to_ball) / max(distance, 1.0)
    t = distance / max(ESTIMATE_SPEED_UU_S, ESTIMATE_SPEED_UU_S + 0.5 * closing)
    upfield = pos[1] - ball[1]
    if upfield > 0.0:
        t += WRONG_SIDE_COST_S + upfield / ESTIMATE_SPEED_UU_S
    return t


def is_kickoff(view: TeamView) -> bool:
    """The ball waits on the centre spot."""
    return abs(view.ball_pos[0]) < 1.0 and abs(view.ball_pos[1]) < 1.0 and float(np.linalg.norm(view.ball_vel)) < 1.0


def kickoff_takers(view: TeamView) -> list[str]:
    """The team's cars in the order they reach the centre spot (ties to the lower name); the first
    ``KICKOFF_TAKERS`` go for the ball at a kickoff."""
    times = {a: arrival_s(view.pos[a], view.vel[a], view.ball_pos) for a in view.agents}
    return sorted(view.agents, key=lambda a: (times[a], a))


def kickoff_lane(pos: np.ndarray) -> KickoffLane:
    """The lane a car at ``pos`` (team frame) drives in towards the centre spot."""
    bearing_deg = math.degrees(math.atan2(abs(pos[0]), abs(pos[1])))
    if bearing_deg > DIAGONAL_BEARING_DEG:
        return KickoffLane.DIAGONAL
    return KickoffLane.OFF_CENTRE if bearing_deg > OFF_CENTRE_BEARING_DEG else KickoffLane.BACK


def kickoff_layout(view: TeamView, order: list[str]) -> tuple[int, tuple[KickoffLane, KickoffLane]]:
    """The keys of the kickoff tables (``KICKOFF_SECOND_AIM_UU``, ``KICKOFF_ALONE``) for a team of two or more cars
    (``order``: ``kickoff_takers(view)``): its team size (2, 3 or 4) and the lanes of its two nearest cars, read from
    their positions now."""
    return len(order), (kickoff_lane(view.pos[order[0]]), kickoff_lane(view.pos[order[1]]))


def kickoff_taker_count(view: TeamView, order: list[str]) -> int:
    """How many of the team's cars (``order``: ``kickoff_takers(view)``) take this kickoff: ``KICKOFF_TAKERS``, or
    one in a ``KICKOFF_ALONE`` layout."""
    if len(order) < 2:
        return len(order)
    size, lanes = kickoff_layout(view, order)
    return 1 if lanes in KICKOFF_ALONE[size] else KICKOFF_TAKERS


def kickoff_aim(view: TeamView, agent: str) -> np.ndarray:
    """Where ``agent``, a kickoff taker, drives at: the ball for the first, for the second beside it by
    ``KICKOFF_SECOND_AIM_UU`` of its team size and layout (towards its own side of the field's long axis when
    positive; a car on the axis counts as on the +x side). The lanes are read from the cars' positions each
    decision."""
    order = kickoff_takers(view)
    if len(order) < 2 or agent != order[1]:
        return view.ball_pos
    pos = view.pos[agent]
    size, lanes = kickoff_layout(view, order)
    aside_uu = KICKOFF_SECOND_AIM_UU[size].get(lanes, 0.0)
    side = math.copysign(1.0, pos[0]) if abs(pos[0]) > 1.0 else 1.0
    return view.ball_pos + np.array([side * aside_uu, 0.0, 0.0])


def assign_roles(view: TeamView, last_touch: str | None) -> dict[str, Role]:
    """Every live team-mate's role; ties go to the lower agent name, so all team-mates reach the same answer.
    At a kickoff the two nearest cars go: the nearer takes it, the other arrives just after it (``kickoff_aim``);
    in a ``KICKOFF_ALONE`` layout only the nearer goes. Of the others the deepest is the last man. Outside kickoffs
    the ``ROTATING_CARS`` lowest-numbered cars rotate (first man, last man, second men between) and the others are
    pressers."""
    if not view.agents:
        return {}
    if is_kickoff(view):
        by_time = kickoff_takers(view)
        count = kickoff_taker_count(view, by_time)
        takers = by_time[:count]
        others = sorted(by_time[count:], key=lambda a: (view.pos[a][1], a))
        return {**{a: Role.FIRST for a in takers},
                **{a: Role.LAST if k == 0 else Role.SECOND for k, a in enumerate(others)}}
    by_number = sorted(view.agents, key=agent_number)
    rotating = by_number[:ROTATING_CARS]
    times = {a: arrival_s(view.pos[a], view.vel[a], view.ball_pos) for a in rotating}
    if last_touch in times and float(np.linalg.norm(view.pos[last_touch] - view.ball_pos)) < KEEP_ROLE_WITHIN_UU:
        times[last_touch] -= KEEP_ROLE_BONUS_S
    first = min(rotating, key=lambda a: (times[a], a))
    others = sorted((a for a in rotating if a != first), key=lambda a: (view.pos[a][1], a))
    roles = {first: Role.FIRST}
    for k, a in enumerate(others):
        roles[a] = Role.LAST if k == 0 else Role.SECOND
    return {**roles, **{a: Role.PRESSER for a in by_number[ROTATING_CARS:]}}


def rotating_count(roles: dict[str, Role]) -> int:
    """How many cars rotate (every car but the pressers)."""
    return sum(1 for r in roles.values() if r is not Role.PRESSER)


def has_pressers(roles: dict[str, Role]) -> bool:
    """Whether some of the team's cars press: outside kickoffs, while the team has more live cars than
    ``ROTATING_CARS`` (a demo in 3v3 leaves two, who both rotate)."""
    return any(r is Role.PRESSER for r in roles.values())


def follow_up(view: TeamView, roles: dict[str, Role]) -> str | None:
    """The car that goes for the ball after the first man (None: no car does): of the rotating cars not first, the
    one that would reach the ball soonest, if it is goal-side of the ball by ``FOLLOW_UP_GOAL_SIDE_UU``. The last
    man is no candidate with three or more rotating (he keeps covering the goal), nor with pressers on the team while
    the ball is beyond ``LAST_MAN_LINE_Y_UU`` (he holds that line). Every team-mate reaches the same answer."""
    last_may_go = rotating_count(roles) <= 2 and not (has_pressers(roles) and view.ball_pos[1] > LAST_MAN_LINE_Y_UU)
    candidates = [a for a, r in roles.items()
                  if r not in (Role.FIRST, Role.PRESSER) and (last_may_go or r is not Role.LAST)]
    if not candidates or is_kickoff(view):
        return None
    car = min(candidates, key=lambda a: (arrival_s(view.pos[a], view.vel[a], view.ball_pos), a))
    return car if view.pos[car][1] < view.ball_pos[1] - FOLLOW_UP_GOAL_SIDE_UU else None


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


def last_man_spot(ball: np.ndarray, roles: dict[str, Role]) -> np.ndarray:
    """The last man's spot for the ball at ``ball``: ``cover_spot`` at ``LAST_BEHIND_PAIR_UU`` behind it with two
    rotating cars, ``LAST_BEHIND_UU`` with more, and with pressers on the team no further up than
    ``LAST_MAN_LINE_Y_UU``."""
    spot = cover_spot(ball, LAST_BEHIND_PAIR_UU if rotating_count(roles) <= 2 else LAST_BEHIND_UU)
    if has_pressers(roles):
        spot[1] = min(spot[1], LAST_MAN_LINE_Y_UU)
    return spot


def support_spot(ball: np.ndarray, rank: int = 1) -> np.ndarray:
    """Behind the ball, towards the middle; a deeper supporter (``rank`` 2, 4v4) further back."""
    y = float(np.clip(ball[1] - SUPPORT_BACK_UU * rank, OWN_GOAL_Y + 900.0, C.ARENA_EXTENT_Y - 1500.0))
    x = float(np.clip(ball[0] * SUPPORT_X_SHARE, -C.ARENA_EXTENT_X + 900.0, C.ARENA_EXTENT_X - 900.0))
    return np.array([x, y, 0.0])


def boost_on_the_way(pos: np.ndarray, spot: np.ndarray, boost: float, pad_timers: np.ndarray,
                     pads_team_frame: np.ndarray, team_size: int) -> np.ndarray | None:
    """The active pad worth a detour on the way from ``pos`` back to ``spot`` (None: drive straight there): only when
    short of boost and coming back (the pad not upfield of the car), the one with the least detour, within
    ``DETOUR_UU`` of the match's ``team_size`` (cars a side, demoed ones too)."""
    if boost >= LOW_BOOST:
        return None
    small_uu, big_uu = DETOUR_UU[min(max(team_size, 2), 3)]
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
