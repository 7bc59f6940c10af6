"""What an insertion backend returns, whatever simulates it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class BackendState:
    """The workpiece after a reset or a control step.

    Attributes:
        pose: True pose ``[x, y, theta, z]`` (mm, rad).
        wrench: Force and torque the board exerts on the workpiece at the end of the
            step, world axes, about the workpiece origin: ``[Fx, Fy, q_theta, Fz]`` (N, N·mm).
        peak_force: Largest summed normal force (N) of the contacts between the board
            and the pins seen during the step.
        error: ``None``, or what went wrong in the simulator (the state is then invalid).
    """

    pose: np.ndarray
    wrench: np.ndarray
    peak_force: float
    error: str | None = None


class Backend(Protocol):
    """A simulator of one workpiece over one board."""

    def reset(self, pose: np.ndarray) -> BackendState:
        """Place the workpiece at ``pose`` ``[x, y, theta, z]`` at rest."""

    def step(self, velocity: np.ndarray) -> BackendState:
        """Command ``velocity`` ``[ux, uy, utheta, uz]`` for one control period."""
