"""Team metrics of a match, built from the physics' typed events (``BallTouch``, ``CarDemolished``,
``BoostPadTaken``) and the cars' positions: how a team played together, for match summaries, league reports and
training logs.

Definitions (also in docs/guides/team-play.md, "Team metrics"):

- **touch**: the first tick of a car's contact with the ball (a dribble is one touch).
- **pass**: a touch by car B after one by its team-mate A, with no touch by anyone in between, at least
  ``DOUBLE_COMMIT_S`` and at most ``PASS_MAX_S`` after A last had the ball. Credited to A (the passer).
- **assist**: a pass whose receiver scores, with nobody else touching the ball in between, within
  ``ASSIST_MAX_S`` of receiving it. Credited to the passer.
- **double commit**: a touch by a car less than ``DOUBLE_COMMIT_S`` after a team-mate last had the ball (whoever
  touched it between). Credited to the later car.
- **mean team-mate distance** (uu): the distance between two live team-mates, averaged over the pairs and over
  the decisions of live play (not during kickoff countdowns); none for a team of one.
- **last back share**: for each car, the share of live-play decisions in which it was the team's live car nearest
  its own goal line.
- **demos**: cars demolished by this car (``CarDemolished`` events; bumps do not count).
- **boost collected**: boost gained from pads (``BoostPadTaken.amount``; a pad taken with a full tank gives 0).

A goal or a kickoff ends every chain: a pass, assist or double commit never spans two kickoffs.
"""
from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from rocketdrl_ma.physics import PhysicsEvent, PhysicsEventKind

from .state import BLUE, TEAM_NAMES, agent_team

DOUBLE_COMMIT_S = 1.0
PASS_MAX_S = 4.0
ASSIST_MAX_S = 5.0
#: per-car counters, in summary order
CAR_METRICS = ("passes", "assists", "double_commits", "demos", "boost_collected", "last_back_share")
TEAM_METRICS = ("passes", "assists", "double_commits", "demos", "boost_collected", "mean_teammate_distance_uu")
#: one number per team and match for training logs: the team totals, and how much of the time its most-back car was
#: last back (1.0 for a team of one; 1 / team size for a team that shares the job evenly)
TEAM_LOG_METRICS = TEAM_METRICS + ("last_back_max_share",)


@dataclass
class _Pass:
    passer: str
    receiver: str
    tick: int  # the receiver's touch


@dataclass
class _CarCounts:
    passes: int = 0
    assists: int = 0
    double_commits: int = 0
    demos: int = 0
    boost_collected: float = 0.0
    last_back: int = 0


@dataclass
class _TeamCounts:
    samples: int = 0          # live-play decisions seen
    distance_sum_uu: float = 0.0
    distance_samples: int = 0
    open_pass: _Pass | None = field(default=None)  # the last pass, while it can still become an assist


