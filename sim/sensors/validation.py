"""Range checks for sensor configuration fields, run in ``__post_init__``.

Each check raises ``ValueError`` naming ``Owner.field``, the allowed range and
the offending value, e.g. ``GpsConfig.rate = -1.0 is out of range: allowed
(0, inf) [Hz]``. NaN fails every check.
"""

from __future__ import annotations

import math


def _fail(owner: str, field: str, value: object, allowed: str) -> ValueError:
    return ValueError(f"{owner}.{field} = {value!r} is out of range: allowed {allowed}")


def check_finite(owner: str, field: str, value: float, unit: str = "") -> None:
    """Require a finite value (of either sign)."""
    if not math.isfinite(value):
        raise _fail(owner, field, value, f"(-inf, inf) {unit}".rstrip())


def check_positive(owner: str, field: str, value: float, unit: str = "") -> None:
    """Require a finite value > 0."""
    if not (math.isfinite(value) and value > 0.0):
        raise _fail(owner, field, value, f"(0, inf) {unit}".rstrip())


def check_non_negative(owner: str, field: str, value: float, unit: str = "") -> None:
    """Require a finite value >= 0."""
    if not (math.isfinite(value) and value >= 0.0):
        raise _fail(owner, field, value, f"[0, inf) {unit}".rstrip())


def check_probability(owner: str, field: str, value: float) -> None:
    """Require a probability in [0, 1]."""
    if not (math.isfinite(value) and 0.0 <= value <= 1.0):
        raise _fail(owner, field, value, "[0, 1]")


def check_interval(
    owner: str, field: str, value: float, *, low: float, high: float, unit: str = ""
) -> None:
    """Require low < value <= high (the field-of-view convention (0, 2 pi])."""
    if not (math.isfinite(value) and low < value <= high):
        raise _fail(owner, field, value, f"({low:g}, {high:g}] {unit}".rstrip())


def check_closed(
    owner: str, field: str, value: float, *, low: float, high: float, unit: str = ""
) -> None:
    """Require low <= value <= high."""
    if not (math.isfinite(value) and low <= value <= high):
        raise _fail(owner, field, value, f"[{low:g}, {high:g}] {unit}".rstrip())


def check_choice(owner: str, field: str, value: str, allowed: tuple[str, ...]) -> None:
    """Require one of the listed names."""
    if value not in allowed:
        raise _fail(owner, field, value, f"one of {allowed}")


def check_pair(owner: str, field: str, value: object, unit: str) -> tuple[float, float]:
    """Require two finite numbers, e.g. an (east, north) rate; returns them as a tuple.

    A list (from YAML) is accepted and returned as the tuple a frozen config keeps.
    """
    pair = tuple(value) if isinstance(value, tuple | list) else (value,)
    if len(pair) != 2:
        raise _fail(owner, field, value, f"a pair of finite numbers {unit}".rstrip())
    for i, v in enumerate(pair):
        check_finite(owner, f"{field}[{i}]", v, unit)
    return float(pair[0]), float(pair[1])
