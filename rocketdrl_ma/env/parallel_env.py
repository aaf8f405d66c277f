"""The PettingZoo face: a ``ParallelEnv`` composing a game mode, an observation builder and an action parser.

One decision: actions -> ActionParser -> CarControls -> ``tick_skip`` physics ticks with the rules'
logic after each -> GameState -> ObsBuilder (observations) and Rules (rewards per term, terminations,
truncations, events). Observation and action spaces are the same for every agent and declared once.
"""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from rocketdrl_ma.config import load_config, make_rules
from rocketdrl_ma.physics import constants as C
from rocketdrl_ma.rules.state import GameState
from rocketdrl_ma.validation import check_int

from .actions import make_action_parser
from .observations import make_obs_builder

STATE_CAR_FEATURES = 19  # pos 3, vel 3, ang_vel 3, forward 3, up 3, boost, on_ground, is_demoed, present
#: event kinds counted per agent in numeric infos (an agent is credited as ``agent`` or goal ``scorer``)
COUNTED_EVENTS = ("goal", "touch", "shot", "save", "demo", "bump", "boost_pickup")


def flat_numbers(tree: dict, prefix: str = "") -> dict[str, float]:
    """``{"score": {"blue": 1}, "overtime": False}`` -> ``{"score_blue": 1.0, "overtime": 0.0}``."""
    flat: dict[str, float] = {}
    for key, value in tree.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flat_numbers(value, name + "_"))
        elif isinstance(value, (bool, int, float, np.number)):
            flat[name] = float(value)
    return flat


def check_seed(seed: object) -> int | None:
    """A reset seed: None or an int >= 0 (NumPy's seeds; a NumPy integer too), bools and floats refused."""
    if seed is None:
        return None
    return check_int("seed", int(seed) if isinstance(seed, np.integer) else seed, minimum=0)


def global_state_vector(state: GameState, agents: list[str]) -> np.ndarray:
    """The whole game in the blue frame for a centralised critic, every value scaled into [-1, 1]."""
    ball = state.ball
    parts = [ball.pos / 6000.0, ball.vel / C.BALL_MAX_SPEED, ball.ang_vel / C.BALL_MAX_ANG_SPEED]
    for agent in agents:
        car = state.cars.get(agent)
        if car is None:
            parts.append(np.zeros(STATE_CAR_FEATURES))
            continue
        parts += [car.pos / 6000.0, car.vel / C.CAR_MAX_SPEED, car.ang_vel / C.CAR_MAX_ANG_SPEED,
                  car.rot_mat[:, 0], car.rot_mat[:, 2],
                  [car.boost / C.BOOST_MAX, float(car.on_ground), float(car.is_demoed), 1.0]]
    cooldown = np.where(C.BOOST_PAD_IS_BIG, C.BOOST_PAD_BIG_COOLDOWN, C.BOOST_PAD_SMALL_COOLDOWN)
    parts.append(state.pad_timers / cooldown)
    parts.append([np.tanh((state.score[0] - state.score[1]) / 3.0), min(state.clock_s / 300.0, 1.0),
                  float(state.is_overtime)])
    return np.clip(np.concatenate([np.asarray(p, dtype=np.float64).ravel() for p in parts]), -1.0, 1.0).astype(
        np.float32)


