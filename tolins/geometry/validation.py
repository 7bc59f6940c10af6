"""Small checks that raise ``ValueError`` naming the field, the value and what is allowed."""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np


def check_int(field: str, value: object, *, minimum: int, maximum: int | None = None) -> int:
    """Return ``value`` as an int if it is an integer in ``[minimum, maximum]``."""
    allowed = (
        f"an integer ≥ {minimum}" if maximum is None else f"{minimum} ≤ an integer ≤ {maximum}"
    )
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise ValueError(f"{field}={value!r} is not an integer; allowed: {allowed}")
    if value < minimum:
        raise ValueError(f"{field}={value!r} is too small; allowed: {allowed}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{field}={value!r} is too large; allowed: {allowed}")
    return int(value)


#: The seeds every seeded library here accepts (numpy's legacy ``np.random.seed`` range).
SEED_MAX = 2**32 - 1


def check_seed(field: str, value: object) -> int:
    """Return ``value`` as an int if it is a seed: an integer 0 … :data:`SEED_MAX`."""
    return check_int(field, value, minimum=0, maximum=SEED_MAX)


def check_positive(field: str, value: object, unit: str = "mm") -> float:
    """Return ``value`` as a float if it is finite and > 0."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ValueError(f"{field}={value!r} is not a number; allowed: a finite number > 0 {unit}")
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{field}={value!r} is not allowed; allowed: a finite number > 0 {unit}")
    return value


def finite_vector(field: str, value: object, size: int, allowed: str) -> np.ndarray:
    """``value`` as a float array of ``size`` finite entries (a scalar is broadcast)."""
    try:
        array = np.broadcast_to(np.asarray(value, dtype=float), (size,)).copy()
    except (TypeError, ValueError) as error:
        raise ValueError(
            f"{field}={value!r} has a wrong shape or type; allowed: {allowed}"
        ) from error
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{field}={value!r} contains NaN or inf; allowed: {allowed}")
    return array


def checked_array(field: str, value: object, shape: tuple[int, ...], allowed: str) -> np.ndarray:
    """``value`` as a float array of exactly ``shape`` with finite entries."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{field}={value!r} is not numeric; allowed: {allowed}") from error
    if array.shape != shape:
        raise ValueError(f"{field} has shape {array.shape}; allowed: {shape} = {allowed}")
    if not np.isfinite(array).all():
        raise ValueError(f"{field}={array.tolist()!r} contains NaN or inf; allowed: {allowed}")
    return array
