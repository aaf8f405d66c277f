"""The shared config checks and the loader of every config dataclass: every message names the field and what is
allowed, and every shipped config loads."""
from __future__ import annotations

import dataclasses
import math
from typing import Annotated, Literal

import pytest

from rocketdrl_ma.config import load_config, shipped_files
from rocketdrl_ma.validation import (Check, Expect, Name, OneOf, Range, as_mapping, check_bool, check_choice,
                                     check_int, check_name, check_number, check_value, checked_fields,
                                     load_dataclass, reject_unknown)


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


@dataclasses.dataclass(frozen=True)
class Inner:
    count: Annotated[int, Range(minimum=1)] = 1
    share: Annotated[float, Range(0.0, 1.0)] = 0.5


@dataclasses.dataclass(frozen=True)
class Outer:
    name: Name
    mode: Literal["fast", "slow"] = "fast"
    device: Annotated[str, OneOf(("cpu", "cuda"))] = "cpu"
    inner: Inner = dataclasses.field(default_factory=Inner)
    extra: Inner | None = None
    limit: Annotated[int, Range(minimum=0)] | None = None
    hosts: Annotated[tuple[str, ...], Expect("a list of host names")] = ()
    weights: dict[str, float] = dataclasses.field(default_factory=dict)
    source: Annotated[str | dict, Expect("a path or a mapping")] = "a.yaml"
    even: Annotated[int, Check(_even)] = 0
    asynchronous: bool = dataclasses.field(default=False, metadata={"key": "async"})

    def check(self) -> None:
        if self.mode == "slow" and self.inner.count > 3:
            raise ValueError("inner.count: at most 3 when mode is 'slow'")


def _even(field: str, n: int) -> int:
    if n % 2:
        raise ValueError(f"{field}: expected an even number, got {n}")
    return n


def test_a_mapping_loads_as_its_dataclass_with_values_converted_and_defaults_filled_in():
    outer = load_dataclass(Outer, {"name": "a", "inner": {"share": 1}, "hosts": ["h1", "h2"], "async": True,
                                   "weights": {"x": 2}, "source": {"mode": "match"}, "limit": None}, "outer")
    assert outer == Outer(name="a", inner=Inner(share=1.0), hosts=("h1", "h2"), asynchronous=True,
                          weights={"x": 2.0}, source={"mode": "match"})
    assert isinstance(outer.inner.share, float) and isinstance(outer.weights["x"], float)
    assert load_dataclass(Outer, {"name": "a", "extra": {}}, "outer").extra is None  # an empty section is off
    assert load_dataclass(Outer, {"name": "a", "extra": {"count": 2}}, "outer").extra == Inner(count=2)
    assert load_dataclass(Outer, outer, "outer") is outer
    base = Outer(name="b", mode="slow")
    assert load_dataclass(Outer, {"device": "cuda"}, "outer", base=base) == Outer(name="b", mode="slow", device="cuda")


@pytest.mark.parametrize("raw, message", [
    ({}, r"^outer: 'name' is required$"),
    ({"name": "a", "nmae": 1}, r"^outer: unknown key\(s\) \['nmae'\]; allowed: \['async', 'device', "),
    ([1], r"^outer: expected a mapping with \['async', 'device', "),
    ({"name": "a/b"}, r"^name: expected 1-64 letters"),
    ({"name": "a", "mode": "medium"}, r"^mode: 'medium' is not one of \['fast', 'slow'\]$"),
    ({"name": "a", "device": "tpu"}, r"^device: 'tpu' is not one of \['cpu', 'cuda'\]$"),
    ({"name": "a", "inner": {"count": 0}}, r"^inner.count: must be >= 1, got 0$"),
    ({"name": "a", "inner": {"share": 2}}, r"^inner.share: must be in \[0.0, 1.0\], got 2$"),
    ({"name": "a", "inner": {"share": "half"}}, r"^inner.share: expected a finite number, got 'half'$"),
    ({"name": "a", "inner": {"cuont": 2}}, r"^inner: unknown key\(s\) \['cuont'\]; allowed: \['count', 'share'\]$"),
    ({"name": "a", "inner": 3}, r"^inner: expected a mapping with \['count', 'share'\], got 3$"),
    ({"name": "a", "extra": {"count": 1.5}}, r"^extra.count: expected an int, got 1.5$"),
    ({"name": "a", "limit": -1}, r"^limit: must be >= 0, got -1$"),
    ({"name": "a", "limit": "none"}, r"^limit: expected an int, got 'none'$"),
    ({"name": "a", "hosts": "h1"}, r"^hosts: expected a list of host names, got 'h1'$"),
    ({"name": "a", "hosts": ["h1", 2]}, r"^hosts\[1\]: expected a string, got 2$"),
    ({"name": "a", "weights": {"x": "heavy"}}, r"^weights.x: expected a finite number, got 'heavy'$"),
    ({"name": "a", "weights": [1]}, r"^weights: expected a mapping, got \[1\]$"),
    ({"name": "a", "source": 3}, r"^source: expected a path or a mapping, got 3$"),
    ({"name": "a", "even": 3}, r"^even: expected an even number, got 3$"),
    ({"name": "a", "async": "yes"}, r"^async: expected true or false, got 'yes'$"),
    ({"name": "a", "mode": "slow", "inner": {"count": 4}}, r"^inner.count: at most 3 when mode is 'slow'$"),
])
def test_every_error_names_the_field_and_what_is_allowed(raw, message):
    with pytest.raises(ValueError, match=message):
        load_dataclass(Outer, raw, "outer")


def test_a_config_made_in_python_is_checked_as_a_yaml_would_be():
    assert checked_fields(Outer(name="a", hosts=["h"]), "outer ")["hosts"] == ("h",)
    with pytest.raises(ValueError, match=r"^outer inner.count: must be >= 1, got 0$"):
        checked_fields(Outer(name="a", inner={"count": 0}), "outer ")
    assert check_value("seed", None, int | None) is None
    with pytest.raises(ValueError, match=r"^seed: must be >= 0, got -1$"):
        check_value("seed", -1, Annotated[int | None, Range(minimum=0)])


# every shipped config through the loader its folder's files are read by
def _loader(name: str):
    from rocketdrl_ma.league.config import load_league_config
    from rocketdrl_ma.league.curve_config import load_curve_config
    from rocketdrl_ma.policies.ppo.config import load_train_config
    from rocketdrl_ma.server.router import RouterSettings
    from rocketdrl_ma.server.settings import ClientSettings, ServerSettings

    folder, file = name.split("/", 1)
    if folder == "leagues" and file.startswith("curves/"):
        return load_curve_config
    if folder == "server":
        return {"client.yaml": ClientSettings.load, "router.yaml": RouterSettings.load}.get(file, ServerSettings.load)
    return {"matches": load_config, "minigames": load_config, "policies": load_train_config,
            "leagues": load_league_config}[folder]


SHIPPED_CONFIGS = [name for name in shipped_files() if name.count("/") == 1 or name.startswith("leagues/curves/")]


def test_the_shipped_configs_are_found():
    folders = {name.split("/")[0] for name in SHIPPED_CONFIGS}
    assert folders == {"matches", "minigames", "policies", "server", "leagues"}


@pytest.mark.parametrize("name", SHIPPED_CONFIGS)
def test_every_shipped_config_loads(name):
    assert _loader(name)(name) is not None
