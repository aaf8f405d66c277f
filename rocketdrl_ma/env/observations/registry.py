"""Builders by name (``make_obs_builder("general_sensors+ray")``) and their concatenation (``CombinedObs``)."""
from __future__ import annotations

import inspect
from collections.abc import Sequence

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.rules.state import GameState

from .base import ObsBuilder, box_space
from .rays import RaySensor
from ..renamed import OBSERVATION_NAMES, current_name
from .sensors import AerialSensors, BarrierSensors, GeneralSensors
from .team_relative import TeamRelativeObs

class CombinedObs(ObsBuilder):
    """The concatenation of several builders' observations, in order (e.g. general sensors + rays)."""

    def __init__(self, builders: Sequence[ObsBuilder]):
        builders = list(builders)
        if not builders or not all(isinstance(b, ObsBuilder) for b in builders):
            raise ValueError(f"builders: expected a non-empty list of ObsBuilder, got {builders!r}")
        self.builders = builders

    def space(self, blue_size: int, orange_size: int) -> spaces.Box:
        parts = [b.space(blue_size, orange_size) for b in self.builders]
        return box_space(np.concatenate([p.low for p in parts]), np.concatenate([p.high for p in parts]))

    def reset(self, state: GameState) -> None:
        for b in self.builders:
            b.reset(state)

    def build(self, agent: str, state: GameState) -> np.ndarray:
        return np.concatenate([b.build(agent, state) for b in self.builders]).astype(np.float32)


OBS_BUILDERS: dict[str, type[ObsBuilder]] = {
    "general_sensors": GeneralSensors, "ray": RaySensor, "team_relative": TeamRelativeObs,
    "barrier_sensors": BarrierSensors, "aerial_sensors": AerialSensors}
# The old names (``renamed.OBSERVATION_NAMES``) are still accepted, by configs and by server allow-lists.
OBS_BUILDERS.update({old: OBS_BUILDERS[new] for old, new in OBSERVATION_NAMES.items()})


def _construct(name: str, kwargs: dict) -> ObsBuilder:
    name = current_name("observation", name, OBSERVATION_NAMES)
    if name not in OBS_BUILDERS:
        raise ValueError(f"observation: unknown observation builder {name!r}; allowed: {sorted(OBS_BUILDERS)} "
                         f"or several joined with '+'")
    cls = OBS_BUILDERS[name]
    allowed = [p for p in inspect.signature(cls.__init__).parameters if p != "self"]
    unknown = sorted(set(kwargs) - set(allowed))
    if unknown:
        raise ValueError(f"observation.{name}: unknown option(s) {unknown}; allowed: {allowed}")
    return cls(**kwargs)


def make_obs_builder(name: str, **kwargs) -> ObsBuilder:
    """A builder by registry name, with its options: ``make_obs_builder("ray", n_rays=12)``.

    Several names joined with ``+`` build a ``CombinedObs`` in that order; each part's options then go in a
    mapping under its name: ``make_obs_builder("general_sensors+ray", ray={"n_rays": 12})``.
    """
    if not isinstance(name, str):
        raise ValueError(f"observation: expected a builder name, got {name!r}")
    parts = [p.strip() for p in name.split("+")]
    if len(parts) == 1:
        return _construct(parts[0], kwargs)
    for p in parts:
        if p not in OBS_BUILDERS:
            _construct(p, {})  # raises, naming the allowed ones
    unknown = sorted(set(kwargs) - set(parts))
    if unknown:
        raise ValueError(f"observation: unknown option(s) {unknown} for {name!r}; allowed: {parts} "
                         f"(each a mapping of that builder's options)")
    for key, value in kwargs.items():
        if not isinstance(value, dict):
            raise ValueError(f"observation.{key}: expected a mapping of options, got {value!r}")
    return CombinedObs([_construct(p, dict(kwargs.get(p, {}))) for p in parts])
