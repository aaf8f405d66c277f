"""The checks every config of the package shares (env and minigame YAMLs, training, self-play, leagues, server
and client settings): each failure is a ValueError that names the field and says what is allowed, so a bad
value in any YAML reads the same way. Imports nothing of the package; everything may use it.
"""
from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Collection, Mapping
from typing import Any

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


def section_values(section: str, value: Any, config_class: type) -> dict[str, Any]:
    """The values of the dataclass ``config_class``'s fields (by field name) from the mapping ``value`` (keyed by
    ``yaml_key``), defaults filled in. A non-mapping or an unknown key is a ValueError naming ``section`` and the
    allowed keys; so is a missing key whose field has no default."""
    fields = dataclasses.fields(config_class)
    given = as_mapping(section, value, [yaml_key(f) for f in fields])
    out = {}
    for f in fields:
        key = yaml_key(f)
        if key in given:
            out[f.name] = given[key]
        elif f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
        else:
            raise ValueError(f"{section}: {key!r} is required")
    return out


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
