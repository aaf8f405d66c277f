"""What a match keeps for its result: event counts, goals, decision and wait times, and the ``MatchResult`` that
goes to the server's results store."""
from __future__ import annotations

from collections import Counter

import numpy as np

from rocketdrl_ma.results import MatchResult
from rocketdrl_ma.rules.events import GameEvent, Goal
from rocketdrl_ma.rules.state import GameState


def _percentile_ms(values: list[float], q: float) -> float | None:
    return round(float(np.percentile(values, q)) * 1e3, 3) if values else None


class MatchRecord:
    """One match's running tally: ``decision_s`` (each decision's wall time) and ``wait_s`` (the part spent waiting
    for remote bots) as the match loop appends them, the events it counts."""

    def __init__(self) -> None:
        self.event_counts: Counter = Counter()
        self.goals: list[dict] = []
        self.decision_s: list[float] = []
        self.wait_s: list[float] = []

    def count_events(self, events: list[GameEvent]) -> None:
        for event in events:
            self.event_counts[event.kind.value] += 1
            if isinstance(event, Goal):
                self.goals.append({k: v for k, v in event.as_dict().items() if k != "kind"})

    def timing(self) -> dict:
        return {"decisions": len(self.decision_s), "decision_ms_median": _percentile_ms(self.decision_s, 50),
                "decision_ms_p99": _percentile_ms(self.decision_s, 99),
                "wait_ms_median": _percentile_ms(self.wait_s, 50), "wait_ms_p99": _percentile_ms(self.wait_s, 99),
                "wall_s": round(sum(self.decision_s), 4)}

    def result(self, key: str, config: dict, entrants: dict[str, str], state: GameState, seed: int,
               summary: dict, about: dict, bots: dict[str, dict], rejected: dict) -> MatchResult:
        """The finished match's result under ``key``: ``about`` (match id, mode, options) first in its details, then
        the tally's events, goals, stats, each bot's missed decisions, the ``bots``, ``rejected`` and timing."""
        return MatchResult(
            match_key=key, source="server", config=config, entrants=entrants,
            score_blue=int(state.score[0]), score_orange=int(state.score[1]),
            duration_s=state.tick / state.tick_rate, seed=seed,
            details={**about, "events": dict(self.event_counts), "goals": self.goals,
                     "stats": summary.get("stats", {}), "overtime": bool(summary.get("overtime", False)),
                     "missed_decisions": {n: s["missed"] + s["disconnected"] for n, s in bots.items()},
                     "bots": bots, "rejected": rejected, "timing": self.timing()})
