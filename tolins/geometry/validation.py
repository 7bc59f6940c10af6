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


def is_seed(value: object) -> bool:
    """Whether ``value`` is an integer ≥ 0 (Python's or numpy's), not a bool."""
    return isinstance(value, Integral) and not isinstance(value, (bool, np.bool_)) and value >= 0


def check_seed(field: str, value: object) -> int:
    """Return ``value`` as an int if it is a seed: an integer 0 … :data:`SEED_MAX`."""
    return check_int(field, value, minimum=0, maximum=SEED_MAX)


def check_real(field: str, value: object, allowed: str) -> float:
    """Return ``value`` as a float if it is a finite real number (an int or float; not a bool,
    a string or a complex number); ``allowed`` ends the message."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real):
        raise ValueError(f"{field}={value!r} is not a number; allowed: {allowed}")
    try:
        number = float(value)
    except OverflowError as error:
        raise ValueError(f"{field}={value!r} is too large; allowed: {allowed}") from error
    if not math.isfinite(number):
        raise ValueError(f"{field}={value!r} is not finite; allowed: {allowed}")
    return number


def _holds_bool(value: object) -> bool:
    """Whether ``value`` is a bool or a (nested) list or tuple holding one."""
    if isinstance(value, (bool, np.bool_)):
        return True
    if isinstance(value, (list, tuple)):
        return any(_holds_bool(item) for item in value)
    return isinstance(value, np.ndarray) and value.dtype.kind == "b"


def real_array(field: str, value: object, allowed: str) -> np.ndarray:
    """``value`` as a new float array if it holds real numbers only: ints and floats (Python or
    numpy), not bools, strings, complex numbers or other objects (``ValueError`` naming
    ``field``). A bool is refused, not read as 0 or 1: in a pose, a goal, a velocity or a
    noise std it is a mistake, not a number."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{field}={value!r} is not numeric; allowed: {allowed}") from error
    if raw.dtype.kind == "O":
        real = all(
            isinstance(item, Real) and not isinstance(item, (bool, np.bool_)) for item in raw.flat
        )
    else:
        real = raw.dtype.kind in "iuf" and not _holds_bool(value)
    if not real:
        raise ValueError(
            f"{field}={value!r} is not real numbers (bools, strings and complex numbers are "
            f"not); allowed: {allowed}"
        )
    try:
        return raw.astype(float)
    except (TypeError, ValueError, OverflowError) as error:
        raise ValueError(f"{field}={value!r} is not numeric; allowed: {allowed}") from error


def check_positive(field: str, value: object, unit: str = "mm") -> float:
    """Return ``value`` as a float if it is finite and > 0."""
    value = check_real(field, value, f"a finite number > 0 {unit}")
    if value <= 0.0:
        raise ValueError(f"{field}={value!r} is not allowed; allowed: a finite number > 0 {unit}")
    return value


def finite_vector(field: str, value: object, size: int, allowed: str) -> np.ndarray:
    """``value`` as a float array of ``size`` finite entries (a scalar is broadcast)."""
    array = real_array(field, value, allowed)
    try:
        array = np.broadcast_to(array, (size,)).copy()
    except ValueError as error:
        raise ValueError(
            f"{field}={value!r} has a wrong shape or type; allowed: {allowed}"
        ) from error
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{field}={value!r} contains NaN or inf; allowed: {allowed}")
    return array


def checked_array(field: str, value: object, shape: tuple[int, ...], allowed: str) -> np.ndarray:
    """``value`` as a float array of exactly ``shape`` with finite entries."""
    array = real_array(field, value, allowed)
    if array.shape != shape:
        raise ValueError(f"{field} has shape {array.shape}; allowed: {shape} = {allowed}")
    if not np.isfinite(array).all():
        raise ValueError(f"{field}={array.tolist()!r} contains NaN or inf; allowed: {allowed}")
    return array
