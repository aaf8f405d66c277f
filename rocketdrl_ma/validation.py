"""The checks every config of the package shares (env and minigame YAMLs, training, self-play, leagues, server
and client settings): each failure is a ValueError that names the field and says what is allowed, so a bad
value in any YAML reads the same way. Imports nothing of the package; everything may use it.

A config is a dataclass whose annotations say what each key holds; ``load_dataclass`` reads a YAML mapping into
it. ``int``, ``float``, ``bool``, ``str``, ``Literal[...]``, ``X | None``, ``tuple[X, ...]``, ``dict[K, V]``,
unions and nested config dataclasses are checked by their type; ``typing.Annotated`` adds what a type cannot
say: ``Range`` (bounds), ``OneOf`` (a registry's names), ``Check`` (a function of the field and its value) and
``Expect`` (how the error describes what is expected). What ties fields together is the dataclass's ``check()``.
"""
from __future__ import annotations

import dataclasses
import functools
import math
import re
import types
import typing
from collections.abc import Callable, Collection, Mapping
from typing import Annotated, Any, Literal, TypeVar

T = TypeVar("T")

#: names that become Zenoh key-expression chunks, match keys, file names: 1-64 of letters, digits, '_', '-', '.',
#: starting with a letter or digit (so never '.' or '..')
NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]{0,63}$")


def reject_unknown(section: str, given: Mapping, allowed: Collection[str]) -> None:
    unknown = sorted(set(given) - set(allowed), key=str)
    if unknown:
        raise ValueError(f"{section}: unknown key(s) {unknown}; allowed: {sorted(allowed)}")


def as_mapping(section: str, value: Any, allowed: Collection[str] | None = None) -> dict:
    """``value`` as a dict (None: empty); with ``allowed``, unknown keys are rejected too."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ValueError(f"{section}: expected a mapping{f' with {sorted(allowed)}' if allowed else ''}, "
                         f"got {value!r}")
    if allowed is not None:
        reject_unknown(section, value, allowed)
    return dict(value)


def yaml_key(field: dataclasses.Field) -> str:
    """The key a config file gives a dataclass field by: its ``metadata["key"]`` (for a name Python reserves, such
    as ``async``), else the field's name."""
    return field.metadata.get("key", field.name)


