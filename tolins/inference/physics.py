"""Contact evidence from the physics: which pins the board blocked on an attempt, and where.

An attempt places the workpiece ``start_height`` mm over the board at the goal and pushes
straight down. It inserted when every pin ends ``success_depth`` deep in its own hole
(:func:`~tolins.geometry.workspace.in_holes`, the envs' success);
otherwise pin ``i`` was blocked when its touch sensor (``MujocoBackend.pin_forces()``)
reads more than ``touch_force`` N, and its bearing is the angle of its touch point
(``MujocoBackend.pin_touch_points()``) seen from its hole's centre. These are the evidence
``History.blocked`` and ``History.bearings`` of the contact likelihoods, measured instead
of computed from the geometry.
"""

from __future__ import annotations

import numpy as np

from tolins.envs.mujoco_backend import MujocoBackend
from tolins.geometry.specs import CircularSocket
from tolins.geometry.workspace import in_holes
from tolins.paper import A_MAX, CONTROL_DT


def physics_attempt(
    backend: MujocoBackend,
    goal: object,
    *,
    start_height: float = 0.05,
    success_depth: float = 1.0,
    steps: int = 4,
    touch_force: float = 0.05,
) -> tuple[bool, np.ndarray, np.ndarray]:
    """``(inserted, blocked, bearings)`` of one downward push at ``goal`` ``[x, y, theta]``.

    ``bearings`` ``(n_pins,)`` (rad) are NaN for the pins not blocked.
    """
    x, y, theta = np.asarray(goal, dtype=float)
    backend.reset(np.array([x, y, theta, start_height]))
    push = np.array([0.0, 0.0, 0.0, -A_MAX[3]])
    for _ in range(steps):
        state = backend.step(push)
        if state.error:
            raise RuntimeError(f"physics attempt at {goal!r}: {state.error}")
        if in_holes(backend.spec, state.pose, success_depth):
            free = np.zeros(backend.spec.n_pins, dtype=bool)
            return True, free, np.full(backend.spec.n_pins, np.nan)
    blocked = backend.pin_forces() > touch_force
    return False, blocked, touch_bearings(backend, blocked)


def touch_bearings(backend: MujocoBackend, blocked: np.ndarray) -> np.ndarray:
    """The bearing (rad) of each ``blocked`` pin's touch point seen from its hole's centre;
    NaN for the other pins (``History.bearings``)."""
    towards = backend.pin_touch_points() - backend.spec.hole_centers
    return np.where(blocked, np.arctan2(towards[:, 1], towards[:, 0]), np.nan)


def make_backend(spec: CircularSocket) -> MujocoBackend:
    """A MuJoCo backend of the (bent) workpiece at the paper's control period."""
    return MujocoBackend(spec, CONTROL_DT)
