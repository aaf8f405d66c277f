"""Action parsers: what a policy outputs, turned into ``CarControls`` (RLGym v2 style, Gymnasium spaces).

Each parser declares its space once (the same for every agent) and parses one agent's action.

Buttons as floats: the Box parsers carry jump, boost and handbrake as floats in the same flat ``Box``
as the analogue axes, and a button counts as pressed when its value is > 0 (0 itself is released).
torchrl's PPO (and most continuous-control code) wants one flat Box, not a Dict or MultiBinary.

Range: analogue values within 1e-6 of [-1, 1] are clipped onto it (float32 round-off); values clearly
outside, NaN/inf, non-numbers and wrong shapes raise ``ValueError`` naming the agent. Nothing is clamped
silently. Parsers: ``DriveActions`` (5), ``ContinuousActions`` (8), ``LookupTableActions`` (Discrete(90)). The old
names (``seed``, ``SeedActions``) still work, with a warning naming the new one (``env.renamed``).
"""
from __future__ import annotations

import inspect
from abc import ABC, abstractmethod

import numpy as np
from gymnasium import spaces

from rocketdrl_ma.physics import CarControls
from rocketdrl_ma.rules.state import GameState

from .renamed import ACTION_NAMES, current_name, renamed_class

RANGE_TOLERANCE = 1e-6


def _vector(agent: str, action, size: int) -> list[float]:
    """The action's ``size`` numbers, checked and clipped onto [-1, 1], as Python floats (a handful of values:
    plain Python is quicker here than NumPy's per-call overhead)."""
    if action is None:
        raise ValueError(f"action for {agent}: expected {size} numbers in [-1, 1], got None")
    try:
        arr = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"action for {agent}: expected {size} numbers, got {action!r}") from None
    if arr.shape != (size,):
        raise ValueError(f"action for {agent}: expected shape ({size},), got {arr.shape}")
    values = arr.tolist()
    limit = 1.0 + RANGE_TOLERANCE
    if not all(-limit <= v <= limit for v in values):  # one test passes every valid action (NaN fails it)
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"action for {agent}: must be finite, got {values}")
        raise ValueError(f"action for {agent}: values must be in [-1, 1], got {values}")
    return [min(max(v, -1.0), 1.0) for v in values]


def _button(pressed: bool) -> float:
    return 1.0 if pressed else -1.0


class ActionParser(ABC):
    """Turns one agent's policy output into ``CarControls``; one space for every agent."""

    @abstractmethod
    def space(self) -> spaces.Space:
        """The action space, the same for every agent."""

    @abstractmethod
    def parse(self, agent: str, action, state: GameState | None = None) -> CarControls:
        """``agent``'s action as controls; ValueError naming the agent if it is not in the space."""

    @abstractmethod
    def encode(self, controls: CarControls):
        """The action (in this parser's space) closest to ``controls``: how scripted bots act through the env."""


class ContinuousActions(ActionParser):
    """``Box(-1, 1, (8,))``: throttle, steer, pitch, yaw, roll, then jump, boost, handbrake as buttons (> 0)."""

    def space(self) -> spaces.Box:
        return spaces.Box(-1.0, 1.0, (8,), np.float32)

    def parse(self, agent: str, action, state: GameState | None = None) -> CarControls:
        a = _vector(agent, action, 8)
        return CarControls(*a[:5], jump=a[5] > 0.0, boost=a[6] > 0.0, handbrake=a[7] > 0.0)

    def encode(self, controls: CarControls) -> np.ndarray:
        c = controls
        return np.array([c.throttle, c.steer, c.pitch, c.yaw, c.roll, _button(c.jump), _button(c.boost),
                         _button(c.handbrake)], dtype=np.float32)


class DriveActions(ActionParser):
    """Five driving controls, ``Box(-1, 1, (5,))``: throttle, steer, then jump, boost, drift (handbrake) as
    buttons; no air control (pitch, yaw, roll). The RocketDRL seed's action set."""

    def space(self) -> spaces.Box:
        return spaces.Box(-1.0, 1.0, (5,), np.float32)

    def parse(self, agent: str, action, state: GameState | None = None) -> CarControls:
        a = _vector(agent, action, 5)
        return CarControls(throttle=a[0], steer=a[1], jump=a[2] > 0.0, boost=a[3] > 0.0, handbrake=a[4] > 0.0)

    def encode(self, controls: CarControls) -> np.ndarray:
        c = controls
        return np.array([c.throttle, c.steer, _button(c.jump), _button(c.boost), _button(c.handbrake)],
                        dtype=np.float32)


