"""The rotator's settings file (``policies/rotator_tuning.py``): the shipped file reads, writes back to the same text,
and a bad value is a ValueError naming its field and what is allowed."""
import dataclasses
from importlib import resources

import pytest
import yaml

from rocketdrl_ma.policies import rotator_tuning
from rocketdrl_ma.policies.rotator_tuning import KickoffLane, KickoffTable, format_tuning, parse_tuning, read_tuning
from rocketdrl_ma.policies.scripted import make_scripted

SHIPPED = rotator_tuning.shipped_tuning()


def _shipped_data() -> dict:
    return yaml.safe_load(format_tuning(SHIPPED))


def test_the_shipped_file_is_in_the_layout_the_search_writes():
    """``tools/search_kickoffs.py --write`` writes ``format_tuning``'s text, so rewriting a table changes only it."""
    shipped = resources.files("rocketdrl_ma.policies") / rotator_tuning.SHIPPED_FILE
    assert format_tuning(SHIPPED) == shipped.read_text()


def test_a_file_round_trips_and_the_rotator_plays_by_it(tmp_path):
    tables = {**SHIPPED.kickoff, 3: KickoffTable({(KickoffLane.DIAGONAL, KickoffLane.BACK): 25.0}, frozenset())}
    tuning = dataclasses.replace(SHIPPED, rotating_cars=3, kickoff=tables)
    path = tmp_path / "tuning.yaml"
    path.write_text(format_tuning(tuning))
    assert read_tuning(path) == tuning
    assert make_scripted("rotator").tuning == SHIPPED
    empty = dataclasses.replace(tuning, kickoff={**tables, 2: KickoffTable({}, frozenset())})
    path.write_text(format_tuning(empty))
    assert read_tuning(path) == empty


@pytest.mark.parametrize("team_size, detour", [(1, 2), (2, 2), (3, 3), (4, 4)])
def test_a_match_of_one_a_side_takes_the_2v2_detours(team_size, detour):
    assert SHIPPED.detour_for(team_size) == SHIPPED.detour_uu[detour]


def _set(data: dict, path: tuple, value) -> dict:
    *parents, last = path
    node = data
    for key in parents:
        node = node[key]
    if value is _set:
        del node[last]
    else:
        node[last] = value
    return data


@pytest.mark.parametrize("path, value, message", [
    (("rotating_cars",), 5, "rotating_cars: must be in [1, 4], got 5"),
    (("rotating_cars",), 2.0, "rotating_cars: expected an int"),
    (("low_boost",), 120.0, "low_boost: must be in [0.0, 100.0]"),
    (("wrong_side_cost_s",), "fast", "wrong_side_cost_s: expected a finite number"),
    (("last_man_line_y_uu",), _set, "'last_man_line_y_uu' is required"),
    (("nonsense",), 1, "unknown key(s) ['nonsense']"),
    (("detour_uu", 4), _set, "detour_uu: expected one entry for each team size [2, 3, 4], got [2, 3]"),
    (("detour_uu", 2), [500.0], "detour_uu.2: expected [small pad uu, big pad uu]"),
    (("detour_uu", 3), [800.0, -1.0], "detour_uu.3[1]: must be >= 0.0"),
    (("kickoff", 2, "second_aim_uu", "diagonal", "sideways"), 10.0,
     "kickoff.2.second_aim_uu.diagonal key: 'sideways' is not one of ['diagonal', 'off_centre', 'back']"),
    (("kickoff", 2, "second_aim_uu", "wide"), {"back": 1.0},
     "kickoff.2.second_aim_uu key: 'wide' is not one of ['diagonal', 'off_centre', 'back']"),
    (("kickoff", 3, "second_aim_uu", "diagonal", "diagonal"), None,
     "kickoff.3.second_aim_uu.diagonal.diagonal: expected a finite number"),
    (("kickoff", 4, "alone", 0), ["off_centre"], "kickoff.4.alone[0]: expected [first lane, second lane]"),
    (("kickoff", 4, "alone", 1), ["off_centre", "front"], "kickoff.4.alone[1][1]: 'front' is not one of"),
    (("kickoff", 2, "alone"), _set, "kickoff.2: 'alone' is required"),
])
def test_a_bad_value_names_its_field_and_what_is_allowed(path, value, message):
    with pytest.raises(ValueError) as error:
        parse_tuning(_set(_shipped_data(), path, value))
    assert message in str(error.value)
