"""The action of the insertion task: a velocity ``[ux, uy, utheta, uz]`` within ``±a_max``."""

from __future__ import annotations

from typing import Any

import numpy as np

from tolins.geometry.validation import real_array
from tolins.paper import A_MAX

_A_MIN = -A_MAX


def check_action(action: Any) -> np.ndarray:
    """``action`` ``[ux, uy, utheta, uz]`` as floats clipped to ±a_max; NaN, inf, a wrong
    shape or anything but real numbers (ints and floats; a bool, string or complex number is
    not a velocity) raise ``ValueError``."""
    action = real_array("action", action, "4 real numbers [ux, uy, utheta, uz]")
    if action.shape != (4,):
        raise ValueError(f"action has shape {action.shape}; allowed: (4,) = [ux, uy, utheta, uz]")
    if not np.isfinite(action).all():
        raise ValueError(f"action={action.tolist()!r} contains NaN or inf; allowed: finite values")
    return np.minimum(np.maximum(action, _A_MIN), A_MAX)
