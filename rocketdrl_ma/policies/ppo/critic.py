"""What the critic reads: the car's own observation (``critic: local``, IPPO) or its whole team's (``central``, MAPPO).

A centralised critic (MAPPO, Yu et al. 2022; torchrl's ``sota-implementations/multiagent/mappo_ippo.py``) is used
only while training, so it may see more than the actor: the policy still acts on each car's own observation, and
the value that baselines its advantages is learned from the team's. Here the central input of a car is the
concatenation of every team-mate's model input (observation, its ``features``, normalised), **its own first**, then
the others in slot order. That is torchrl's ``MultiAgentMLP(centralised=True)`` input with the "agent-specific"
ordering of the MAPPO paper: one shared value network, yet a value per car, as each car has its own rewards (its
touches, its shaping) here.

Why the team's observations rather than ``env.state()``: ``state()`` is the whole game in the blue frame, so a
policy shared by both sides would have to mirror it for orange (positions, velocities, the pad order, the score
sign) to learn side-independent values; the ``team_relative`` observations are already mirrored and already hold
the ball, every car, the pads and the clock, and their ``car_local`` features add what ``state()`` lacks: each
team-mate's own view of the ball (the ball in its car's frame), which is what decides whether it, not this car,
gets to the ball first. The learner's batch already holds every team-mate's observation (the rows of an env copy
are its cars), so the rollout workers, the env and the checkpoints' actor stay as they are; with an observation
that sees less than everything (``rays``, ``general_sensors``) the central input is also more information.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

CRITICS = ("local", "central")


def team_order(row_teams: Sequence[str], critic: str) -> np.ndarray:
    """[rows of a copy, k]: for each row of an env copy, the rows of the copy its critic reads, its own first,
    then its team-mates in order (``row_teams``: the team of each row). ``local``: k = 1, the row itself."""
    rows = np.arange(len(row_teams))
    if critic == "local":
        return rows[:, None]
    teams = {team: [r for r in rows if row_teams[r] == team] for team in dict.fromkeys(row_teams)}
    sizes = {team: len(members) for team, members in teams.items()}
    if len(set(sizes.values())) != 1:
        raise ValueError(f"critic: 'central' needs teams of one size (its input is a team's observations), "
                         f"got teams of {sizes}; use critic: local")
    return np.array([[r] + [m for m in teams[row_teams[r]] if m != r] for r in rows])


def critic_input(x: torch.Tensor, order: torch.Tensor) -> torch.Tensor:
    """[rows, T, D] model inputs (rows copy by copy, as the rollout workers give them) to [rows, T, k * D]: each
    row's input followed by its team-mates' at the same decision, in ``order`` ([rows of a copy, k])."""
    rows, horizon, dim = x.shape
    per_copy, k = order.shape
    by_copy = x.reshape(rows // per_copy, per_copy, horizon, dim)
    gathered = by_copy[:, order]  # [copies, rows of a copy, k, T, D]
    return gathered.permute(0, 1, 3, 2, 4).reshape(rows, horizon, k * dim)
