"""The full state from one agent's side, in its team frame (``team_relative``), one agent at a time
(``TeamRelativeObs``) or every game of a batch at once (``BatchedTeamRelativeObs``, bit-identical)."""
from __future__ import annotations

import functools
import math

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.physics import ArenaBatch
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.physics.state import CarState
from rocketdrl_ma.rules.state import BLUE, GameState, TEAM_NAMES, agent_number, agent_team

from .base import (BALL_ANG_VEL_SCALE, BALL_VEL_SCALE, CAR_ANG_VEL_SCALE, CAR_VEL_SCALE, CLOCK_SCALE_S, MIRROR, N_PADS,
                   ObsBuilder, PAD_COOLDOWN, PAD_MIRROR, POS_SCALE, SCORE_DIFF_SCALE, box_space, check_sizes,
                   has_flip_available)

CAR_FEATURES = ("pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z", "ang_vel_x", "ang_vel_y", "ang_vel_z",
                "forward_x", "forward_y", "forward_z", "up_x", "up_y", "up_z", "boost", "on_ground",
                "has_flip", "is_demoed", "present")
_CAR_LOW = [-1.0] * 15 + [0.0] * 5
BALL_FEATURES = ("pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z", "ang_vel_x", "ang_vel_y", "ang_vel_z")
GAME_FEATURES = ("score_diff", "clock", "is_overtime", "kickoff_pending")
_GAME_LOW = [-1.0, 0.0, 0.0, 0.0]


_FEATURE_MIRROR = np.concatenate([np.tile(MIRROR, 5), np.ones(5)])  # team frame of CAR_FEATURES for orange
# The divisors of the first 15 car features and of the ball block (1.0 for direction vectors: an exact no-op).
_CAR_SCALE = np.concatenate([POS_SCALE, [CAR_VEL_SCALE] * 3, [CAR_ANG_VEL_SCALE] * 3, np.ones(6)])
_BALL_SCALE = np.concatenate([POS_SCALE, [BALL_VEL_SCALE] * 3, [BALL_ANG_VEL_SCALE] * 3])
_BALL_MIRROR = np.tile(MIRROR, 3)


def car_features(car: CarState | None) -> np.ndarray:
    """``CAR_FEATURES`` of one car in the blue (world) frame, zeros for an absent car; multiply by
    ``_FEATURE_MIRROR`` for orange's frame."""
    features = np.zeros(len(CAR_FEATURES))
    if car is None:
        return features
    np.divide(np.concatenate((car.pos, car.vel, car.ang_vel, car.rot_mat[:, 0], car.rot_mat[:, 2])), _CAR_SCALE,
              out=features[:15])
    features[15:20] = (car.boost / C.BOOST_MAX, float(car.on_ground), float(has_flip_available(car)),
                       float(car.is_demoed), 1.0)
    return features


@functools.lru_cache(maxsize=None)
def _padded_slots(blue_size: int, orange_size: int) -> tuple[int, int]:
    """(teammate slots, opponent slots) that fit every agent of a ``blue_size`` v ``orange_size`` game."""
    teams = [(own, other) for own, other in ((blue_size, orange_size), (orange_size, blue_size)) if own > 0]
    return max(own - 1 for own, _ in teams), max(other for _, other in teams)


