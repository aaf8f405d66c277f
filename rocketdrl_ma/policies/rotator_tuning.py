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
from typing import Any

from rocketdrl_ma.config import load_yaml_file
from rocketdrl_ma.validation import as_mapping, check_choice, check_int, check_number

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


@dataclass(frozen=True)
class KickoffTable:
    """One team size's kickoff: how far beside the ball the second taker aims by layout (uu along x, towards its own
    side of the long axis when positive; a layout not listed aims at the ball's centre), and the layouts where the
    nearest car goes alone and the other stays back. The lanes are read every decision and a car staying back drives
    into the back lane, so ``alone`` names the layouts a kickoff turns into on the way too."""
    second_aim_uu: dict[Layout, float]
    alone: frozenset[Layout]


@dataclass(frozen=True)
class RotatorTuning:
    """The settings ``rotation.py`` plays by, one field per key of the tuning file. Its dicts are not changed in
    place: ``dataclasses.replace`` (or ``with_kickoff_table``) makes a variant."""
    rotating_cars: int             # cars that rotate outside kickoffs; the team's others are pressers
    wrong_side_cost_s: float       # the first man's pick: a car upfield of the ball pays this for turning round
    keep_role_bonus_s: float       # the last toucher near the ball keeps the first man's role at this head start
    follow_up_goal_side_uu: float  # the follow-up car is at least this much nearer its own goal than the ball
    last_behind_pair_uu: float     # the last man's distance behind the ball with one other rotating car
    last_man_line_y_uu: float      # with pressers on the team, the last man goes no further up (team frame y)
    low_boost: float               # below this much boost a car coming back takes a pad on the way
    detour_uu: dict[int, tuple[float, float]]  # by team size: the detour a small pad, a big pad is worth
    kickoff: dict[int, KickoffTable]           # by team size

    def detour_for(self, team_size: int) -> tuple[float, float]:
        """``detour_uu`` of a match with ``team_size`` cars a side (1v1 takes 2v2's)."""
        return self.detour_uu[min(max(team_size, TEAM_SIZES[0]), TEAM_SIZES[-1])]


SHIPPED_FILE = "data/rotator_tuning.yaml"  # inside this package
LANE_NAMES = [lane.value for lane in KickoffLane]


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
    given = _every_key(source, data, [f.name for f in fields(RotatorTuning)])
    numbers = {name: check_number(f"{source}: {name}", given[name]) for name in
               ("wrong_side_cost_s", "keep_role_bonus_s", "follow_up_goal_side_uu", "last_behind_pair_uu",
                "last_man_line_y_uu")}
    detours = _by_team_size(f"{source}: detour_uu", given["detour_uu"])
    kickoff = _by_team_size(f"{source}: kickoff", given["kickoff"])
    return RotatorTuning(
        rotating_cars=check_int(f"{source}: rotating_cars", given["rotating_cars"], 1, TEAM_SIZES[-1]),
        low_boost=check_number(f"{source}: low_boost", given["low_boost"], 0.0, 100.0),
        detour_uu={size: _detour(f"{source}: detour_uu.{size}", value) for size, value in detours.items()},
        kickoff={size: parse_kickoff_table(f"{source}: kickoff.{size}", value) for size, value in kickoff.items()},
        **numbers)


def parse_kickoff_table(field: str, data: Any) -> KickoffTable:
    table = _every_key(field, data, ["second_aim_uu", "alone"])
    aims = {}
    for first, seconds in as_mapping(f"{field}.second_aim_uu", table["second_aim_uu"]).items():
        for second, aside in as_mapping(f"{field}.second_aim_uu.{first}", seconds).items():
            where = f"{field}.second_aim_uu.{first}.{second}"
            aims[_lane(f"{field}.second_aim_uu", first), _lane(where, second)] = check_number(where, aside)
    alone = table["alone"]
    if not isinstance(alone, list):
        raise ValueError(f"{field}.alone: expected a list of [first lane, second lane] pairs, got {alone!r}")
    layouts = set()
    for k, pair in enumerate(alone):
        if not (isinstance(pair, list) and len(pair) == 2):
            raise ValueError(f"{field}.alone[{k}]: expected [first lane, second lane] of {LANE_NAMES}, got {pair!r}")
        layouts.add((_lane(f"{field}.alone[{k}]", pair[0]), _lane(f"{field}.alone[{k}]", pair[1])))
    return KickoffTable(aims, frozenset(layouts))


def _every_key(field: str, data: Any, names: list[str]) -> dict:
    given = as_mapping(field, data, names)
    missing = [name for name in names if name not in given]
    if missing:
        raise ValueError(f"{field}: missing {missing}; every one of {names} is required")
    return given


def _lane(field: str, name: Any) -> KickoffLane:
    return KickoffLane(check_choice(field, name, LANE_NAMES))


def _by_team_size(field: str, data: Any) -> dict[int, Any]:
    given = as_mapping(field, data)
    if sorted(given, key=str) != list(TEAM_SIZES):
        raise ValueError(f"{field}: expected one entry for each team size {list(TEAM_SIZES)}, got {list(given)}")
    return {size: given[size] for size in TEAM_SIZES}


def _detour(field: str, value: Any) -> tuple[float, float]:
    if not (isinstance(value, list) and len(value) == 2):
        raise ValueError(f"{field}: expected [small pad uu, big pad uu], got {value!r}")
    return check_number(f"{field}[0]", value[0], 0.0), check_number(f"{field}[1]", value[1], 0.0)


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