class RocketDRLParallelEnv(ParallelEnv):
    """Car football for multi-agent RL. Agents are ``blue_0..`` and ``orange_0..``.

    ``config`` is a YAML path (``matches/2v2.yaml``), a dict, or None for a 1v1 match; keyword overrides
    replace keys (dict-valued ones such as ``rewards`` merge).

    ``infos[agent]`` (``info_format: full``, the default) holds the scoreboard, this decision's events
    and the reward broken down per term; at the episode's end also ``summary``. Frameworks that turn
    infos into tensors (torchrl's ``PettingZooWrapper``) need the same keys and shapes every step:
    ``info_format: numeric`` gives flat floats instead: the scoreboard's numbers (``score_blue``, ...),
    this agent's count of each event kind in ``COUNTED_EVENTS`` this decision, and ``reward_<term>``.
    """

    metadata = {"name": "rocketdrl_ma_v0", "render_modes": ["human", "rgb_array"], "is_parallelizable": True,
                "render_fps": C.TICK_RATE_HZ / 8}

    def __init__(self, config: str | Path | dict | None = "matches/1v1.yaml", render_mode: str | None = None,
                 **overrides: Any):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode: {render_mode!r} is not one of {self.metadata['render_modes']} or None")
        self.config = load_config(config, overrides)
        self.rules = make_rules(self.config)
        obs_spec, act_spec = dict(self.config["observation"]), dict(self.config["action"])
        self.obs_builder = make_obs_builder(obs_spec.pop("name"), **obs_spec)
        self.action_parser = make_action_parser(act_spec.pop("name"), **act_spec)
        self.tick_skip: int = self.config["tick_skip"]
        self.max_cycles: int | None = self.config["max_cycles"]
        self.info_format: str = self.config["info_format"]
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": C.TICK_RATE_HZ / self.tick_skip}
        self.possible_agents = list(self.rules.possible_agents)
        self.agents: list[str] = []
        self._obs_space = self.obs_builder.space(self.rules.blue_size, self.rules.orange_size)
        self._action_space = self.action_parser.space()
        n_state = 9 + STATE_CAR_FEATURES * len(self.possible_agents) + len(C.BOOST_PAD_POSITIONS) + 3
        self.state_space = spaces.Box(-1.0, 1.0, (n_state,), np.float32)
        self._rng: np.random.Generator | None = None
        self._state: GameState | None = None
        self._cycles = 0
        self._renderer = None
        self._frames: list[np.ndarray] = []
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

    # The same space object every call, as PettingZoo asks, without its docs' ``functools.lru_cache``: a cache on the
    # method keys on ``self`` and so kept every env that was ever asked (and its PyBullet world) alive.
    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        return self._action_space

    # ------------------------------------------------------------------ episode
    def reset(self, seed: int | None = None, options: dict | None = None):
        seed = check_seed(seed)
        if options is not None and not isinstance(options, dict):
            raise ValueError(f"options: expected a dict or None, got {type(options).__name__} {options!r}")
        if seed is not None or self._rng is None:
            self._rng = np.random.default_rng(seed)
            self._action_space.seed(seed)
        used = self.rules.arena is not None
        self.rules.reset(self._rng)
        if seed is not None and used and self.rules.arena_factory is None:
            # The rules have put every car: a new PyBullet world with them (about 18 ms in 3v3) makes a used lone env
            # replay a fresh env's game exactly. A VectorEnv renews its shared batch itself, the same way.
            self.rules.arena.renew_world()
        self.agents = list(self.possible_agents)
        self._cycles = 0
        self._frames = []
        state = self._state = self.rules.game_state()
        self.obs_builder.reset(state)
        observations = {agent: self.obs_builder.build(agent, state) for agent in self.agents}
        no_terms = {term: 0.0 for term in self.rules.REWARD_TERMS}
        infos = {agent: self._info(agent, state, no_terms) for agent in self.agents}
        self._after_decision(state)
        return observations, infos

    def step(self, actions: dict):
        self.rules.advance(self.decision_controls(actions), self.tick_skip)
        return self.end_decision()

    def decision_controls(self, actions: dict) -> dict:
        """The first half of ``step``: validated actions parsed into each live agent's controls. ``VectorEnv``
        calls the two halves around one physics step of all its lanes' arenas."""
        if not self.agents:
            raise ValueError("step: the episode is over; call reset()")
        if not isinstance(actions, dict):
            raise ValueError(f"actions: expected a dict of agent -> action for the live agents {self.agents}, got "
                             f"{type(actions).__name__}")
        for agent in actions:
            if agent not in self.possible_agents:
                raise ValueError(f"actions: unknown agent {agent!r}; agents are {self.possible_agents}")
        missing = [agent for agent in self.agents if agent not in actions]
        if missing:
            raise ValueError(f"actions: no action for live agent(s) {missing}")
        # Actions for agents no longer in the game are ignored (torchrl sends them for finished agents).
        return {agent: self.action_parser.parse(agent, actions[agent], self._state) for agent in self.agents}

    def end_decision(self, observe: bool = True):
        """The second half of ``step``: everything a step returns, once the rules have run the decision's ticks
        (``VectorEnv`` builds the observations of all its lanes at once when it can: ``observe=False`` leaves them
        out)."""
        self._cycles += 1
        state = self._state = self.rules.game_state()
        terminated = self.rules.is_terminated()
        truncated = self.rules.is_truncated() or (self.max_cycles is not None and self._cycles >= self.max_cycles)
        observations, rewards, infos = {}, {}, {}
        for agent in self.agents:
            if observe:
                observations[agent] = self.obs_builder.build(agent, state)
            rewards[agent], terms = self.rules.weighted_rewards(agent, state)
            infos[agent] = self._info(agent, state, terms)
        rewards = self.rules.team_rewards(rewards)
        if (terminated or truncated) and self.info_format == "full":
            summary = self.rules.summary()
            for agent in self.agents:
                infos[agent]["summary"] = summary
        terminations = {agent: bool(terminated) for agent in self.agents}
        truncations = {agent: bool(truncated and not terminated) for agent in self.agents}
        if terminated or truncated:
            self.agents = []
        self._after_decision(state)
        return observations, rewards, terminations, truncations, infos

    def _info(self, agent: str, state: GameState, reward_terms: dict[str, float]) -> dict:
        if self.info_format == "full":
            return {"scoreboard": self.rules.scoreboard(), "events": list(state.events), "reward_terms": reward_terms}
        info = flat_numbers(self.rules.scoreboard())
        counts = dict.fromkeys(COUNTED_EVENTS, 0.0)
        for event in state.events:
            if event.kind in counts and event.credited_to == agent:
                counts[event.kind] += 1.0
        info.update(counts)
        info.update({f"reward_{term}": value for term, value in reward_terms.items()})
        return info

    def _after_decision(self, state: GameState) -> None:
        if self._replay is not None:
            self._replay.add(state)
            if not self.agents:
                self.stop_replay()
        if self.render_mode == "human":
            self.render()

    @property
    def game_state(self) -> GameState | None:
        """The game after the last reset or step (None before the first reset)."""
        return self._state

    def state(self) -> np.ndarray:
        if self._state is None:
            raise ValueError("state: call reset() first")
        return global_state_vector(self._state, self.possible_agents)

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
        self.rules.close()
