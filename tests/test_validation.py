"""The shared config checks: every message names the field and what is allowed."""
from __future__ import annotations

import math

import pytest

from rocketdrl_ma.validation import (as_mapping, check_bool, check_choice, check_int, check_name, check_number,
                                     reject_unknown)


def test_unknown_keys_are_listed_with_the_allowed_ones():
    with pytest.raises(ValueError, match=r"limits: unknown key\(s\) \['max_mathces'\]; allowed: \['a', 'b'\]"):
        reject_unknown("limits", {"max_mathces": 1, "a": 2}, ("b", "a"))
    assert as_mapping("access", None) == {} and as_mapping("access", {"a": 1}, ("a",)) == {"a": 1}
    with pytest.raises(ValueError, match="access: expected a mapping"):
        as_mapping("access", [1])


@pytest.mark.parametrize("value, message", [(True, "expected an int"), (1.0, "expected an int"),
                                            (0, r"must be >= 1"), (11, r"must be in \[1, 10\]")])
def test_ints(value, message):
    if message == r"must be >= 1":
        with pytest.raises(ValueError, match=f"n_envs: {message}"):
            check_int("n_envs", value, minimum=1)
    else:
        with pytest.raises(ValueError, match=f"n_envs: {message}"):
            check_int("n_envs", value, 1, 10)
    assert check_int("n_envs", 3, 1, 10) == 3


def test_numbers_are_finite_floats_in_range():
    assert check_number("gamma", 1, 0.0, 1.0) == 1.0 and isinstance(check_number("gamma", 1), float)
    for bad in (math.inf, math.nan, "0.5", False, None):
        with pytest.raises(ValueError, match="gamma: expected a finite number"):
            check_number("gamma", bad)
    with pytest.raises(ValueError, match=r"epsilon: must be > 0.0"):
        check_number("epsilon", 0.0, above=0.0)


def test_bools_choices_and_names():
    assert check_bool("async", False) is False
    with pytest.raises(ValueError, match="async: expected true or false"):
        check_bool("async", "no")
    with pytest.raises(ValueError, match=r"device: 'tpu' is not one of \['auto', 'cpu', 'cuda'\]"):
        check_choice("device", "tpu", ("auto", "cpu", "cuda"))
    for good in ("alice", "selfplay_1.09M", "m-1", "x" * 64):
        assert check_name("name", good) == good
    for bad in ("", ".", "..", "../etc", "a/b", "*", "a$b", "x" * 65, 3, "-flag"):
        with pytest.raises(ValueError, match="name: expected 1-64 letters"):
            check_name("name", bad)
