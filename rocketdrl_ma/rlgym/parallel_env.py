"""``RLGymParallelEnv``: any RLGym v2 env (``rlgym.api.RLGym``, on any engine) as a PettingZoo ``ParallelEnv``.

RLGym speaks in space tuples (``('real', n)``, ``('discrete', n)``) and has no seeds, no infos and no agent
removal; PettingZoo users expect gymnasium spaces, ``reset(seed=...)`` and the ``agents`` list emptying at the end.
The wrapper adds exactly that:

- spaces: ``('real', n)`` is ``Box(-inf, inf, (n,), float32)``, ``('discrete', n)`` ``Discrete(n)``,
  ``('multi_discrete', [n, ...])`` ``MultiDiscrete``, a gymnasium ``Space`` passes through; observations are
  cast to the space's dtype; a ``Discrete`` action ``a`` reaches the action parser as ``np.array([a])`` (the shape
  ``LookupTableAction`` takes), other actions as arrays.
- seeds: RLGym's components draw from Python's ``random`` and NumPy's global generator (``KickoffMutator``
  shuffles with ``random.shuffle``); ``reset(seed=s)`` seeds both, so a seeded episode replays exactly.
- episode end: RLGym episodes end for everyone (RLGym's own loop resets when any agent is done): once any agent
  is terminated or truncated, every agent leaves ``agents``; those RLGym did not flag are reported truncated.
- global state (Rocket League states): ``state()`` is one float32 vector for centralised critics, laid out as
  ``STATE_LAYOUT`` describes; ``state_space`` is its ``Box``.
- rendering: ``render_mode="rgb_array"`` draws the state with our headless renderer (``RLGymRenderer``);
  ``"human"`` calls the env's own RLGym ``Renderer``.
"""
from __future__ import annotations

import random
from typing import Any, Hashable

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv
from rlgym.api import RLGym
from rlgym.rocket_league.api import GameState
from rlgym.rocket_league.common_values import BOOST_LOCATIONS

from .render import RLGymRenderer

AgentID = Hashable


def gymnasium_space(space: Any, what: str = "space") -> spaces.Space:
    """The gymnasium space of an RLGym space tuple (or a gymnasium space, unchanged)."""
    if isinstance(space, spaces.Space):
        return space
    if isinstance(space, tuple) and len(space) == 2 and isinstance(space[0], str):
        kind, size = space
        if kind == "real" and isinstance(size, (int, np.integer)) and size > 0:
            return spaces.Box(-np.inf, np.inf, shape=(int(size),), dtype=np.float32)
        if kind == "discrete" and isinstance(size, (int, np.integer)) and size > 0:
            return spaces.Discrete(int(size))
        if kind == "multi_discrete":
            return spaces.MultiDiscrete(np.asarray(size, dtype=np.int64))
    raise ValueError(f"{what}: expected a gymnasium Space or an RLGym space tuple ('real', n > 0), "
                     f"('discrete', n > 0) or ('multi_discrete', [n, ...]), got {space!r} (an observation builder "
                     f"whose size depends on the state, e.g. DefaultObs(zero_padding=None), knows it after a reset)")


BALL_STATE_FIELDS = ("position", "linear_velocity", "angular_velocity")  # 3 numbers each
CAR_STATE_FIELDS = ("present", "team_num", "position", "linear_velocity", "angular_velocity", "forward", "up",
                    "boost_amount", "on_ground", "is_demoed")
CAR_STATE_SIZE = 1 + 1 + 3 * 5 + 1 + 1 + 1
#: ``state()``: the ball's fields, then per possible agent (in ``possible_agents`` order; zeros for an agent not in
#: the state) its car's fields, then every boost pad's timer (s, ``BOOST_LOCATIONS`` order); raw uu, uu/s, rad/s.
STATE_LAYOUT = (BALL_STATE_FIELDS, CAR_STATE_FIELDS, "boost_pad_timers")


def global_state(state: GameState, possible_agents: list[AgentID]) -> np.ndarray:
    """The ``state()`` vector of an RLGym Rocket League ``GameState`` (``STATE_LAYOUT``)."""
    if not isinstance(state, GameState):
        raise ValueError(f"state: a global state needs an rlgym.rocket_league.api.GameState, got "
                         f"{type(state).__name__}")
    timers = np.asarray(state.boost_pad_timers, dtype=np.float32).ravel()
    if timers.shape[0] != len(BOOST_LOCATIONS):
        raise ValueError(f"state.boost_pad_timers: expected {len(BOOST_LOCATIONS)} pads, got {timers.shape[0]}")
    ball = state.ball
    cars = np.zeros((len(possible_agents), CAR_STATE_SIZE), dtype=np.float32)
    for row, agent in zip(cars, possible_agents):
        car = state.cars.get(agent)
        if car is None:
            continue
        physics = car.physics
        row[:] = np.concatenate(([1.0, car.team_num], physics.position, physics.linear_velocity,
                                 physics.angular_velocity, physics.forward, physics.up,
                                 [car.boost_amount, car.on_ground, car.is_demoed]))
    return np.concatenate((ball.position, ball.linear_velocity, ball.angular_velocity, cars.ravel(),
                           timers)).astype(np.float32)


def global_state_space(n_agents: int) -> spaces.Box:
    size = 3 * len(BALL_STATE_FIELDS) + n_agents * CAR_STATE_SIZE + len(BOOST_LOCATIONS)
    return spaces.Box(-np.inf, np.inf, shape=(size,), dtype=np.float32)


