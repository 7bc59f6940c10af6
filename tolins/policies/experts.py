"""The paper's two scripted experts. Both act on the (noisy) observation only.

Observation ``[x̂−x*, ŷ−y*, θ̂−θ*, ẑ, F̂x, F̂y, q̂θ, F̂z]``; action ``[ux, uy, utheta, uz]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tolins.paper import A_MAX, CONTROL_DT


def _default_a_max() -> np.ndarray:
    return A_MAX.copy()


@dataclass
class SafeExpert:
    """Align x, y and theta first, then descend: the paper's L-shaped path.

    While any measured error exceeds ``align_tolerance`` (``[mm, mm, rad]``) and the
    pins are above the board, it moves horizontally only, cancelling the error in one
    step where the speed limit allows. Once aligned (or inside the board) it descends
    at full speed while still correcting the horizontal error.
    """

    align_tolerance: np.ndarray = field(default_factory=lambda: np.array([0.3, 0.3, 0.01]))
    a_max: np.ndarray = field(default_factory=_default_a_max)
    dt: float = CONTROL_DT
    name: str = "safe"

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        error = np.asarray(observation[:3], dtype=float)
        horizontal = np.clip(-error / self.dt, -self.a_max[:3], self.a_max[:3])
        aligned = bool(np.all(np.abs(error) <= self.align_tolerance))
        descend = aligned or observation[3] < 0.0
        return np.append(horizontal, -self.a_max[3] if descend else 0.0)


@dataclass
class EfficientExpert:
    """Full speed straight toward the inserted pose ``[x*, y*, θ*, -depth]``.

    All four axes arrive together: the slowest axis moves at its limit and the others
    scale down, so the path is a straight line (which meets the board early when the
    workpiece starts off to the side).
    """

    depth: float = 2.0
    a_max: np.ndarray = field(default_factory=_default_a_max)
    dt: float = CONTROL_DT
    name: str = "efficient"

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        error = np.append(np.asarray(observation[:3], dtype=float), observation[3] + self.depth)
        time_to_go = max(float(np.max(np.abs(error) / self.a_max)), self.dt)
        return -error / time_to_go


EXPERTS = {"safe": SafeExpert, "efficient": EfficientExpert}
