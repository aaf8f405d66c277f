"""The PettingZoo face: a ``ParallelEnv`` over a ``GameEngine`` of one game, with the learner's side of it.

One decision: actions -> ActionParser -> CarControls -> the engine plays ``tick_skip`` physics ticks with the
rules' logic after each -> GameState -> ObsBuilder (observations) and Rules (rewards per term, terminations,
truncations, events). Observation and action spaces are the same for every agent and declared once.
"""
from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from pettingzoo import ParallelEnv

from rocketdrl_ma.config import load_config
from rocketdrl_ma.engine import GameEngine
from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.physics import constants as C

from .learner_game import (COUNTED_EVENTS, STATE_CAR_FEATURES, LearnerGame, check_seed, flat_numbers,
                           global_state_vector)

__all__ = ["COUNTED_EVENTS", "STATE_CAR_FEATURES", "RocketDRLParallelEnv", "check_seed", "flat_numbers",
           "global_state_vector"]


class RocketDRLParallelEnv(LearnerGame, ParallelEnv):
    """Car football for multi-agent RL. Agents are ``blue_0..`` and ``orange_0..``.

    ``config`` is a YAML path (``matches/2v2.yaml``), a dict, or None for a 1v1 match; keyword overrides
    replace keys (dict-valued ones such as ``rewards`` merge).

    ``infos[agent]`` (``info_format: full``, the default) holds the scoreboard, this decision's events
    and the reward broken down per term; at the episode's end also ``summary``. Frameworks that turn
    infos into tensors (torchrl's ``PettingZooWrapper``) need the same keys and shapes every step:
    ``info_format: numeric`` gives flat floats instead: the scoreboard's numbers (``score_blue``, ...),
    this agent's count of each event kind in ``COUNTED_EVENTS`` this decision, and ``reward_<term>``.

    ``play(controls, actions)`` is a step in which some cars (scripted bots) drive with ``CarControls`` directly.
    """

    metadata = {"name": "rocketdrl_ma_v0", "render_modes": ["human", "rgb_array"], "is_parallelizable": True,
                "render_fps": C.TICK_RATE_HZ / 8}

    def __init__(self, config: str | Path | dict | None = "matches/1v1.yaml", render_mode: str | None = None,
                 **overrides: Any):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode: {render_mode!r} is not one of {self.metadata['render_modes']} or None")
        config = load_config(config, overrides)
        self.engine = GameEngine.from_config(config, n_games=1)
        super().__init__(config, self.engine.games[0])
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": C.TICK_RATE_HZ / self.tick_skip}
        self._renderer = None
        self._frames: list = []
        self._replay = None

    # ------------------------------------------------------------------ copies
    def __getstate__(self) -> dict:
        """``copy.deepcopy``, ``pickle`` and ``cloudpickle`` give an independent env in this env's state: its own
        PyBullet world restored from this one's (see ``PhysicsWorld.__getstate__``), the same rules, random
        generators and episode, so it returns the same observations and, under the same actions, the same future,
        bit for bit. A copy does not carry the renderer (it makes its own when it first renders) or a replay being
        recorded (that file belongs to this env)."""
        state = self.__dict__.copy()
        state["_renderer"] = None
        state["_replay"] = None
        return state

    # ------------------------------------------------------------------ episode
    def reset(self, seed: int | None = None, options: dict | None = None):
        seed = check_seed(seed)
        if options is not None and not isinstance(options, dict):
            raise ValueError(f"options: expected a dict or None, got {type(options).__name__} {options!r}")
        engine = self.engine
        if seed is not None or engine.rngs[0] is None:
            self._action_space.seed(seed)
        used = engine.is_used(0)
        state = engine.reset_game(0, seed)
        if seed is not None and used:
            # The rules have put every car: a new PyBullet world with them (about 18 ms in 3v3) makes a used env
            # replay a fresh env's game exactly.
            engine.renew_world()
        self._frames = []
        observations, infos = self.start(state)
        self._after_decision(state)
        return observations, infos

    def step(self, actions: dict):
        return self.play({}, actions)

    def play(self, controls: Mapping[str, CarControls], actions: Mapping | None = None, observe: bool = True):
        """A step in which the live agents in ``controls`` drive with those ``CarControls`` (scripted bots, a match
        server's checked actions) and the others' ``actions`` go through the action parser; ``observe=False``
        leaves the observations out (a face whose players observe for themselves)."""
        state = self.engine.step([self.controls(actions, controls)])[0]
        results = self.finish(state, observe=observe)
        self._after_decision(state)
        return results

    def _after_decision(self, state) -> None:
        if self._replay is not None:
            self._replay.add(state)
            if not self.agents:
                self.stop_replay()
        if self.render_mode == "human":
            self.render()

    # ------------------------------------------------------------------ rendering, video, replays
    def render(self) -> np.ndarray | None:
        if self.render_mode is None or self._state is None:
            return None
        if self.render_mode == "human":
            sb = self.rules.scoreboard()
            score = sb.get("score", {})
            print(f"\r[{self._state.tick / C.TICK_RATE_HZ:7.1f} s] blue {score.get('blue', 0)} - "
                  f"{score.get('orange', 0)} orange  clock {sb.get('clock_s', 0):6.1f}"
                  f"{'  OT' if sb.get('overtime') else ''}", end="", file=sys.stderr)
            return None
        if self._renderer is None:
            from .render import Renderer
            self._renderer = Renderer(arena_shape=self.rules.arena_shape)
        frame = self._renderer.render(self._state)
        self._frames.append(frame)
        return frame

    def save_video(self, path: str | Path, fps: float | None = None) -> None:
        """Write the frames ``render()`` produced since the last reset as an mp4 or gif."""
        from .render import save_video
        if not self._frames:
            raise ValueError("save_video: no frames; use render_mode='rgb_array' and call render() each step")
        save_video(self._frames, str(path), fps or self.metadata["render_fps"])

    def start_replay(self, path: str | Path) -> None:
        """Record every decision's state to a replay file (closed at the episode's end or on close)."""
        from .replay import ReplayWriter
        self.stop_replay()
        self._replay = ReplayWriter(str(path), meta={"config": self.config, "agents": self.possible_agents,
                                                     "tick_skip": self.tick_skip})
        if self._state is not None:
            self._replay.add(self._state)

    def stop_replay(self) -> None:
        if self._replay is not None:
            self._replay.close()
            self._replay = None

    def close(self) -> None:
        self.stop_replay()
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self.engine.close()
