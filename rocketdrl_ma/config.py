"""YAML game configs: loading, defaults and validation shared by the env, the server and the trainer.

A config names a game mode (``mode``), the mode's own parameters (its constructor arguments, e.g.
``team_size`` and ``clock_s`` for a match) and the env's (``tick_skip``, ``max_cycles``,
``observation``, ``action``, ``rewards``). Unknown keys and wrong types are errors naming the key and
the allowed ones; nothing is silently dropped or clamped. The env's keys are the typed fields of ``EnvKeys``; a
mode's are its constructor's parameters, typed by their defaults; both are checked by ``rocketdrl_ma.validation``.
"""
from __future__ import annotations

import dataclasses
import inspect
from pathlib import Path
from collections.abc import Mapping
from typing import Annotated, Any, TypeVar

import yaml

from rocketdrl_ma.physics import PRESETS
from rocketdrl_ma.physics.arena_shape import arena_shape_index
from rocketdrl_ma.rules import GAME_MODES
from rocketdrl_ma.rules.match import check_team_size
from rocketdrl_ma.rules.rewards import check_weights
from rocketdrl_ma.validation import (Check, OneOf, Range, check_number, check_value, field_types, load_dataclass,
                                     reject_unknown)

T = TypeVar("T")
PACKAGE_DIR = Path(__file__).resolve().parent
REPO_ROOT = PACKAGE_DIR.parent
#: The top-level folders that ship with the package: game, server, training and league configs, and the trained
#: checkpoints the docs use (``policies/checkpoints``).
SHIPPED_FOLDERS = ("matches", "minigames", "server", "policies", "leagues")
#: Where a wheel carries them (``setup.py`` copies them there at build time).
WHEEL_DATA_DIR = PACKAGE_DIR / "data"

INFO_FORMATS = ("full", "numeric")


def _builder_spec(field: str, spec: Any) -> dict[str, Any]:
    """An observation or action spec as ``{name, **options}``."""
    if isinstance(spec, str):
        return {"name": spec}
    if not (isinstance(spec, dict) and isinstance(spec.get("name"), str)):
        raise ValueError(f"{field}: expected a name or a mapping with 'name' and its options, got {spec!r}")
    return spec


@dataclasses.dataclass(frozen=True)
class EnvKeys:
    """The keys every game config has besides its mode's (``rewards`` is checked against the mode's terms)."""
    tick_skip: Annotated[int, Range(minimum=1)] = 8
    max_cycles: Annotated[int, Range(minimum=1)] | None = None
    observation: Annotated[Any, Check(_builder_spec)] = "team_relative"
    action: Annotated[Any, Check(_builder_spec)] = "continuous"
    rewards: Any = dataclasses.field(default_factory=dict)
    info_format: Annotated[str, OneOf(INFO_FORMATS)] = "full"


ENV_DEFAULTS: dict[str, Any] = {f.name: f.default if f.default is not dataclasses.MISSING else f.default_factory()
                                for f in dataclasses.fields(EnvKeys)}


def shipped_root() -> Path | None:
    """The folder holding the shipped folders: ``rocketdrl_ma/data`` in an installed wheel, the repository's top
    level in a clone (an editable install included); None if neither is there."""
    if WHEEL_DATA_DIR.is_dir():
        return WHEEL_DATA_DIR
    if (REPO_ROOT / "pyproject.toml").is_file() and (REPO_ROOT / "matches").is_dir():
        return REPO_ROOT
    return None


def resolve_shipped_path(path: str | Path, what: str = "config") -> Path:
    """A file as given if it exists, else the shipped file of that name (``matches/1v1.yaml``,
    ``policies/checkpoints/penalty_tuned.pt``), the same from a clone and from an installed wheel. ``what`` names
    the field in the error."""
    p = Path(path)
    if p.is_file():
        return p
    root = shipped_root()
    if root is not None and not p.is_absolute():
        candidate = (root / p).resolve()
        if candidate.is_file() and candidate.is_relative_to(root.resolve()):
            return candidate
    raise ValueError(f"{what}: no such file {str(path)!r} in the working directory or among the shipped files "
                     f"(`rocketdrl-ma configs` lists them)")


def resolve_config_path(path: str | Path) -> Path:
    """A config path as given, else the shipped config of that name (``matches/1v1.yaml`` works from anywhere)."""
    return resolve_shipped_path(path, "config")


def load_yaml_file(path: str | Path, what: str = "config") -> Any:
    """The YAML document in ``path``; a syntax error is a ValueError naming ``what``, the file, line and column."""
    try:
        text = Path(path).read_text()
    except OSError as e:
        raise ValueError(f"{what}: cannot read {str(path)!r}: {e.strerror}") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f"{path}, line {mark.line + 1}, column {mark.column + 1}" if mark is not None else str(path)
        problem = " ".join(part for part in (getattr(e, "context", None), getattr(e, "problem", None)) if part)
        raise ValueError(f"{what}: YAML syntax error in {where}: {problem or e}") from None