class RLGymParallelEnv(ParallelEnv):
    """PettingZoo's parallel API over an RLGym v2 env.

    :param rlgym_env: the env, e.g. ``RLGym(..., transition_engine=RocketDRLEngine())``; the wrapper owns it
        (``close`` closes it).
    :param possible_agents: every agent the env can have; by default the agents after one reset of the env
        (which fixes the spaces of builders sized by the state, such as ``DefaultObs(zero_padding=None)``).
    :param render_mode: ``None``; ``"rgb_array"`` to get a frame of the state from ``render()`` (drawn by
        ``rgb_renderer``); or ``"human"`` to call the env's RLGym ``Renderer`` on ``render()``.
    :param rgb_renderer: the ``RLGymRenderer`` of ``"rgb_array"`` (the wrapper closes it); by default a 640 x 360
        broadcast view of the engine's arena shape.
    """

    metadata = {"name": "rlgym_v2", "render_modes": ["human", "rgb_array"], "is_parallelizable": True,
                "render_fps": 15}

    def __init__(self, rlgym_env: RLGym, possible_agents: list[AgentID] | None = None,
                 render_mode: str | None = None, rgb_renderer: RLGymRenderer | None = None):
        if not isinstance(rlgym_env, RLGym):
            raise ValueError(f"rlgym_env: expected an rlgym.api.RLGym, got {type(rlgym_env).__name__}")
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode: must be one of {[None, *self.metadata['render_modes']]}, "
                             f"got {render_mode!r}")
        if render_mode == "human" and rlgym_env.renderer is None:
            raise ValueError("render_mode: 'human' needs an RLGym env with a renderer")
        if rgb_renderer is not None and render_mode != "rgb_array":
            raise ValueError(f"rgb_renderer: only used with render_mode='rgb_array', got render_mode={render_mode!r}")
        self.rlgym_env = rlgym_env
        self.render_mode = render_mode
        self._last_obs: dict[AgentID, Any] = {}
        if possible_agents is None:
            self._last_obs = rlgym_env.reset()
            possible_agents = list(rlgym_env.agents)
        if not possible_agents:
            raise ValueError("possible_agents: the env has no agents (does its state mutator add cars?)")
        self.possible_agents = list(possible_agents)
        self.agents: list[AgentID] = []
        self.state_space = global_state_space(len(self.possible_agents))
        self._rgb_renderer = None
        if render_mode == "rgb_array":
            engine_arena = getattr(rlgym_env.transition_engine, "arena", None)
            shape = getattr(getattr(engine_arena, "batch", None), "arena_shape", None)
            self._rgb_renderer = rgb_renderer or RLGymRenderer(**({} if shape is None else {"arena_shape": shape}))
        self._observation_spaces = {a: gymnasium_space(rlgym_env.observation_space(a), f"observation_space({a!r})")
                                    for a in self.possible_agents}
        self._action_spaces = {a: gymnasium_space(rlgym_env.action_space(a), f"action_space({a!r})")
                               for a in self.possible_agents}

    def observation_space(self, agent: AgentID) -> spaces.Space:
        return self._observation_spaces[agent]

    def action_space(self, agent: AgentID) -> spaces.Space:
        return self._action_spaces[agent]

    @property
    def rlgym_state(self):
        """The RLGym state (``GameState`` for Rocket League engines) after the last reset or step."""
        return self.rlgym_env.state

    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            random.seed(seed)
            np.random.seed(seed % 2**32)
        obs = self.rlgym_env.reset()
        self.agents = list(self.rlgym_env.agents)
        unknown = [a for a in self.agents if a not in self._observation_spaces]
        if unknown:
            raise ValueError(f"possible_agents: the env's reset made agents {unknown} outside {self.possible_agents}")
        return self._observations(obs), {a: {} for a in self.agents}

    def step(self, actions: dict[AgentID, Any]):
        if not self.agents:
            raise RuntimeError("step: the episode is over (no agents left); call reset()")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"actions: missing for agents {missing}")
        obs, rewards, terminated, truncated = self.rlgym_env.step(
            {a: self._engine_action(a, actions[a]) for a in self.agents})
        agents = self.agents
        terminations = {a: bool(terminated[a]) for a in agents}
        truncations = {a: bool(truncated[a]) for a in agents}
        if any(terminations.values()) or any(truncations.values()):
            truncations = {a: truncations[a] or not terminations[a] for a in agents}
            self.agents = []
        return (self._observations(obs), {a: float(rewards[a]) for a in agents}, terminations, truncations,
                {a: {} for a in agents})

    def state(self) -> np.ndarray:
        """The global state of the last reset or step (``STATE_LAYOUT``), for centralised critics."""
        return global_state(self.rlgym_env.state, self.possible_agents)

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gymnasium.logger.warn("render: this env was made with render_mode=None")
            return None
        if self.render_mode == "rgb_array":
            return self._rgb_renderer.render(self.rlgym_env.state, self.rlgym_env.shared_info)
        self.rlgym_env.render()
        return None

    def close(self) -> None:
        if self._rgb_renderer is not None:
            self._rgb_renderer.close()
        self.rlgym_env.close()

    # ---- conversions
    def _observations(self, obs: dict[AgentID, Any]) -> dict[AgentID, Any]:
        out = {}
        for agent in obs:
            space = self._observation_spaces[agent]
            out[agent] = np.asarray(obs[agent], dtype=space.dtype) if isinstance(space, spaces.Box) else obs[agent]
        return out

    def _engine_action(self, agent: AgentID, action: Any) -> np.ndarray:
        space = self._action_spaces[agent]
        if isinstance(space, spaces.Discrete):
            return np.asarray([action], dtype=np.int64).reshape(1)
        return np.asarray(action, dtype=space.dtype)
