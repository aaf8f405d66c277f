"""Observation builders: a ``GameState`` turned into one flat float32 vector per agent.

The interface follows RLGym v2's small composable builders and Gymnasium's spaces:

* ``space(blue_size, orange_size)`` declares the ``Box`` once; it is the same for every agent, float32,
  with finite bounds (slot by slot: flags in [0, 1], signed quantities in [-1, 1]).
* ``reset(state)`` is an optional per-episode hook (a no-op here for every builder).
* ``build(agent, state)`` returns a float32 vector inside that space. The **last step** of every builder
  is a clip to the space's bounds, so a state beyond the scales below (a car past the declared speed
  cap, a ball deep in a goal) saturates instead of leaving the space. Inputs are validated upstream
  (``CarState``/``BallState`` reject NaN), so the clip never hides a bad value, only a large one.

Team frame: orange sees the field turned half a circle about z (x -> -x, y -> -y), so one policy plays
both sides. Positions, velocities and direction vectors map ``v -> (-vx, -vy, vz)``; angular velocity
does the same (a proper rotation about z by pi maps ``(wx, wy, wz) -> (-wx, -wy, wz)``); boost pads are
permuted to the pad at the mirrored position. A blue car at a state and the matching orange car at the
mirrored state (teams swapped) get bit-identical observations.

One family per module: ``base`` (the interface, scales, team frame), ``sensors`` (``GeneralSensors``, 12 general
data sensors of one car, and ``BarrierSensors`` / ``AerialSensors``, the general sensors plus the Barrier and Aerial
minigames' own), ``rays`` (``RaySensor``: a fan of distance rays with a hit class),
``team_relative`` (``TeamRelativeObs``, the full state in the team frame, and ``BatchedTeamRelativeObs``, the
same for every arena of a batch at once) and ``registry`` (``CombinedObs``, concatenation;
``make_obs_builder("general_sensors+ray")`` combines by name). The old names (``seed_sensors``, ``SeedSensors``...)
still work, with a warning naming the new one (``env.renamed``).
"""
from __future__ import annotations

from ..renamed import renamed_class
from .base import (ARENA_DIAGONAL, BALL_ANG_VEL_SCALE, BALL_VEL_SCALE, CAR_ANG_VEL_SCALE, CAR_VEL_SCALE, MIRROR, N_PADS,
                   PAD_MIRROR, POS_SCALE, ObsBuilder, has_flip_available, team_sign)
from .rays import RAY_CLASSES, RaySensor
from .registry import OBS_BUILDERS, CombinedObs, make_obs_builder
from .sensors import AerialSensors, BarrierSensors, GeneralSensors
from .team_relative import (BALL_FEATURES, CAR_FEATURES, GAME_FEATURES, BatchedTeamRelativeObs, TeamRelativeObs,
                            car_features)

__all__ = ["ARENA_DIAGONAL", "BALL_ANG_VEL_SCALE", "BALL_FEATURES", "BALL_VEL_SCALE", "CAR_ANG_VEL_SCALE",
           "CAR_FEATURES", "CAR_VEL_SCALE", "GAME_FEATURES", "MIRROR", "N_PADS", "OBS_BUILDERS", "PAD_MIRROR",
           "POS_SCALE", "RAY_CLASSES", "AerialSensors", "BarrierSensors", "BatchedTeamRelativeObs", "CombinedObs",
           "GeneralSensors", "ObsBuilder", "RaySensor", "TeamRelativeObs", "car_features", "has_flip_available",
           "make_obs_builder", "team_sign"]


def __getattr__(name: str) -> type:
    """The builders' old class names (``SeedSensors``...) still import, with a DeprecationWarning."""
    return renamed_class(__name__, name, globals())
