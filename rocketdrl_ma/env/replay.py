"""Replays: ``GameState`` snapshots recorded to one ``.npz`` file and re-rendered later without physics.

    with ReplayWriter("game.npz", meta={"config": cfg}) as rec:
        for state in states:            # per tick or per decision
            rec.add(state)
    replay = load_replay("game.npz")
    replay.state(10)                    # a GameState with CarState / BallState objects
    render_replay("game.npz", "game.mp4")

File layout (numpy ``.npz``, no pickles; T states, A agents, K obstacle slots, C distinct car configs):
    format_version ()        int64, FORMAT_VERSION; checked on load
    meta_json      ()        str: the writer's meta plus ``format_version``, ``agents`` and ``tick_rate``
    agents         (A,)      str: every agent seen, in order of first appearance
    tick, tick_rate (T,)     int64
    ball_pos, ball_vel, ball_ang_vel (T, 3)
    car_present    (T, A)    bool: the agent was in ``state.cars`` (agents that leave or join mid-replay)
    car_<field>    (T, A, ...) one array per ``CarState`` field (float64 or bool; zeros where not present)
    controls       (T, A, 8) ``CarControls.as_array()``; controls_present (T, A) bool
    car_config_index (T, A) int32 into car_configs_json (C,) str; -1 = no config for that agent
    pad_timers     (T, 34); score (T, 2) int64; clock_s (T,); is_overtime, kickoff_pending (T,) bool
    last_touch     (T,) str, "" when None
    obstacle_count (T,) int64; obstacle_center, obstacle_half_extents (T, K, 3)
    events_json    (T,) str: each state's event list as JSON
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
from typing import Iterator

import numpy as np

from rocketdrl_ma.physics import BallState, CarConfig, CarControls, CarState
from rocketdrl_ma.physics.arena_shape import DEFAULT_ARENA_SHAPE
from rocketdrl_ma.physics.car_config import WheelPair
from rocketdrl_ma.rules.events import events_from_dicts
from rocketdrl_ma.rules.state import GameState, Obstacle

FORMAT_VERSION = 1
_CAR_FIELDS = tuple(f.name for f in dataclasses.fields(CarState))
_CONTROL_FIELDS = tuple(f.name for f in dataclasses.fields(CarControls))
_CONTROL_BOOLS = frozenset(name for name in _CONTROL_FIELDS if isinstance(getattr(CarControls(), name), bool))


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if isinstance(obj, (set, frozenset, tuple)):
        return list(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON serialisable")


def _config_to_json(config: CarConfig) -> str:
    return json.dumps(dataclasses.asdict(config), sort_keys=True)


def _config_from_json(text: str) -> CarConfig:
    d = json.loads(text)
    return CarConfig(name=d["name"], hitbox_size=tuple(d["hitbox_size"]), hitbox_offset=tuple(d["hitbox_offset"]),
                     front=WheelPair(d["front"]["radius"], d["front"]["rest_length_config"],
                                     tuple(d["front"]["connection"])),
                     back=WheelPair(d["back"]["radius"], d["back"]["rest_length_config"],
                                    tuple(d["back"]["connection"])),
                     three_wheel=bool(d["three_wheel"]))


def _car_value_array(value) -> np.ndarray:
    """A CarState field as an array: bools (and tuples of bools) stay bool, everything else float64."""
    if isinstance(value, (bool, np.bool_)):
        return np.asarray(value, dtype=bool)
    if isinstance(value, tuple) and all(isinstance(v, (bool, np.bool_)) for v in value):
        return np.asarray(value, dtype=bool)
    return np.asarray(value, dtype=np.float64)


class ReplayWriter:
    """Records ``GameState`` snapshots and writes them to ``path`` (one ``.npz``) on ``close()``.

    ``meta`` must be JSON-serialisable (the match config, seeds, policy names, ...); the writer adds
    ``format_version``, ``agents`` (every agent seen) and ``tick_rate`` (of the first state), overriding keys of
    those names. States are kept in memory until ``close()``, which writes atomically (temp file + rename).
    """

    def __init__(self, path: str, meta: dict | None = None):
        meta = {} if meta is None else meta
        if not isinstance(meta, dict):
            raise ValueError(f"meta: expected a dict, got {type(meta).__name__}")
        try:
            json.dumps(meta, default=_json_default)
        except (TypeError, ValueError) as e:
            raise ValueError(f"meta: must be JSON-serialisable ({e})") from None
        self.path = os.fspath(path)
        self.meta = dict(meta)
        self._states: list[GameState] = []
        self._agents: dict[str, None] = {}  # insertion-ordered set
        self._closed = False

    def __len__(self) -> int:
        return len(self._states)

    def add(self, state: GameState) -> None:
        """Record one snapshot. The writer copies nothing until ``close()``: do not mutate ``state`` after."""
        if self._closed:
            raise ValueError(f"replay {self.path!r}: writer already closed")
        if not isinstance(state, GameState):
            raise ValueError(f"state: expected a GameState, got {type(state).__name__}")
        if self._states and np.shape(state.pad_timers) != np.shape(self._states[0].pad_timers):
            raise ValueError(f"pad_timers: shape {np.shape(state.pad_timers)} differs from the first state's "
                             f"{np.shape(self._states[0].pad_timers)}")
        for agent in state.cars:
            self._agents.setdefault(agent, None)
        for agent in state.last_controls:
            self._agents.setdefault(agent, None)
        for agent in state.car_configs:
            self._agents.setdefault(agent, None)
        # Snapshot the mutable parts now, so a caller that reuses objects between ticks still records each tick.
        self._states.append(dataclasses.replace(
            state,
            cars={a: dataclasses.replace(c) for a, c in state.cars.items()},
            ball=dataclasses.replace(state.ball),
            pad_timers=np.array(state.pad_timers, dtype=np.float64),
            last_controls=dict(state.last_controls),
            events=list(state.events),  # typed events are frozen: nothing to snapshot
            car_configs=dict(state.car_configs),
        ))

    def _arrays(self) -> dict[str, np.ndarray]:
        states, agents = self._states, list(self._agents)
        T, A = len(states), len(agents)
        col = {a: i for i, a in enumerate(agents)}
        n_pads = int(np.size(states[0].pad_timers)) if states else 34
        K = max((len(s.obstacles) for s in states), default=0)
        tick_rate = int(states[0].tick_rate) if states else None
        meta = dict(self.meta)
        meta.update(format_version=FORMAT_VERSION, agents=agents, tick_rate=tick_rate)
        out: dict[str, np.ndarray] = {
            "format_version": np.asarray(FORMAT_VERSION, dtype=np.int64),
            "meta_json": np.asarray(json.dumps(meta, default=_json_default)),
            "agents": np.asarray(agents, dtype=str).reshape(A),
            "tick": np.array([s.tick for s in states], dtype=np.int64).reshape(T),
            "tick_rate": np.array([s.tick_rate for s in states], dtype=np.int64).reshape(T),
            "ball_pos": np.array([s.ball.pos for s in states], dtype=np.float64).reshape(T, 3),
            "ball_vel": np.array([s.ball.vel for s in states], dtype=np.float64).reshape(T, 3),
            "ball_ang_vel": np.array([s.ball.ang_vel for s in states], dtype=np.float64).reshape(T, 3),
            "car_present": np.zeros((T, A), dtype=bool),
            "controls": np.zeros((T, A, len(_CONTROL_FIELDS)), dtype=np.float64),
            "controls_present": np.zeros((T, A), dtype=bool),
            "car_config_index": np.full((T, A), -1, dtype=np.int32),
            "pad_timers": np.array([np.asarray(s.pad_timers, dtype=np.float64).ravel() for s in states],
                                   dtype=np.float64).reshape(T, n_pads),
            "score": np.array([tuple(s.score) for s in states], dtype=np.int64).reshape(T, 2),
            "clock_s": np.array([s.clock_s for s in states], dtype=np.float64).reshape(T),
            "is_overtime": np.array([s.is_overtime for s in states], dtype=bool).reshape(T),
            "kickoff_pending": np.array([s.kickoff_pending for s in states], dtype=bool).reshape(T),
            "last_touch": np.asarray([s.last_touch or "" for s in states], dtype=str).reshape(T),
            "obstacle_count": np.array([len(s.obstacles) for s in states], dtype=np.int64).reshape(T),
            "obstacle_center": np.zeros((T, K, 3), dtype=np.float64),
            "obstacle_half_extents": np.zeros((T, K, 3), dtype=np.float64),
            "events_json": np.asarray([json.dumps([e.as_dict() for e in s.events], default=_json_default)
                                       for s in states], dtype=str).reshape(T),
        }
        template = _car_value_array  # shapes and dtypes come from a default CarState
        default_car = CarState()
        for name in _CAR_FIELDS:
            proto = template(getattr(default_car, name))
            out[f"car_{name}"] = np.zeros((T, A) + proto.shape, dtype=proto.dtype)
        configs: dict[str, int] = {}
        for t, s in enumerate(states):
            for agent, car in s.cars.items():
                a = col[agent]
                out["car_present"][t, a] = True
                for name in _CAR_FIELDS:
                    out[f"car_{name}"][t, a] = template(getattr(car, name))
            for agent, ctrl in s.last_controls.items():
                out["controls"][t, col[agent]] = ctrl.as_array()
                out["controls_present"][t, col[agent]] = True
            for agent, cfg in s.car_configs.items():
                key = _config_to_json(cfg)
                out["car_config_index"][t, col[agent]] = configs.setdefault(key, len(configs))
            for k, ob in enumerate(s.obstacles):
                out["obstacle_center"][t, k] = np.asarray(ob.center, dtype=np.float64)
                out["obstacle_half_extents"][t, k] = np.asarray(ob.half_extents, dtype=np.float64)
        out["car_configs_json"] = np.asarray(list(configs), dtype=str).reshape(len(configs))
        return out

    def close(self) -> None:
        """Write the file (once); later calls do nothing."""
        if self._closed:
            return
        arrays = self._arrays()
        tmp = f"{self.path}.tmp{os.getpid()}"
        try:
            with open(tmp, "wb") as f:
                np.savez_compressed(f, **arrays)
            os.replace(tmp, self.path)
        finally:
            if os.path.exists(tmp):
                os.remove(tmp)
        self._closed = True
        self._states = []

    def __enter__(self) -> "ReplayWriter":
        return self

    def __exit__(self, exc_type, *exc) -> None:
        self.close()


class Replay:
    """A loaded replay: ``len(replay)`` states, ``replay.meta`` (dict), ``replay.state(i)`` -> ``GameState``."""

    def __init__(self, arrays: dict[str, np.ndarray], path: str = "<memory>"):
        self.path = path
        self._a = arrays
        self.meta: dict = json.loads(str(arrays["meta_json"]))
        self.agents: list[str] = [str(a) for a in arrays["agents"]]
        self._configs = [_config_from_json(str(t)) for t in arrays["car_configs_json"]]
        config = self.meta.get("config")
        # the recorded game's arena (an env's recording carries its config; other recordings are classic)
        self.arena_shape: str = (config.get("arena_shape", DEFAULT_ARENA_SHAPE) if isinstance(config, dict)
                                 else DEFAULT_ARENA_SHAPE)

    def __len__(self) -> int:
        return int(self._a["tick"].shape[0])

    @property
    def ticks(self) -> np.ndarray:
        return self._a["tick"].copy()

    @property
    def tick_rate(self) -> int:
        if len(self):
            return int(self._a["tick_rate"][0])
        return int(self.meta.get("tick_rate") or 0)

    def states_per_second(self) -> float:
        """How many recorded states make one game second (tick rate over the median tick step)."""
        steps = np.diff(self._a["tick"])
        steps = steps[steps > 0]
        rate = self.tick_rate
        if rate <= 0:
            return 0.0
        return float(rate) / float(np.median(steps)) if steps.size else float(rate)

    def __iter__(self) -> Iterator[GameState]:
        for i in range(len(self)):
            yield self.state(i)

    def __getitem__(self, i: int) -> GameState:
        return self.state(i)

    def state(self, i: int) -> GameState:
        n = len(self)
        if not isinstance(i, (int, np.integer)) or not -n <= i < n:
            raise IndexError(f"i: state index {i!r} out of range for a replay of {n} states")
        i = int(i) % n
        a = self._a
        cars: dict[str, CarState] = {}
        controls: dict[str, CarControls] = {}
        configs: dict[str, CarConfig] = {}
        for j, agent in enumerate(self.agents):
            if a["car_present"][i, j]:
                kw = {}
                for name in _CAR_FIELDS:
                    key = f"car_{name}"
                    if key not in a:  # a field newer than the file: the CarState default
                        continue
                    v = a[key][i, j]
                    if v.ndim == 0:
                        kw[name] = bool(v) if v.dtype == bool else float(v)
                    elif v.dtype == bool:
                        kw[name] = tuple(bool(x) for x in v)
                    else:
                        kw[name] = v.copy()
                cars[agent] = CarState(**kw)
            if a["controls_present"][i, j]:
                vals = a["controls"][i, j]
                controls[agent] = CarControls(**{name: (bool(v) if name in _CONTROL_BOOLS else float(v))
                                                 for name, v in zip(_CONTROL_FIELDS, vals)})
            k = int(a["car_config_index"][i, j])
            if k >= 0:
                configs[agent] = self._configs[k]
        n_ob = int(a["obstacle_count"][i])
        obstacles = tuple(Obstacle(a["obstacle_center"][i, k].copy(), a["obstacle_half_extents"][i, k].copy())
                          for k in range(n_ob))
        touch = str(a["last_touch"][i])
        return GameState(
            tick=int(a["tick"][i]), tick_rate=int(a["tick_rate"][i]), cars=cars,
            ball=BallState(pos=a["ball_pos"][i], vel=a["ball_vel"][i], ang_vel=a["ball_ang_vel"][i]),
            pad_timers=a["pad_timers"][i].copy(), last_controls=controls,
            score=(int(a["score"][i, 0]), int(a["score"][i, 1])), clock_s=float(a["clock_s"][i]),
            is_overtime=bool(a["is_overtime"][i]), kickoff_pending=bool(a["kickoff_pending"][i]),
            last_touch=touch or None, obstacles=obstacles, events=events_from_dicts(json.loads(str(a["events_json"][i]))),
            car_configs=configs, arena_shape=self.arena_shape)


def load_replay(path: str) -> Replay:
    """Load a replay written by ``ReplayWriter``; a file of another format version is a ValueError."""
    path = os.fspath(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (OSError, ValueError) as e:
        if isinstance(e, FileNotFoundError):
            raise
        raise ValueError(f"path: {path!r} is not a replay file ({e})") from None
    if "format_version" not in arrays or "meta_json" not in arrays:
        raise ValueError(f"path: {path!r} is not a replay file (no format_version / meta_json)")
    version = int(arrays["format_version"])
    if version != FORMAT_VERSION:
        raise ValueError(f"format_version: {path!r} has replay format version {version}; this build reads "
                         f"version {FORMAT_VERSION} only")
    return Replay(arrays, path)


def render_replay(path: str, out_path: str, fps: float | None = None, width: int = 640, height: int = 360,
                  camera: str = "broadcast", **renderer_kwargs) -> int:
    """Render every state of the replay at ``path`` to the video ``out_path`` (``.mp4`` or ``.gif``).

    ``fps`` defaults to real time: the replay's states per game second. Returns the number of frames written.
    """
    from .render import Renderer, VideoWriter

    replay = load_replay(path)
    if len(replay) == 0:
        raise ValueError(f"path: replay {os.fspath(path)!r} has no states to render")
    if fps is None:
        fps = replay.states_per_second() or 30.0
    if not math.isfinite(float(fps)) or float(fps) <= 0.0:
        raise ValueError(f"fps: must be a positive number, got {fps!r}")
    renderer = Renderer(width, height, camera, **{"arena_shape": replay.arena_shape, **renderer_kwargs})
    try:
        with VideoWriter(out_path, fps) as video:
            for state in replay:
                video.append(renderer.render(state))
        return video.count
    finally:
        renderer.close()
