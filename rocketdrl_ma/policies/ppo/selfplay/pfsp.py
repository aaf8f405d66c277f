"""Prioritised fictitious self-play (AlphaStar): pick opponent B with probability proportional to
``f(P[learner beats B])``, so the opponents the learner loses to come up most often.

``hard``: ``f(x) = (1 - x) ** p`` (the hardest opponents); ``variance``: ``f(x) = x (1 - x)`` (the even
ones). P is the learner's points rate (win 1, draw 0.5) over its last ``window`` matches against B,
with one win and one loss of prior so an opponent never played yet counts as even (x = 0.5).
"""
from __future__ import annotations

import collections

import numpy as np

WEIGHTINGS = ("hard", "variance")


class PFSP:
    def __init__(self, weighting: str = "hard", p: float = 2.0, window: int = 50):
        if weighting not in WEIGHTINGS:
            raise ValueError(f"selfplay.weighting: {weighting!r} is not one of {list(WEIGHTINGS)}")
        self.weighting, self.p, self.window = weighting, float(p), int(window)
        self.results: dict[str, collections.deque] = {}

    def add_opponent(self, name: str) -> None:
        self.results.setdefault(name, collections.deque(maxlen=self.window))

    def remove_opponent(self, name: str) -> None:
        self.results.pop(name, None)

    def record(self, name: str, points: float) -> None:
        """The learner's result against ``name``: 1 win, 0.5 draw, 0 loss."""
        if name in self.results:
            self.results[name].append(float(points))

    def win_rate(self, name: str) -> float:
        games = self.results[name]
        return (sum(games) + 1.0) / (len(games) + 2.0)

    def weights(self) -> dict[str, float]:
        """Normalised selection probabilities of every opponent in the pool."""
        raw = {}
        for name in self.results:
            x = self.win_rate(name)
            raw[name] = (1.0 - x) ** self.p if self.weighting == "hard" else x * (1.0 - x)
        total = sum(raw.values())
        if total <= 0.0:  # every opponent beaten every time: fall back to uniform
            return {name: 1.0 / len(raw) for name in raw}
        return {name: w / total for name, w in raw.items()}

    def sample(self, rng: np.random.Generator) -> str:
        if not self.results:
            raise ValueError("selfplay: the opponent pool is empty")
        weights = self.weights()
        names = list(weights)
        return names[int(rng.choice(len(names), p=np.array([weights[n] for n in names])))]
