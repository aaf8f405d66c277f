"""Competitive penalty: a shooter against a goalkeeper, zero-sum (RocketDRL's multi-agent penalty)."""
from __future__ import annotations

from ..mutators import StateMutator
from .penalty import Penalty
from .shot import check_number


class PenaltyDuel(Penalty):
    """``Penalty`` with a goalkeeper: ``blue_0`` shoots at the +y goal, ``orange_0`` starts on that goal's
    line (x within +-``keeper_x_range_uu`` times ``difficulty``) facing the shooter.

    The round ends as in ``Penalty``: a goal for the shooter, or a miss (a save that sends the ball back
    over ``miss_line_y``, a shot wide, the timeout...), which is the keeper's win. Opposite rewards: the
    keeper gets every term negated (``ShotMinigame``), so goal -10, miss +10, time +0.01 per decision with
    the default weights, and the two rewards sum to zero every step. The keeper's ``saves`` count touches
    that take an on-target ball off target.
    """

    KEEPERS = 1

    def __init__(self, keeper_x_range_uu: float = 500.0, **kwargs):
        super().__init__(**kwargs)
        self.keeper_x_range_uu = check_number("keeper_x_range_uu", keeper_x_range_uu, 0.0, 800.0)

    def spawn_mutators(self) -> list[StateMutator]:
        return [self.shot_spawn(keeper_x_uu=self.keeper_x_range_uu)]
