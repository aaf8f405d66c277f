"""Team-relative observations of every arena of a ``VectorEnv`` at once, straight from the batch's arrays.

``TeamRelativeObs.build`` (one agent, one ``GameState``) stays the reference: this computes the same numbers
with whole-array operations that repeat its arithmetic element by element (the same divisions, mirror products,
``math.tanh`` and clip), so the rows are bit-identical; ``tests/env/test_batched_obs.py`` checks that. It pays
for itself once a batch has a few arenas: the per-agent Python of ``build`` ran once per agent and decision.
"""
from __future__ import annotations

import math

import numpy as np

from rocketdrl_ma.physics import ArenaBatch
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import BLUE, GameState, agent_team

from .observations import (_BALL_MIRROR, _BALL_SCALE, _CAR_SCALE, _FEATURE_MIRROR, BALL_FEATURES, CAR_FEATURES,
                           CLOCK_SCALE_S, N_PADS, PAD_COOLDOWN, PAD_MIRROR, SCORE_DIFF_SCALE, TeamRelativeObs)


class BatchedTeamRelativeObs:
    """``TeamRelativeObs`` for ``agents`` (every car present) in all arenas of a batch: ``[n_arenas, agents, dim]``."""

    def __init__(self, builder: TeamRelativeObs, agents: list[str], blue_size: int, orange_size: int):
        self.agents = list(agents)
        self._layouts = [builder._layout(agent, blue_size, orange_size) for agent in self.agents]
        self.low, self.high = builder._bounds[(blue_size, orange_size)]
        self._teams = [agent_team(agent) for agent in self.agents]
        self._column = {agent: j for j, agent in enumerate(self.agents)}

    def build(self, batch: ArenaBatch, car_rows: np.ndarray, states: list[GameState]) -> np.ndarray | None:
        """Observations of arena ``k``'s agents from the batch arrays; ``car_rows[k, j]`` is the batch row of arena
        ``k``'s car of ``agents[j]`` and ``states[k]`` that arena's state now (for score and clock). None when a car
        is missing from a state (then ``build`` has zeros to write: use the reference per agent)."""
        n_agents = len(self.agents)
        if any(len(state.cars) != n_agents for state in states):
            return None
        a = batch.arrays()
        world = np.zeros(car_rows.shape + (len(CAR_FEATURES),))  # car_features of every car, world frame
        rot = a.car_rot[car_rows]
        np.divide(np.concatenate((a.car_pos[car_rows], a.car_vel[car_rows], a.car_ang_vel[car_rows],
                                  rot[..., 0], rot[..., 2]), axis=-1),
                  _CAR_SCALE, out=world[..., :15])
        on_ground = a.car_on_ground[car_rows] != 0.0  # bool() of the state's float, as CarState holds it
        world[..., 15] = a.car_boost[car_rows] / C.BOOST_MAX
        world[..., 16] = on_ground
        world[..., 17] = on_ground | ((a.car_has_double_jumped[car_rows] == 0.0) & (a.car_has_flipped[car_rows] == 0.0)
                                      & (a.car_air_time_since_jump[car_rows] < C.DOUBLEJUMP_MAX_DELAY))
        world[..., 18] = a.car_is_demoed[car_rows] != 0.0
        world[..., 19] = 1.0
        ball = np.concatenate((a.ball_pos, a.ball_vel, a.ball_ang_vel), axis=1)[:len(states)]
        timers = a.pad_timers[:len(states)] / PAD_COOLDOWN
        frames = {BLUE: (world, ball / _BALL_SCALE, timers)}
        if any(team != BLUE for team in self._teams):
            frames[1 - BLUE] = (world * _FEATURE_MIRROR, ball * _BALL_MIRROR / _BALL_SCALE, timers[:, PAD_MIRROR])
        out = np.zeros(car_rows.shape + (len(self.low),))
        n_car = len(CAR_FEATURES)
        for j, ((car_slots, ball_at, pads_at), team) in enumerate(zip(self._layouts, self._teams)):
            cars, ball_block, pads = frames[team]
            for at, name in car_slots:
                out[:, j, at:at + n_car] = cars[:, self._column[name]]
            out[:, j, ball_at:ball_at + len(BALL_FEATURES)] = ball_block
            out[:, j, pads_at:pads_at + N_PADS] = pads
            out[:, j, pads_at + N_PADS:] = [
                (math.tanh((s.score[team] - s.score[1 - team]) / SCORE_DIFF_SCALE), s.clock_s / CLOCK_SCALE_S,
                 float(s.is_overtime), float(s.kickoff_pending)) for s in states]
        return np.clip(out, self.low, self.high, out=out).astype(np.float32)
