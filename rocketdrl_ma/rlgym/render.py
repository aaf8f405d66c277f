"""Drawing RLGym Rocket League states with our headless renderer (``rocketdrl_ma.env.render``).

``RLGymRenderer`` is an RLGym ``Renderer``: pass it as ``RLGym(..., renderer=RLGymRenderer())`` and every
``env.render()`` draws the current ``GameState`` (of ``RocketDRLEngine`` or ``RocketSimEngine``) to an RGB frame,
kept as ``last_frame`` and, given ``video_path``, appended to a video. ``rules_game_state`` converts an RLGym state
to the snapshot type our renderer, observations and rewards read.
"""
from __future__ import annotations

from typing import Any, Hashable

import numpy as np
from rlgym.api import Renderer as RLGymRendererBase
from rlgym.rocket_league.api import GameState as RLGymGameState

from rocketdrl_ma.env.render import Renderer, VideoWriter
from rocketdrl_ma.physics import BallState
from rocketdrl_ma.physics.arena_shape import DEFAULT_ARENA_SHAPE
from rocketdrl_ma.physics.car_config import PRESETS
from rocketdrl_ma.rules.state import TEAM_NAMES, GameState

from .game_state import HITBOX_PRESETS, car_state

RLGYM_TICK_RATE = 120


def agent_names(cars: dict[Hashable, Any]) -> dict[Hashable, str]:
    """Our ``blue_N`` / ``orange_N`` name of each RLGym agent, numbered per team in the state's order."""
    counts = [0, 0]
    names = {}
    for agent, car in cars.items():
        team = int(car.team_num)
        if team not in (0, 1):
            raise ValueError(f"cars[{agent!r}].team_num: must be 0 (blue) or 1 (orange), got {car.team_num!r}")
        names[agent] = f"{TEAM_NAMES[team]}_{counts[team]}"
        counts[team] += 1
    return names


def rules_game_state(state: RLGymGameState, arena_shape: str = DEFAULT_ARENA_SHAPE) -> GameState:
    """Our ``GameState`` snapshot of an RLGym Rocket League state (cars renamed by ``agent_names``)."""
    if not isinstance(state, RLGymGameState):
        raise ValueError(f"state: expected an rlgym.rocket_league.api.GameState, got {type(state).__name__}")
    names = agent_names(state.cars)
    cars = {names[agent]: car_state(car, agent) for agent, car in state.cars.items()}
    configs = {names[agent]: PRESETS[HITBOX_PRESETS[int(car.hitbox_type)]] for agent, car in state.cars.items()}
    ball = BallState(pos=state.ball.position, vel=state.ball.linear_velocity, ang_vel=state.ball.angular_velocity)
    return GameState(tick=int(state.tick_count), tick_rate=RLGYM_TICK_RATE, cars=cars, ball=ball,
                     pad_timers=np.asarray(state.boost_pad_timers, dtype=np.float64), last_controls={},
                     car_configs=configs, arena_shape=arena_shape)


class RLGymRenderer(RLGymRendererBase[RLGymGameState]):
    """An RLGym ``Renderer`` drawing with our PyBullet TinyRenderer (headless, no display needed).

    :param width: the frame's width in pixels.
    :param height: the frame's height in pixels.
    :param camera: ``"broadcast"`` or ``"top"`` (``rocketdrl_ma.env.render.Renderer``'s cameras).
    :param arena_shape: the arena drawn: ``"classic"`` or ``"game"`` (as the engine's).
    :param video_path: if given (``.mp4`` or ``.gif``), every frame is appended to this video, written on
        ``close()``.
    :param fps: the video's frame rate.
    """

    def __init__(self, width: int = 640, height: int = 360, camera: str = "broadcast",
                 arena_shape: str = DEFAULT_ARENA_SHAPE, video_path: str | None = None, fps: float = 15.0):
        self._renderer = Renderer(width, height, camera, arena_shape=arena_shape, scoreboard=False)
        self.arena_shape = arena_shape
        self._video = VideoWriter(video_path, fps) if video_path is not None else None
        self.last_frame: np.ndarray | None = None

    def render(self, state: RLGymGameState, shared_info: dict[str, Any]) -> np.ndarray:
        """The frame (height, width, 3) uint8 of ``state``; also kept as ``last_frame``."""
        frame = self._renderer.render(rules_game_state(state, self.arena_shape))
        self.last_frame = frame
        if self._video is not None:
            self._video.append(frame)
        return frame

    def close(self) -> None:
        self._renderer.close()
        if self._video is not None:
            self._video.close()
            self._video = None