def lookup_table() -> np.ndarray:
    """RLGym's 90 control combinations (``LookupTableAction.make_lookup_table``), rows of
    [throttle, steer, pitch, yaw, roll, jump, boost, handbrake].

    Ground (24): throttle x steer x boost x handbrake, boost only with throttle 1; yaw follows steer so
    the row also turns in the air. Aerial (66): pitch x yaw x roll x jump x boost, without jumps that yaw
    (roll gives the side flips) and without the rows pitch = roll = jump = 0 (ground duplicates); throttle
    follows boost, and handbrake is held on jumps with a direction (wavedashes).
    """
    rows = []
    for throttle in (-1, 0, 1):  # on the ground
        for steer in (-1, 0, 1):
            for boost in (0, 1):
                for handbrake in (0, 1):
                    if boost == 1 and throttle != 1:
                        continue
                    rows.append([throttle or boost, steer, 0, steer, 0, 0, boost, handbrake])
    for pitch in (-1, 0, 1):  # in the air
        for yaw in (-1, 0, 1):
            for roll in (-1, 0, 1):
                for jump in (0, 1):
                    for boost in (0, 1):
                        if jump == 1 and yaw != 0:  # roll gives the side flips
                            continue
                        if pitch == roll == jump == 0:  # already a ground action
                            continue
                        handbrake = int(jump == 1 and (pitch != 0 or yaw != 0 or roll != 0))  # wavedashes
                        rows.append([boost, yaw, pitch, yaw, roll, jump, boost, handbrake])
    return np.array(rows, dtype=np.float64)


class LookupTableActions(ActionParser):
    """``Discrete(90)``: an index into RLGym's standard table of control combinations (``lookup_table``)."""

    def __init__(self):
        self.table = lookup_table()
        self._signed_table = self.table.copy()  # buttons as +-1, as ``encode`` compares them
        self._signed_table[:, 5:] = np.where(self.table[:, 5:] > 0, 1.0, -1.0)

    def space(self) -> spaces.Discrete:
        return spaces.Discrete(len(self.table))

    def parse(self, agent: str, action, state: GameState | None = None) -> CarControls:
        """Accepts a Python int, a numpy integer scalar or a shape-(1,) integer array."""
        try:
            arr = np.asarray(action)
        except (TypeError, ValueError):
            raise ValueError(f"action for {agent}: expected one integer index, got {action!r}") from None
        if arr.shape not in ((), (1,)) or not np.issubdtype(arr.dtype, np.integer):
            raise ValueError(f"action for {agent}: expected one integer index, got {action!r}")
        index = int(arr.reshape(-1)[0])
        if not 0 <= index < len(self.table):
            raise ValueError(f"action for {agent}: index must be in 0..{len(self.table) - 1}, got {index}")
        r = self.table[index]
        return CarControls(*r[:5], jump=r[5] > 0, boost=r[6] > 0, handbrake=r[7] > 0)

    def encode(self, controls: CarControls) -> int:
        """The nearest row with the same jump button (L1 over the eight controls, buttons as +-1), the
        controls first put in the table's conventions: with no air input (pitch, yaw and roll 0, as a
        driving bot gives) yaw follows steer, as in the ground rows, or every hard-steering row would be one
        yaw off and a bot could not turn; a jump holds handbrake exactly when it has a direction, as in the
        jump rows, or a dodge would be nearer the plain jump. The jump is kept whatever else differs: a
        dropped press loses a jump or a dodge, a dropped steer only one decision's turn."""
        target = ContinuousActions().encode(controls).astype(np.float64)
        air_input = not controls.pitch == controls.yaw == controls.roll == 0.0
        if not air_input:
            target[3] = target[1]
        if controls.jump:
            target[7] = 1.0 if air_input else -1.0
        distance = np.abs(self._signed_table - target).sum(axis=1)
        distance[self._signed_table[:, 5] != target[5]] = np.inf
        return int(np.argmin(distance))


ACTION_PARSERS: dict[str, type[ActionParser]] = {
    "continuous": ContinuousActions, "drive": DriveActions, "lookup": LookupTableActions}
ACTION_PARSERS.update({old: ACTION_PARSERS[new] for old, new in ACTION_NAMES.items()})  # old names still accepted


def make_action_parser(name: str, **kwargs) -> ActionParser:
    """A parser by registry name; unknown names and options are ValueErrors naming the allowed ones."""
    if isinstance(name, str):
        name = current_name("action", name, ACTION_NAMES)
    if not isinstance(name, str) or name not in ACTION_PARSERS:
        raise ValueError(f"action: unknown action parser {name!r}; allowed: {sorted(ACTION_PARSERS)}")
    cls = ACTION_PARSERS[name]
    allowed = [p for p in inspect.signature(cls.__init__).parameters if p not in ("self", "args", "kwargs")]
    unknown = sorted(set(kwargs) - set(allowed))
    if unknown:
        raise ValueError(f"action.{name}: unknown option(s) {unknown}; allowed: {allowed}")
    return cls(**kwargs)


def __getattr__(name: str) -> type:
    """``SeedActions`` (now ``DriveActions``) still imports, with a DeprecationWarning."""
    return renamed_class(__name__, name, globals())