class TeamMetrics:
    """Counts the team metrics of one match; ``Match`` feeds it every tick's physics events, every decision's car
    positions and every goal."""

    def __init__(self, agents: Sequence[str], tick_rate: float):
        self.agents = list(agents)
        self.tick_rate = float(tick_rate)
        self.reset()

    def reset(self) -> None:
        self.cars = {agent: _CarCounts() for agent in self.agents}
        self.teams = {team: _TeamCounts() for team in range(len(TEAM_NAMES))}
        self._touching: set[str] = set()
        self.end_chains()

    def end_chains(self) -> None:
        """A goal or kickoff: nothing before it pairs with anything after it."""
        self._last_contact: dict[str, int] = {}  # agent -> last tick it was in contact with the ball
        self._last_toucher: str | None = None     # who started the latest touch
        for counts in self.teams.values():
            counts.open_pass = None

    # ------------------------------------------------------------------ feeding
    def on_tick(self, events: Sequence[PhysicsEvent], agent_of: Mapping[int, str]) -> None:
        """One tick's physics events; ``agent_of`` maps a car id to its agent."""
        if not events and not self._touching:
            return
        touching: set[str] = set()
        for event in events:
            kind = event.kind
            if kind is PhysicsEventKind.BALL_TOUCH:
                agent = agent_of[event.car_id]
                if agent not in touching:
                    touching.add(agent)
                    if agent not in self._touching:
                        self._touch_started(agent, event.tick)
                    self._last_contact[agent] = event.tick
            elif kind is PhysicsEventKind.DEMO:
                self.cars[agent_of[event.attacker_id]].demos += 1
            elif kind is PhysicsEventKind.BOOST_PICKUP:
                self.cars[agent_of[event.car_id]].boost_collected += float(event.amount)
        self._touching = touching

    def _touch_started(self, agent: str, tick: int) -> None:
        team = agent_team(agent)
        double_commit_ticks = DOUBLE_COMMIT_S * self.tick_rate
        mates = [a for a, t in self._last_contact.items()
                 if a != agent and agent_team(a) == team and tick - t < double_commit_ticks]
        if mates:
            self.cars[agent].double_commits += 1
        previous = self._last_toucher
        for t, counts in self.teams.items():
            if counts.open_pass is not None and counts.open_pass.receiver != agent:
                counts.open_pass = None  # someone else touched it: that pass cannot be an assist any more
        if previous is not None and previous != agent and agent_team(previous) == team:
            gap = tick - self._last_contact[previous]
            if double_commit_ticks <= gap <= PASS_MAX_S * self.tick_rate:
                self.cars[previous].passes += 1
                self.teams[team].open_pass = _Pass(previous, agent, tick)
        self._last_toucher = agent

    def on_goal(self, team: int, scorer: str | None, tick: int) -> None:
        """``team`` scored; ``scorer`` touched the ball last (None: nobody since the kickoff)."""
        open_pass = self.teams[team].open_pass
        if (open_pass is not None and scorer == open_pass.receiver
                and tick - open_pass.tick <= ASSIST_MAX_S * self.tick_rate):
            self.cars[open_pass.passer].assists += 1
        self.end_chains()

    def on_decision(self, positions: Mapping[str, np.ndarray | None]) -> None:
        """The cars' positions (uu) at a decision of live play; None for a demoed car."""
        for team in range(len(TEAM_NAMES)):
            live = [(a, p) for a, p in positions.items() if p is not None and agent_team(a) == team]
            if not live:
                continue
            counts = self.teams[team]
            counts.samples += 1
            # team frame y: blue defends -y, orange +y
            back = min(live, key=lambda ap: (ap[1][1] if team == BLUE else -ap[1][1], ap[0]))
            self.cars[back[0]].last_back += 1
            for (_, p), (_, q) in itertools.combinations(live, 2):
                counts.distance_sum_uu += float(np.linalg.norm(p - q))
                counts.distance_samples += 1

    # ------------------------------------------------------------------ results
    def car_summary(self, agent: str) -> dict[str, float]:
        c, samples = self.cars[agent], self.teams[agent_team(agent)].samples
        return {"passes": c.passes, "assists": c.assists, "double_commits": c.double_commits, "demos": c.demos,
                "boost_collected": round(c.boost_collected, 3),
                "last_back_share": round(c.last_back / samples, 4) if samples else 0.0}

    def summary(self) -> dict[str, dict]:
        """``{"blue": {...}, "orange": {...}}``: each team's totals, mean team-mate distance (None for a team of
        one) and every car's last-back share."""
        out = {}
        for team, name in enumerate(TEAM_NAMES):
            members = [a for a in self.agents if agent_team(a) == team]
            if not members:
                continue
            cars = {a: self.car_summary(a) for a in members}
            counts = self.teams[team]
            distance = (round(counts.distance_sum_uu / counts.distance_samples, 1)
                        if counts.distance_samples else None)
            out[name] = {**{key: sum(cars[a][key] for a in members)
                            for key in ("passes", "assists", "double_commits", "demos")},
                         "boost_collected": round(sum(cars[a]["boost_collected"] for a in members), 3),
                         "mean_teammate_distance_uu": distance,
                         "last_back_share": {a: cars[a]["last_back_share"] for a in members}}
        return out


def team_log_vector(team_summary: Mapping[str, object]) -> list[float]:
    """``TEAM_LOG_METRICS`` of one team's ``TeamMetrics.summary()`` entry (NaN: not defined, a team of one's
    team-mate distance)."""
    shares = team_summary["last_back_share"]
    values = {**team_summary, "last_back_max_share": max(shares.values()) if shares else float("nan")}
    return [float("nan") if values[key] is None else float(values[key]) for key in TEAM_LOG_METRICS]
