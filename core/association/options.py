"""Validation of method options: every error names the method and the option."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from core.errors import OptionError

Options = Mapping[str, object]


def check_keys(method: str, options: Options, allowed: Sequence[str]) -> None:
    """Reject option names the method does not know."""
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise OptionError(
            f"{method}: unknown option(s) {unknown}; allowed options are {sorted(allowed)}"
        )


def number(
    method: str,
    options: Options,
    name: str,
    default: float | None,
    *,
    low: float,
    high: float = math.inf,
    low_open: bool = True,
    high_open: bool = False,
) -> float | None:
    """A real option in the interval (low, high] (ends open or closed as told)."""
    value = options.get(name, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise OptionError(f"{method}: option {name!r} must be a number, got {value!r}")
    value = float(value)
    below = value <= low if low_open else value < low
    above = value >= high if high_open else value > high
    if math.isnan(value) or below or above:
        left = "(" if low_open else "["
        right = ")" if high_open else "]"
        raise OptionError(
            f"{method}: option {name!r} must lie in {left}{low:g}, {high:g}{right}, got {value!r}"
        )
    return value


def choice(method: str, options: Options, name: str, default: str, choices: Sequence[str]) -> str:
    """A string option among ``choices``."""
    value = options.get(name, default)
    if value not in choices:
        raise OptionError(
            f"{method}: option {name!r} must be one of {list(choices)}, got {value!r}"
        )
    return str(value)


def exclusive(method: str, options: Options, names: Sequence[str]) -> None:
    """At most one of ``names`` may be given."""
    given = [name for name in names if options.get(name) is not None]
    if len(given) > 1:
        raise OptionError(f"{method}: give at most one of the options {given}, not both")
