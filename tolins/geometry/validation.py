"""Small checks that raise ``ValueError`` naming the field, the value and what is allowed."""

from __future__ import annotations

import math
from numbers import Integral, Real


def check_int(field: str, value: object, *, minimum: int) -> int:
    """Return ``value`` as an int if it is an integer ≥ ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise ValueError(f"{field}={value!r} is not an integer; allowed: an integer ≥ {minimum}")
    if value < minimum:
        raise ValueError(f"{field}={value!r} is too small; allowed: an integer ≥ {minimum}")
    return int(value)


def check_positive(field: str, value: object, unit: str = "mm") -> float:
    """Return ``value`` as a float if it is finite and > 0."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"{field}={value!r} is not a number; allowed: a finite number > 0 {unit}")
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{field}={value!r} is not allowed; allowed: a finite number > 0 {unit}")
    return value
