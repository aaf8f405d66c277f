"""Controls as rows of numbers, and at float32 resolution: that of the learners' actions and of the wire.

Where scripted bots play a learner's game (``play``, league matches, evaluation, self-play opponents, fixed teams)
their ``CarControls`` go in at float32 resolution, as a parsed action and a remote bot's action (Zenoh carries
actions as float32) arrive: a bot then drives a car identically in this process and through the match server, and
a recorded league replays bit for bit.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rocketdrl_ma.physics import CarControls

N_CONTROLS = 8  # throttle, steer, pitch, yaw, roll, jump, boost, handbrake (``CarControls.as_array``)


def _from_row(row: np.ndarray) -> CarControls:
    return CarControls(*row[:5].tolist(), jump=row[5] > 0.5, boost=row[6] > 0.5, handbrake=row[7] > 0.5)


def float32_controls(controls: Mapping[str, CarControls]) -> dict[str, CarControls]:
    """Each agent's controls at float32 resolution (controls already there are kept as they are)."""
    out = {}
    for agent, given in controls.items():
        if not isinstance(given, CarControls):
            raise ValueError(f"controls for {agent}: expected CarControls, got {type(given).__name__}")
        row = given.as_array()
        played = row.astype(np.float32).astype(np.float64)
        out[agent] = given if np.array_equal(played, row) else _from_row(played)
    return out


def controls_from_rows(rows: np.ndarray, agents: Sequence[str]) -> dict[str, CarControls]:
    """``rows`` ``[len(agents), 8]`` (throttle, steer, pitch, yaw, roll in [-1, 1]; buttons pressed above 0.5) as
    each agent's ``CarControls``; ValueError naming the field if a number is out of range."""
    rows = np.asarray(rows, dtype=np.float64)
    if rows.shape != (len(agents), N_CONTROLS):
        raise ValueError(f"controls: expected shape ({len(agents)}, {N_CONTROLS}) (cars, controls), got {rows.shape}")
    return {agent: _from_row(row) for agent, row in zip(agents, rows)}