class TeamRelativeObs(ObsBuilder):
    """The whole game from one agent's side, in its team frame (orange mirrored; see the module doc).

    Layout for ``T = teammate slots`` and ``O = opponent slots`` (below), all scaled to [-1, 1]:

    ================= ======== ==============================================================================
    block             size     contents
    ================= ======== ==============================================================================
    self              20       ``CAR_FEATURES``: pos / (4096, 6000, 2048), vel / 2300, ang_vel / 5.5,
                               forward (3), up (3), boost / 100, on_ground, has_flip (on the ground, or
                               airborne within 1.25 s of a jump with no double jump or flip used yet),
                               is_demoed, present (1 for a car in ``state.cars``)
    ball              9        pos / (4096, 6000, 2048), vel / 6000, ang_vel / 6
    teammates         20 * T   ``CAR_FEATURES`` of each teammate, by index, self excluded
    opponents         20 * O   ``CAR_FEATURES`` of each opponent, by index
    boost pads        34       seconds until back / the pad's cooldown (0 = available), team-frame pad order
    game              4        tanh((own - opponent score) / 3), clock_s / 300 (clipped to [0, 1]),
                               is_overtime, kickoff_pending
    ================= ======== ==============================================================================

    ``T = max(team size - 1)`` and ``O = max(other team's size)`` over the teams that have cars, so every
    agent gets the same shape; unused slots and cars absent from ``state.cars`` are zeros (``present`` 0).
    A demoed car still appears with ``is_demoed`` 1. Sizes: 1v1 87, 2v2 127, 3v3 167, 4v4 207.

    Unequal teams are padded: in a 1v2 (``T`` 1, ``O`` 2) blue's lone car has an empty team-mate slot and orange's
    cars an empty second opponent slot, so both sides' observations have one shape (127). ``max_team_size``
    (1..4) fixes the layout whatever the game: ``T = max_team_size - 1`` and ``O = max_team_size`` slots, the
    absent cars zero, so one policy (a checkpoint trained with it) plays 1v1, 1v2, 2v2 and 2v1 with the same
    input; a game with a bigger team is a ValueError naming ``max_team_size``.

    ``space(blue_size, orange_size)`` fixes the team sizes for later ``build`` calls; before it is called,
    ``build`` infers them from the agent names in the state. The per-car features of the last state are
    cached for the other agents of the same decision (keyed on the object, which is a read-only snapshot).
    """

    def __init__(self, max_team_size: int | None = None):
        if max_team_size is not None and (isinstance(max_team_size, bool) or not isinstance(max_team_size, int)
                                          or not 1 <= max_team_size <= 4):
            raise ValueError(f"max_team_size: must be an int in 1..4 or null, got {max_team_size!r}")
        self.max_team_size = max_team_size
        self._sizes: tuple[int, int] | None = None
        self._spaces: dict[tuple[int, int], spaces.Box] = {}
        self._cached_state: GameState | None = None  # the last state seen, held so its id cannot be reused
        self._cached_cars: dict[str, np.ndarray] = {}
        self._cached_sizes: tuple[int, int] | None = None
        self._cached_frames: dict[int, tuple] = {}
        self._bounds: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}  # a space's bounds as float64
        self._layouts: dict[tuple[str, int, int], tuple] = {}  # see _layout

    def for_batch(self, agents: list[str], blue_size: int, orange_size: int) -> BatchedTeamRelativeObs:
        """This builder for every agent of every game of a batch at once (``VectorEnv``)."""
        return BatchedTeamRelativeObs(self, agents, blue_size, orange_size)

    def slots(self, blue_size: int, orange_size: int) -> tuple[int, int]:
        """(teammate slots, opponent slots) for this team size."""
        if self.max_team_size is not None:
            for name, size in (("blue_size", blue_size), ("orange_size", orange_size)):
                if size > self.max_team_size:
                    raise ValueError(f"max_team_size: the observation has room for teams of up to "
                                     f"{self.max_team_size} cars, but {name} is {size}")
            return self.max_team_size - 1, self.max_team_size
        return _padded_slots(blue_size, orange_size)

    def size(self, blue_size: int, orange_size: int) -> int:
        mates, opps = self.slots(blue_size, orange_size)
        return len(CAR_FEATURES) * (1 + mates + opps) + len(BALL_FEATURES) + N_PADS + len(GAME_FEATURES)

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        check_sizes(blue_size, orange_size)
        self._sizes = (int(blue_size), int(orange_size))
        return self._make_space(blue_size, orange_size)

    def _make_space(self, blue_size: int, orange_size: int) -> spaces.Box:
        key = (int(blue_size), int(orange_size))
        if key not in self._spaces:
            mates, opps = self.slots(blue_size, orange_size)
            low = _CAR_LOW + [-1.0] * len(BALL_FEATURES) + _CAR_LOW * (mates + opps) + [0.0] * N_PADS + _GAME_LOW
            self._spaces[key] = box_space(low, [1.0] * len(low))
            self._bounds[key] = (self._spaces[key].low.astype(np.float64), self._spaces[key].high.astype(np.float64))
        return self._spaces[key]

    def _team_sizes(self, state: GameState) -> tuple[int, int]:
        if self._sizes is not None:
            return self._sizes
        sizes = [0, 0]
        for name in list(state.cars) + list(state.last_controls) + list(state.car_configs):
            team = agent_team(name)
            sizes[team] = max(sizes[team], agent_number(name) + 1)
        return sizes[0], sizes[1]

    def _layout(self, agent: str, blue_size: int, orange_size: int) -> tuple[tuple[tuple[int, str], ...], int, int]:
        """Where ``agent``'s observation puts each car's block (offset, car), the ball block and the pad timers
        (the game features follow them); worked out and validated once per agent and team sizes."""
        key = (agent, blue_size, orange_size)
        if key not in self._layouts:
            team = agent_team(agent)
            own_size, other_size = (blue_size, orange_size) if team == BLUE else (orange_size, blue_size)
            index = agent_number(agent)
            if not 0 <= index < own_size:
                raise ValueError(f"agent: {agent!r} is not in a {blue_size}v{orange_size} game")
            self._make_space(blue_size, orange_size)
            mates_n, opps_n = self.slots(blue_size, orange_size)
            own, other = TEAM_NAMES[team], TEAM_NAMES[1 - team]
            n_car = len(CAR_FEATURES)
            slots = [(0, agent)]
            at = n_car + len(BALL_FEATURES)
            for i in [i for i in range(own_size) if i != index]:
                slots.append((at, f"{own}_{i}"))
                at += n_car
            at += n_car * (mates_n - (own_size - 1))
            for i in range(other_size):
                slots.append((at, f"{other}_{i}"))
                at += n_car
            at += n_car * (opps_n - other_size)
            self._layouts[key] = (tuple(slots), n_car, at)
        return self._layouts[key]

    def build(self, agent: str, state: GameState) -> np.ndarray:
        team = agent_team(agent)
        blue_size, orange_size = self._team_sizes(state)
        car_slots, ball_at, pads_at = self._layout(agent, blue_size, orange_size)
        # Every agent of one decision shares the per-car features and the team frames' blocks.
        if self._cached_state is not state or self._cached_sizes != (blue_size, orange_size):
            for name in state.cars:
                t, i = agent_team(name), agent_number(name)
                if i >= (blue_size, orange_size)[t]:
                    raise ValueError(f"state.cars: {name!r} is not in a {blue_size}v{orange_size} game")
            self._cached_cars = {name: car_features(car) for name, car in state.cars.items()}
            self._cached_frames = {}
            self._cached_state, self._cached_sizes = state, (blue_size, orange_size)
        if team not in self._cached_frames:
            self._cached_frames[team] = self._team_frame(team, state)
        cars, ball_block, timers = self._cached_frames[team]
        low, high = self._bounds[(blue_size, orange_size)]
        # Filled block by block in the layout above; absent cars and unused slots stay zero.
        out = np.zeros(len(low))
        n_car = len(CAR_FEATURES)
        for at, name in car_slots:
            features = cars.get(name)
            if features is not None:
                out[at:at + n_car] = features
        out[ball_at:ball_at + len(BALL_FEATURES)] = ball_block
        out[pads_at:pads_at + N_PADS] = timers
        own_score, other_score = state.score[team], state.score[1 - team]
        out[pads_at + N_PADS:] = (math.tanh((own_score - other_score) / SCORE_DIFF_SCALE),
                                  state.clock_s / CLOCK_SCALE_S, float(state.is_overtime), float(state.kickoff_pending))
        # clip_to_space's clip and cast, with the bounds already in float64 (the same values)
        return np.clip(out, low, high, out=out).astype(np.float32)

    def _team_frame(self, team: int, state: GameState) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
        """What every agent of ``team`` sees alike: car features, the ball block and pad timers in the team's
        frame."""
        ball = state.ball
        ball_block = np.concatenate((ball.pos, ball.vel, ball.ang_vel))
        timers = np.asarray(state.pad_timers, dtype=np.float64) / PAD_COOLDOWN
        if team == BLUE:  # the world frame: the features as they are (build copies them into its output)
            return self._cached_cars, ball_block / _BALL_SCALE, timers
        cars = {name: features * _FEATURE_MIRROR for name, features in self._cached_cars.items()}
        return cars, ball_block * _BALL_MIRROR / _BALL_SCALE, timers[PAD_MIRROR]


class BatchedTeamRelativeObs:
    """``TeamRelativeObs`` for ``agents`` (every car present) in all games of a batch: ``[n_games, agents, dim]``."""

    def __init__(self, builder: TeamRelativeObs, agents: list[str], blue_size: int, orange_size: int):
        self.agents = list(agents)
        self._layouts = [builder._layout(agent, blue_size, orange_size) for agent in self.agents]
        self.low, self.high = builder._bounds[(blue_size, orange_size)]
        self._teams = [agent_team(agent) for agent in self.agents]
        self._column = {agent: j for j, agent in enumerate(self.agents)}

    def build(self, batch: ArenaBatch, car_rows: np.ndarray, states: list[GameState]) -> np.ndarray | None:
        """Observations of game ``k``'s agents from the batch arrays; ``car_rows[k, j]`` is the batch row of game
        ``k``'s car of ``agents[j]`` and ``states[k]`` that game's state now (for score and clock). None when a car
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
