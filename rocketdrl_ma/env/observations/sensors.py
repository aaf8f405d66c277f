"""Compact sensors: 12 general data sensors of one car (``general_sensors``), and the Barrier and Aerial
minigames' own on top of them (``barrier_sensors``, ``aerial_sensors``), as the predecessor project (the RocketDRL
seed) defined them."""
from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import ATTACKED_GOAL_MOUTH, GameState

from .base import ARENA_DIAGONAL, ObsBuilder, box_space, check_sizes, clip_to_space, team_sign

class GeneralSensors(ObsBuilder):
    """12 general data sensors of one car (18 numbers; 15 without the goal sensor), the RocketDRL seed paper's.

    ====== ================ ======================================================================== =========
    index  sensor           value                                                                    range
    ====== ================ ======================================================================== =========
    0      ready to drive   on the ground and not in a jump                                           {0, 1}
    1      body on ground   ``on_ground`` (at least 3 wheels touching)                                {0, 1}
    2      wheels on ground number of wheels in contact / 4                                           [0, 1]
    3      jumping          ``is_jumping`` (the jump button's held phase)                             {0, 1}
    4      boost amount     boost / 100                                                               [0, 1]
    5      boosting         last control's boost pressed and boost > 0                                {0, 1}
    6      velocity sign    sign of the forward speed (velocity . forward)                            {-1,0,1}
    7      speed            |velocity| / 2300                                                         [0, 1]
    8      steer angle      last control's steer                                                      [-1, 1]
    9-11   rotation         Euler pitch, yaw, roll / pi, in the team frame (see below)                [-1, 1]
    12-14  car -> ball      ball - car in the car's frame (forward, right, up) / ARENA_DIAGONAL       [-1, 1]
    15-17  ball -> goal     opponent goal centre - ball, team frame / ARENA_DIAGONAL (if goal_sensor) [-1, 1]
    ====== ================ ======================================================================== =========

    Euler angles from the team-frame rotation matrix (columns forward ``f``, right ``r``, up ``u``):
    pitch = atan2(f.z, |f.xy|) (nose up > 0), yaw = atan2(f.y, f.x), roll = atan2(r.z, u.z).
    ``ARENA_DIAGONAL`` (~14673 uu) is the longest line through the arena including the goals, so the two
    vectors never saturate. The opponent goal centre is (0, 5120, 321.4) in the team frame for both teams.
    An agent missing from ``state.cars`` observes zeros.
    """

    _LOW = (0, 0, 0, 0, 0, 0, -1, 0, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1)

    def __init__(self, goal_sensor: bool = True):
        if not isinstance(goal_sensor, bool):
            raise ValueError(f"goal_sensor: expected a bool, got {goal_sensor!r}")
        self.goal_sensor = goal_sensor
        self.size = 18 if goal_sensor else 15
        self._space = box_space(self._LOW[:self.size], [1.0] * self.size)

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        check_sizes(blue_size, orange_size)
        return self._space

    def build(self, agent: str, state: GameState) -> np.ndarray:
        sign = team_sign(agent)
        car = state.cars.get(agent)
        out = np.zeros(self.size)
        if car is None:
            return clip_to_space(out, self._space)
        controls = state.last_controls.get(agent) or CarControls()
        rot = car.rot_mat * sign[:, None]  # the team frame: each column mirrored
        forward, right, up = rot[:, 0], rot[:, 1], rot[:, 2]
        forward_speed = float(np.dot(car.vel, car.rot_mat[:, 0]))
        out[0] = float(car.on_ground and not car.is_jumping)
        out[1] = float(car.on_ground)
        out[2] = sum(car.wheels_in_contact) / 4.0
        out[3] = float(car.is_jumping)
        out[4] = car.boost / C.BOOST_MAX
        out[5] = float(controls.boost and car.boost > 0.0)
        out[6] = float(np.sign(forward_speed))
        out[7] = float(np.linalg.norm(car.vel)) / C.CAR_MAX_SPEED
        out[8] = controls.steer
        out[9] = math.atan2(forward[2], math.hypot(forward[0], forward[1])) / math.pi
        out[10] = math.atan2(forward[1], forward[0]) / math.pi
        out[11] = math.atan2(right[2], up[2]) / math.pi
        out[12:15] = car.rot_mat.T @ (state.ball.pos - car.pos) / ARENA_DIAGONAL
        if self.goal_sensor:
            out[15:18] = (ATTACKED_GOAL_MOUTH - state.ball.pos * sign) / ARENA_DIAGONAL
        return clip_to_space(out, self._space)


