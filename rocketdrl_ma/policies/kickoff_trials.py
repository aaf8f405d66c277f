"""Every kickoff a match can have, played by rotators against flip-chasers with the real countdown: what the
rotator's kickoff tables (``RotatorTuning.kickoff``) are searched by (``tools/search_kickoffs.py``) and tested by.

A kickoff is fixed by its layout (the spots the cars start on), the end the rotators defend and its decision
phase: a kickoff after a goal starts its 3 s countdown at the goal's tick, so the countdown ends 0 to 7 physics ticks
into a decision of 8. The same layout, end and phase play the same kickoff to the tick, so a match's kickoffs are
draws from this finite set, not a sample of something larger.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from itertools import repeat

import numpy as np

from rocketdrl_ma.engine import GameEngine
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules import Match

from .rotator_tuning import RotatorTuning
from .scripted import FlipChaser, Rotator

COUNTDOWN_S = 3.0
DECISION_TICKS = 8  # tick_skip of every match config: the phases a countdown can end at
ENDS = ("blue", "orange")  # the rotators' team
#: every match's first kickoff is at phase 0, later ones at any of the 8: with about 6.4 goals a match, a quarter of
#: a match's kickoffs are at phase 0 and a ninth at each other phase, so phase 0 counts 2.25 times as much
PHASE_0_WEIGHT = 2.25


@dataclass(frozen=True)
class Kickoff:
    seed: int          # a match reset with this seed deals the layout
    rotator_team: str  # "blue" or "orange"
    phase_ticks: int   # the countdown ends this many physics ticks into a decision (0..7)

    @property
    def weight(self) -> float:
        return PHASE_0_WEIGHT if self.phase_ticks == 0 else 1.0


@dataclass(frozen=True)
class Tally:
    """Goals within the horizon over a set of kickoffs, from the rotators' side."""
    scored: int
    conceded: int
    weighted_net: float  # scored - conceded, each kickoff at its ``Kickoff.weight``
    by_phase: dict[int, tuple[int, int]]  # phase -> (scored, conceded)


def layout_seeds(team_size: int) -> list[int]:
    """The first seed that deals each kickoff layout of a ``team_size`` game (every ordered choice of spots), in the
    order found. One match is reset with every seed: a reset draws what a fresh match's would."""
    layouts: dict[tuple, int] = {}
    seed = 0
    m = Match(team_size=team_size, kickoff_countdown_s=COUNTDOWN_S)
    engine = GameEngine([m])
    while len(layouts) < math.perm(len(C.KICKOFF_SPOTS_BLUE), team_size):
        engine.reset_game(0, seed)
        spots = tuple(tuple(m.game_state().cars[f"blue_{i}"].pos[:2].round()) for i in range(team_size))
        layouts.setdefault(spots, seed)
        seed += 1
    return list(layouts.values())


def every_kickoff(team_size: int, phases: Iterable[int] = range(DECISION_TICKS)) -> list[Kickoff]:
    """Each layout from both ends at each of ``phases``."""
    phases = list(phases)
    return [Kickoff(seed, team, phase) for seed in layout_seeds(team_size) for team in ENDS for phase in phases]


def one_phase_each(team_size: int) -> list[Kickoff]:
    """Each layout from both ends at one phase each, the phases taken in turn (and the two ends of a layout 4
    apart), so every phase is played about as often: an eighth of ``every_kickoff``."""
    return [Kickoff(seed, team, (k + 4 * end) % DECISION_TICKS)
            for k, seed in enumerate(layout_seeds(team_size)) for end, team in enumerate(ENDS)]


def play_kickoff(tuning: RotatorTuning, team_size: int, kickoff: Kickoff, horizon_s: float) -> tuple[bool, bool]:
    """``kickoff`` played by rotators on ``tuning`` against flip-chasers: (the rotators scored within ``horizon_s``
    of the countdown's end, the flip-chasers did)."""
    rotator, chaser = Rotator(tuning), FlipChaser()
    m = Match(team_size=team_size, kickoff_countdown_s=COUNTDOWN_S + kickoff.phase_ticks / C.TICK_RATE_HZ)
    engine = GameEngine([m])
    engine.reset_game(0, kickoff.seed)
    for _ in range(int((COUNTDOWN_S + horizon_s) * C.TICK_RATE_HZ / DECISION_TICKS) + 1):
        state = m.game_state()
        engine.step([{a: (rotator if a.startswith(kickoff.rotator_team) else chaser).controls(a, state)
                      for a in m.cars}], DECISION_TICKS)
        blue, orange = m.game_state().score
        if blue or orange:
            rotators_scored = (blue > 0) == (kickoff.rotator_team == "blue")
            return rotators_scored, not rotators_scored
    return False, False


#: ``map``'s shape: a function and its argument iterables in, results out in order (a process pool's ``map`` fits)
Mapper = Callable[..., Iterator]


def play_kickoffs(tunings: list[RotatorTuning], team_size: int, kickoffs: list[Kickoff], horizon_s: float,
                  mapper: Mapper = map) -> list[Tally]:
    """Every kickoff under each of ``tunings``, through ``mapper``: a process pool's ``map`` plays them in parallel
    (the bots are stateless and every kickoff starts from its seed, so the tallies are those of one process). All
    tunings' kickoffs are submitted before any is waited for."""
    outcomes = [mapper(play_kickoff, repeat(tuning), repeat(team_size), kickoffs, repeat(horizon_s))
                for tuning in tunings]
    return [tally(kickoffs, list(results)) for results in outcomes]


def tally(kickoffs: list[Kickoff], outcomes: list[tuple[bool, bool]]) -> Tally:
    by_phase: dict[int, tuple[int, int]] = {}
    for kickoff, (scored, conceded) in zip(kickoffs, outcomes, strict=True):
        s, c = by_phase.get(kickoff.phase_ticks, (0, 0))
        by_phase[kickoff.phase_ticks] = (s + scored, c + conceded)
    return Tally(scored=sum(s for s, _ in outcomes), conceded=sum(c for _, c in outcomes),
                 weighted_net=sum(k.weight * (s - c) for k, (s, c) in zip(kickoffs, outcomes)),
                 by_phase=dict(sorted(by_phase.items())))
