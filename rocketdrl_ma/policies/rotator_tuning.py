"""The rotator's searched settings as data: which cars rotate, how the roles are picked, where the last man stands,
the pad detours and the kickoff tables by team size (``rotation.py`` plays by them).

The shipped values are ``data/rotator_tuning.yaml``; ``tools/search_kickoffs.py --write`` rewrites a team size's
kickoff table there in ``format_tuning``'s layout. How each value was chosen: docs/experiments/rotator-tuning.md.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, fields, replace
from enum import Enum
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

from rocketdrl_ma.config import load_yaml_file
from rocketdrl_ma.validation import Check, Expect, Range, check_choice, load_dataclass

#: the team sizes with tables of their own; a single car has no team-mate to rotate with
TEAM_SIZES = (2, 3, 4)


class KickoffLane(Enum):
    """Where a car comes from at a kickoff, by its bearing from the centre spot: a diagonal spot (39 deg off the
    field's long axis), an off-centre spot (4 deg), or straight behind the ball."""
    DIAGONAL = "diagonal"
    OFF_CENTRE = "off_centre"
    BACK = "back"


#: the lanes of a team's first and second kickoff taker
Layout = tuple[KickoffLane, KickoffLane]
LANE_NAMES = [lane.value for lane in KickoffLane]
LaneName = Literal["diagonal", "off_centre", "back"]
TeamSize = Literal[2, 3, 4]


def _lane_pair(field: str, pair: tuple) -> Layout:
    if len(pair) != 2:
        raise ValueError(f"{field}: expected [first lane, second lane] of {LANE_NAMES}, got {list(pair)!r}")
    return KickoffLane(pair[0]), KickoffLane(pair[1])


def _aims_by_layout(_: str, aims: dict) -> dict[Layout, float]:
    return {(KickoffLane(first), KickoffLane(second)): uu for first, row in aims.items() for second, uu in row.items()}


def _layout_set(_: str, layouts: tuple) -> frozenset[Layout]:
    return frozenset(layouts)


def _every_team_size(field: str, by_size: dict) -> dict:
    if sorted(by_size) != list(TEAM_SIZES):
        raise ValueError(f"{field}: expected one entry for each team size {list(TEAM_SIZES)}, got {list(by_size)}")
    return {size: by_size[size] for size in TEAM_SIZES}


def _detour(field: str, pair: tuple) -> tuple[float, float]:
    if len(pair) != 2:
        raise ValueError(f"{field}: expected [small pad uu, big pad uu], got {list(pair)!r}")
    return pair


LanePair = Annotated[tuple[LaneName, ...], Check(_lane_pair)]
Detour = Annotated[tuple[Annotated[float, Range(0.0)], ...], Check(_detour),
                   Expect("[small pad uu, big pad uu]")]


@dataclass(frozen=True)
class KickoffTable:
    """One team size's kickoff: how far beside the ball the second taker aims by layout (uu along x, towards its own
    side of the long axis when positive; a layout not listed aims at the ball's centre), and the layouts where the
    nearest car goes alone and the other stays back. The lanes are read every decision and a car staying back drives
    into the back lane, so ``alone`` names the layouts a kickoff turns into on the way too. The annotations say what
    the file holds (``{first lane: {second lane: uu}}``, a list of lane pairs); read, they are keyed by ``Layout``."""
    second_aim_uu: Annotated[dict[LaneName, dict[LaneName, float]], Check(_aims_by_layout)]
    alone: Annotated[tuple[LanePair, ...], Check(_layout_set),
                     Expect("a list of [first lane, second lane] pairs")]


@dataclass(frozen=True)
class RotatorTuning:
    """The settings ``rotation.py`` plays by, one field per key of the tuning file (every key required). Its dicts
    are not changed in place: ``dataclasses.replace`` (or ``with_kickoff_table``) makes a variant."""
    rotating_cars: Annotated[int, Range(1, TEAM_SIZES[-1])]  # cars that rotate outside kickoffs; the others press
    wrong_side_cost_s: float       # the first man's pick: a car upfield of the ball pays this for turning round
    keep_role_bonus_s: float       # the last toucher near the ball keeps the first man's role at this head start
    follow_up_goal_side_uu: float  # the follow-up car is at least this much nearer its own goal than the ball
    last_behind_pair_uu: float     # the last man's distance behind the ball with one other rotating car
    last_man_line_y_uu: float      # with pressers on the team, the last man goes no further up (team frame y)
    low_boost: Annotated[float, Range(0.0, 100.0)]  # below this much boost a car coming back takes a pad on the way
    #: by team size: the detour a small pad, a big pad is worth
    detour_uu: Annotated[dict[TeamSize, Detour], Check(_every_team_size)]
    kickoff: Annotated[dict[TeamSize, KickoffTable], Check(_every_team_size)]  # by team size

    def detour_for(self, team_size: int) -> tuple[float, float]:
        """``detour_uu`` of a match with ``team_size`` cars a side (1v1 takes 2v2's)."""
        return self.detour_uu[min(max(team_size, TEAM_SIZES[0]), TEAM_SIZES[-1])]


SHIPPED_FILE = "data/rotator_tuning.yaml"  # inside this package


@functools.cache
def shipped_tuning() -> RotatorTuning:
    """The shipped settings, read once."""
    with resources.as_file(resources.files(__package__) / SHIPPED_FILE) as path:
        return read_tuning(path)


def read_tuning(path: str | Path) -> RotatorTuning:
    """The settings in the YAML file ``path``; a bad value is a ValueError naming its field and what is allowed."""
    return parse_tuning(load_yaml_file(path, "rotator tuning"), f"rotator tuning {Path(path).name}")


def parse_tuning(data: Any, source: str = "rotator tuning") -> RotatorTuning:
    """``data`` (a mapping with every field of ``RotatorTuning``, as in ``format_tuning``'s text) checked."""
    return load_dataclass(RotatorTuning, data, source, f"{source}: ")


def parse_kickoff_table(field: str, data: Any) -> KickoffTable:
    return load_dataclass(KickoffTable, data, field, f"{field}.")


HEADER = """\
# The rotator's searched settings (rocketdrl_ma/policies/rotation.py plays by them, rotator_tuning.py reads them).
# How each value was chosen: docs/experiments/rotator-tuning.md. `python tools/search_kickoffs.py --size N --write`
# rewrites team size N's kickoff table. Lanes: diagonal, off_centre, back (kickoff_lane in rotation.py).
"""


def kickoff_table_data(table: KickoffTable) -> dict[str, Any]:
    """``table`` as plain data, lanes in ``KickoffLane``'s order: what ``parse_kickoff_table`` reads."""
    aims: dict[str, dict[str, float]] = {}
    for first, second in sorted(table.second_aim_uu, key=_lane_order):
        aims.setdefault(first.value, {})[second.value] = table.second_aim_uu[first, second]
    return {"second_aim_uu": aims, "alone": [[first.value, second.value] for first, second in sorted(
        table.alone, key=_lane_order)]}


def _lane_order(layout: Layout) -> tuple[int, int]:
    return LANE_NAMES.index(layout[0].value), LANE_NAMES.index(layout[1].value)


def format_tuning(tuning: RotatorTuning) -> str:
    """``tuning`` as the text of a tuning file: the shipped file's layout, which ``read_tuning`` reads back."""
    lines = [HEADER.rstrip("\n")]
    lines += [f"{f.name}: {getattr(tuning, f.name)!r}" for f in fields(RotatorTuning)
              if f.name not in ("detour_uu", "kickoff")]
    lines.append("detour_uu:  # by team size: [small pad, big pad]")
    lines += [f"  {size}: [{small!r}, {big!r}]" for size, (small, big) in sorted(tuning.detour_uu.items())]
    lines.append("kickoff:  # by team size")
    for size, table in sorted(tuning.kickoff.items()):
        data = kickoff_table_data(table)
        lines.append(f"  {size}:")
        empty = "" if data["second_aim_uu"] else " {}"
        lines.append(f"    second_aim_uu:{empty}  # first taker's lane: {{second taker's lane: uu}}")
        for first, row in data["second_aim_uu"].items():
            lines.append(f"      {first}:")
            lines += [f"        {second}: {uu!r}" for second, uu in row.items()]
        lines.append("    alone:" + ("" if data["alone"] else " []"))
        lines += [f"      - [{first}, {second}]" for first, second in data["alone"]]
    return "\n".join(lines) + "\n"


def with_kickoff_table(tuning: RotatorTuning, team_size: int, table: KickoffTable) -> RotatorTuning:
    """``tuning`` with team size ``team_size``'s kickoff table replaced."""
    check_choice("team_size", team_size, TEAM_SIZES)
    return replace(tuning, kickoff={**tuning.kickoff, team_size: table})