def check_int(field: str, value: Any, minimum: int | None = None, maximum: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{field}: expected an int, got {value!r}")
    _check_range(field, value, minimum, maximum)
    return value


def check_number(field: str, value: Any, minimum: float | None = None, maximum: float | None = None,
                 above: float | None = None) -> float:
    """A finite int or float as a float, within [minimum, maximum] and > ``above`` where given."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{field}: expected a finite number, got {value!r}")
    _check_range(field, value, minimum, maximum)
    if above is not None and not value > above:
        raise ValueError(f"{field}: must be > {above}, got {value!r}")
    return float(value)


def check_bool(field: str, value: Any) -> bool:
    if not isinstance(value, bool):
        raise ValueError(f"{field}: expected true or false, got {value!r}")
    return value


def check_choice(field: str, value: Any, allowed: Collection) -> Any:
    if value not in allowed:
        raise ValueError(f"{field}: {value!r} is not one of {list(allowed)}")
    return value


def check_name(field: str, value: Any) -> str:
    """Server, user, match, slot, league and entrant names (``NAME_PATTERN``)."""
    if not isinstance(value, str) or not NAME_PATTERN.match(value):
        raise ValueError(f"{field}: expected 1-64 letters, digits, '_', '-' or '.', starting with a letter or "
                         f"digit, got {value!r}")
    return value


def _check_range(field: str, value: float, minimum: float | None, maximum: float | None) -> None:
    if minimum is not None and value < minimum or maximum is not None and value > maximum:
        bounds = f"in [{minimum}, {maximum}]" if minimum is not None and maximum is not None else (
            f">= {minimum}" if minimum is not None else f"<= {maximum}")
        raise ValueError(f"{field}: must be {bounds}, got {value!r}")


@dataclasses.dataclass(frozen=True)
class Range:
    """Bounds of an int or float field: within [minimum, maximum] and > ``above`` where given."""
    minimum: float | None = None
    maximum: float | None = None
    above: float | None = None


@dataclasses.dataclass(frozen=True)
class OneOf:
    """The values a field allows, when they are a registry's names that ``Literal`` cannot spell."""
    values: Collection


@dataclasses.dataclass(frozen=True)
class Check:
    """A check of one field that its type cannot say: ``function(field, value)`` returns the value to keep or
    raises a ValueError naming ``field``; it runs after the type's own checks. A module-level function, not a
    lambda: a class's annotations are evaluated in the class's namespace, where a lambda finds no module names."""
    function: Callable[[str, Any], Any]


@dataclasses.dataclass(frozen=True)
class Expect:
    """What the field's error says is expected (``a list of endpoints like ...``), for any failure of its type and
    range checks."""
    description: str


#: a name of ``NAME_PATTERN`` (server, user, match, league, entrant)
Name = Annotated[str, Check(check_name)]


def load_dataclass(config_class: type[T], value: Any, section: str, prefix: str = "", base: T | None = None) -> T:
    """The ``config_class`` of the mapping ``value`` (keyed by ``yaml_key``; None: every default), each given value
    checked against its field's annotation, then the instance's ``check()`` (if it has one) for what ties fields
    together. Errors name ``prefix`` + the key; an unknown or missing key names ``section``. A value that already
    is a ``config_class`` is kept as it is; ``base`` gives the defaults instead of the fields' own."""
    if isinstance(value, config_class):
        return value
    fields = dataclasses.fields(config_class)
    given = as_mapping(section, value, [yaml_key(f) for f in fields])
    hints = field_types(config_class)
    values = {}
    for f in fields:
        key = yaml_key(f)
        if key in given:
            values[f.name] = check_value(prefix + key, given[key], hints[f.name])
        elif base is not None:
            values[f.name] = getattr(base, f.name)
        elif f.default is not dataclasses.MISSING:
            values[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            values[f.name] = f.default_factory()
        else:
            raise ValueError(f"{section}: {key!r} is required")
    config = config_class(**values)
    if hasattr(config, "check"):
        config.check()
    return config


def checked_fields(config: Any, prefix: str = "") -> dict[str, Any]:
    """The field values of a dataclass made by its constructor (from Python, not a YAML), each checked against its
    annotation as ``load_dataclass`` checks a YAML's, by field name."""
    hints = field_types(type(config))
    return {f.name: check_value(prefix + yaml_key(f), getattr(config, f.name), hints[f.name])
            for f in dataclasses.fields(config)}


def check_value(field: str, value: Any, annotation: Any) -> Any:
    """``value`` checked (and converted: lists to tuples, ints to floats) as ``annotation`` says; see the module
    docstring. A ValueError names ``field``."""
    kind, marks = annotation, ()
    if typing.get_origin(annotation) is Annotated:
        kind, marks = annotation.__origin__, annotation.__metadata__
    expect = next((m.description for m in marks if isinstance(m, Expect)), None)
    bounds = next((m for m in marks if isinstance(m, Range)), Range())
    try:
        checked = _check_type(field, value, kind, bounds)
    except ValueError as e:
        if expect is None or not str(e).startswith(f"{field}: "):  # an item's own error names the item
            raise
        raise ValueError(f"{field}: expected {expect}, got {value!r}") from None
    for mark in marks:
        if isinstance(mark, OneOf):
            check_choice(field, checked, mark.values)
        elif isinstance(mark, Check):
            checked = mark.function(field, checked)
    return checked


@functools.cache
def field_types(config_class: type) -> dict[str, Any]:
    """The annotations of a config dataclass's fields, ``Annotated`` marks kept, by field name."""
    return typing.get_type_hints(config_class, include_extras=True)


def _check_type(field: str, value: Any, kind: Any, bounds: Range) -> Any:
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if kind is Any:
        return value
    if origin in (typing.Union, types.UnionType):
        return _check_union(field, value, args, bounds)
    if origin is Literal:
        return check_choice(field, value, args)
    if kind is bool:
        return check_bool(field, value)
    if kind is int:
        return check_int(field, value, bounds.minimum, bounds.maximum)
    if kind is float:
        return check_number(field, value, bounds.minimum, bounds.maximum, bounds.above)
    if kind is str:
        if not isinstance(value, str):
            raise ValueError(f"{field}: expected a string, got {value!r}")
        return value
    if origin is tuple or kind is tuple:
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"{field}: expected a list, got {value!r}")
        item = args[0] if args else Any
        return tuple(check_value(f"{field}[{i}]", v, item) for i, v in enumerate(value))
    if origin is dict or kind is dict:
        if not isinstance(value, Mapping):
            raise ValueError(f"{field}: expected a mapping, got {value!r}")
        key_kind, item = args or (Any, Any)
        return {check_value(f"{field} key", k, key_kind): check_value(f"{field}.{k}", v, item)
                for k, v in value.items()}
    if dataclasses.is_dataclass(kind):
        return load_dataclass(kind, value, field, f"{field}.")
    if not isinstance(value, kind):
        raise ValueError(f"{field}: expected {kind.__name__}, got {value!r}")
    return value


def _check_union(field: str, value: Any, members: tuple, bounds: Range) -> Any:
    """``X | None``: None, else an X; a dataclass section that is null or empty is off (None). ``X | Y``: the first
    member the value passes as. Bounds around the union hold for each member."""
    optional = type(None) in members
    members = tuple(m if bounds == Range() else Annotated[m, bounds] for m in members if m is not type(None))
    if optional and (value is None or (len(members) == 1 and dataclasses.is_dataclass(members[0])
                                       and isinstance(value, Mapping) and not value)):
        return None
    if len(members) == 1:
        return check_value(field, value, members[0])
    for member in members:
        try:
            return check_value(field, value, member)
        except ValueError:
            continue
    names = " or ".join(getattr(typing.get_origin(m) or m, "__name__", str(m)) for m in members)
    raise ValueError(f"{field}: expected {names}{' or null' if optional else ''}, got {value!r}")