def load_yaml_mapping(path: str | Path, what: str, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The mapping a config YAML holds (the file as given, else the shipped one of that name; empty: ``{}``),
    ``overrides`` replacing its top-level keys; anything but a mapping is a ValueError naming ``what``."""
    raw = load_yaml_file(resolve_shipped_path(path, what), what) or {}
    if not isinstance(raw, dict):
        raise ValueError(f"{what}: {path} must hold a mapping of keys to values")
    return {**raw, **(overrides or {})}


def load_yaml_dataclass(cls: type[T], path: str | Path, what: str, overrides: Mapping[str, Any] | None = None) -> T:
    """A config dataclass read from a YAML file (``load_yaml_mapping``) by ``validation.load_dataclass``: every error
    names the key and what is allowed."""
    return load_dataclass(cls, load_yaml_mapping(path, what, overrides), what)


def shipped_files(suffixes: tuple[str, ...] = (".yaml",)) -> list[str]:
    """The shipped files with these suffixes, as the names that resolve to them (``matches/1v1.yaml``)."""
    root = shipped_root()
    if root is None:
        return []
    return sorted(f.relative_to(root).as_posix() for folder in SHIPPED_FOLDERS if (root / folder).is_dir()
                  for f in (root / folder).rglob("*") if f.is_file() and f.suffix in suffixes)


def mode_parameters(mode: str) -> dict[str, Any]:
    """The mode's configurable parameters and their defaults, from its constructor and, through ``**kwargs``,
    its base classes' (a constructor without ``**kwargs`` fixes what its bases take, e.g. a one-car minigame)."""
    cls = GAME_MODES[mode]
    params: dict[str, Any] = {}
    for klass in cls.__mro__:
        if "__init__" not in vars(klass):
            continue
        forwards = False
        for name, p in inspect.signature(klass.__init__).parameters.items():
            forwards = forwards or p.kind == p.VAR_KEYWORD
            if name in ("self", "kwargs", "reward_weights") or p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL):
                continue
            params.setdefault(name, p.default)
        if not forwards:
            break
    if "team_size" in params and "blue_size" not in inspect.signature(cls.__init__).parameters:
        # a symmetric mode sets both sides through team_size
        params.pop("blue_size", None)
        params.pop("orange_size", None)
    return params


def _check_type(key: str, value: Any, default: Any) -> None:
    if default is None or value is None and key in ("max_cycles", "overtime_limit_s"):
        return
    expected = type(default)
    ok = isinstance(value, expected) and not (expected is int and isinstance(value, bool))
    if expected is float and isinstance(value, int) and not isinstance(value, bool):
        ok = True
    if not ok:
        raise ValueError(f"{key}: expected {expected.__name__}, got {type(value).__name__} {value!r}")
    if expected is float:  # YAML's .inf and .nan: no clock or limit is endless
        check_number(key, value)


def load_config(config: str | Path | dict | None = None, overrides: dict | None = None) -> dict[str, Any]:
    """Read (if a path), merge ``overrides`` (dict sections such as ``rewards`` merge key by key), validate."""
    if config is None:
        raw: dict[str, Any] = {"mode": "match"}
    elif isinstance(config, dict):
        raw = dict(config)
    elif not isinstance(config, (str, Path)):
        raise ValueError(f"config: expected a YAML path (e.g. 'matches/1v1.yaml'), a dict or None, got "
                         f"{type(config).__name__} {config!r}")
    else:
        raw = load_yaml_mapping(config, "config")
    for key, value in (overrides or {}).items():
        if isinstance(value, dict) and isinstance(raw.get(key), dict):
            raw[key] = {**raw[key], **value}
        else:
            raw[key] = value
    mode = raw.pop("mode", "match")
    if mode not in GAME_MODES:
        raise ValueError(f"mode: unknown game mode {mode!r}; allowed: {sorted(GAME_MODES)}")
    params = mode_parameters(mode)
    allowed = {"mode", *ENV_DEFAULTS, *params}
    reject_unknown(f"config (mode {mode!r})", raw, allowed)
    cfg: dict[str, Any] = {"mode": mode}
    env_types = field_types(EnvKeys)
    for key, default in {**ENV_DEFAULTS, **params}.items():
        value = raw.get(key, default)
        if value is inspect.Parameter.empty:
            raise ValueError(f"{key}: required for mode {mode!r}")
        if key in env_types:
            value = check_value(key, value, env_types[key])
        elif key != "arena_shape":  # checked below
            _check_type(key, value, default)
        cfg[key] = value
    if "team_size" in cfg:  # the sides of a match, named as the config names them (not as the rules call them)
        for key in ("team_size", "blue_size", "orange_size"):
            if cfg.get(key) is not None:
                check_team_size(key, cfg[key])
    if "arena_shape" in cfg:
        arena_shape_index(cfg["arena_shape"])  # a ValueError naming the field and the shapes
    if "car_preset" in cfg and cfg["car_preset"] not in PRESETS:
        raise ValueError(f"car_preset: unknown car preset {cfg['car_preset']!r}; allowed: {sorted(PRESETS)}")
    cfg["rewards"] = check_weights(GAME_MODES[mode].REWARD_TERMS, cfg["rewards"], "rewards")
    return cfg


def make_rules(cfg: dict[str, Any]):
    """The game-mode object a validated config describes."""
    params = {k: cfg[k] for k in mode_parameters(cfg["mode"])}
    return GAME_MODES[cfg["mode"]](reward_weights=cfg["rewards"], **params)
