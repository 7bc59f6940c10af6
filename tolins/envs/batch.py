"""What a batched simulator of many workpieces offers the vector env, whatever simulates it.

A :class:`BatchPhysics` holds ``num_envs`` simulations of one socket family (the same
model layout; each simulation may have its own workpiece, e.g. a bent-pin draw). The
vector env (:mod:`tolins.envs.vector`) resets and steps any subset of them per call;
every row it gets back means what :class:`~tolins.envs.backend.BackendState` means for
one workpiece, so the task logic (noise, reward, success) is the single env's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from tolins.envs.backend import BackendState
from tolins.geometry.specs import SocketSpec


@dataclass(frozen=True)
class BatchState:
    """The workpieces of the simulations a call touched, one row each, in the call's order.

    Attributes:
        pose: ``(n, 4)`` true poses ``[x, y, theta, z]`` (mm, rad).
        wrench: ``(n, 4)`` ``[Fx, Fy, q_theta, Fz]`` (N, N·mm), as ``BackendState.wrench``.
        peak_force: ``(n,)`` largest summed normal pin force during the step (N).
        errors: ``n`` entries: ``None``, or what went wrong in that simulation (its row
            is then invalid, as ``BackendState.error``).
    """

    pose: np.ndarray
    wrench: np.ndarray
    peak_force: np.ndarray
    errors: tuple[str | None, ...] | None = None

    def row(self, i: int) -> BackendState:
        """Row ``i`` as the single env's :class:`BackendState`."""
        error = None if self.errors is None else self.errors[i]
        return BackendState(self.pose[i], self.wrench[i], float(self.peak_force[i]), error)


class BatchPhysics(Protocol):
    """``num_envs`` simulations of one socket family, reset and stepped by index."""

    num_envs: int

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        """Simulate ``socket`` (a workpiece of the batch's family) in simulation ``index``
        from its next reset on."""

    def reset(self, ids: np.ndarray, poses: np.ndarray) -> BatchState:
        """Place simulation ``ids[k]``'s workpiece at ``poses[k]`` ``[x, y, theta, z]`` at
        rest (``poses``: ``(len(ids), 4)``)."""

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        """Command ``velocities[k]`` ``[ux, uy, utheta, uz]`` to simulation ``ids[k]`` for
        one control period; the other simulations do not move."""

    def close(self) -> None:
        """Release threads, devices and buffers."""