class BarrierSensors(ObsBuilder):
    """``GeneralSensors`` plus the Barrier sensor (21 numbers; 18 without the goal sensor).

    ====== ================== ==================================================================== =======
    index  sensor             value                                                                range
    ====== ================== ==================================================================== =======
    0-17   general            ``GeneralSensors``                                                      above
    18-20  barrier -> ball    ball - centre of the first ``state.obstacles`` box, team frame,      [-1, 1]
                              / ARENA_DIAGONAL; zeros when there is no barrier
    ====== ================== ==================================================================== =======

    The z part tells a lifted barrier (centre high above the ball) from one standing on the floor.
    """

    def __init__(self, goal_sensor: bool = True):
        self.general = GeneralSensors(goal_sensor)
        self.size = self.general.size + 3
        g = self.general.space(1, 0)
        self._space = box_space(np.concatenate([g.low, [-1.0] * 3]), np.concatenate([g.high, [1.0] * 3]))

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        check_sizes(blue_size, orange_size)
        return self._space

    def build(self, agent: str, state: GameState) -> np.ndarray:
        extra = np.zeros(3)
        if state.obstacles and agent in state.cars:
            extra = (state.ball.pos - np.asarray(state.obstacles[0].center)) * team_sign(agent) / ARENA_DIAGONAL
        return clip_to_space(np.concatenate([self.general.build(agent, state), extra]), self._space)


class AerialSensors(ObsBuilder):
    """``GeneralSensors`` plus the Aerial sensors (22 numbers; 19 without the goal sensor).

    ====== ================== ==================================================================== =======
    index  sensor             value                                                                range
    ====== ================== ==================================================================== =======
    0-17   general            ``GeneralSensors``                                                      above
    18     ball frozen        the ball still hangs where it was placed (``mode_state["ball_frozen"]``) {0, 1}
    19     release countdown  seconds until the ball is released / the release delay                [0, 1]
    20     aerial touch done  this agent made this round's valid aerial touch                       {0, 1}
    21     touch state        1: touched the ball and waiting for reset (not on the ground since),  {0, 1}
                              0: ready
    ====== ================== ==================================================================== =======

    The flags come from ``GameState.mode_state`` (the Aerial minigame fills it); elsewhere they are zeros.
    """

    def __init__(self, goal_sensor: bool = True):
        self.general = GeneralSensors(goal_sensor)
        self.size = self.general.size + 4
        g = self.general.space(1, 0)
        self._space = box_space(np.concatenate([g.low, [0.0] * 4]), np.concatenate([g.high, [1.0] * 4]))

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        check_sizes(blue_size, orange_size)
        return self._space

    def build(self, agent: str, state: GameState) -> np.ndarray:
        mode = state.mode_state
        release_after = float(mode.get("release_after_s", 0.0))
        extra = [float(mode.get("ball_frozen", False)),
                 float(mode.get("release_in_s", 0.0)) / release_after if release_after > 0.0 else 0.0,
                 float(mode.get("aerial_touch_done", {}).get(agent, False)),
                 float(mode.get("touch_waiting_reset", {}).get(agent, False))]
        return clip_to_space(np.concatenate([self.general.build(agent, state), extra]), self._space)
