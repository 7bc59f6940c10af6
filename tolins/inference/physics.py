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

from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import CircularSocket
from tolins.geometry.workspace import in_holes
from tolins.paper import A_MAX, CONTROL_DT
from tolins.physics.mujoco import MujocoBackend, MujocoBatch


def physics_attempt(
    workpiece: CircularSocket, goal: object, **push: float
) -> tuple[bool, np.ndarray, np.ndarray]:
    """``(inserted, blocked, bearings)`` of one downward push at ``goal`` ``[x, y, theta]``
    on ``workpiece``: :meth:`AttemptBatch.attempts` of a batch of one (``push``: its
    keywords). ``bearings`` ``(n_pins,)`` (rad) are NaN for the pins not blocked."""
    batch = AttemptBatch(workpiece, slots=1, num_threads=1)
    try:
        return batch.attempts([(workpiece, np.asarray(goal, dtype=float))], **push)[0]
    finally:
        batch.close()


def touch_bearings(backend: MujocoBackend, blocked: np.ndarray) -> np.ndarray:
    """The bearing (rad) of each ``blocked`` pin's touch point seen from its hole's centre;
    NaN for the other pins (``History.bearings``)."""
    return _bearings(backend.pin_touch_points(), backend.spec, blocked)


def _bearings(points: np.ndarray, spec: CircularSocket, blocked: np.ndarray) -> np.ndarray:
    towards = points - spec.hole_centers
    return np.where(blocked, np.arctan2(towards[:, 1], towards[:, 0]), np.nan)


class AttemptBatch:
    """Many workpieces' attempts at once: up to ``slots`` downward pushes (the module
    docstring) in one persistent :class:`~tolins.physics.mujoco.MujocoBatch` (each
    simulation on its own workpiece, each the single env's physics bit for bit), stepped
    on ``num_threads`` threads.

    Args:
        spec: The nominal socket of the workpieces (one family, one model layout).
        slots: Attempts simulated side by side.
        num_threads: Threads of the batch (default: every core).
        pins: Elastic-plastic pins (:class:`~tolins.geometry.delicate.ElasticPins`), or
            ``None``: rigid ones. A slot's part may keep its bends from one attempt to
            the next (:meth:`attempts`' ``keep_part``); :meth:`bend` tells them.
    """

    def __init__(
        self,
        spec: CircularSocket,
        slots: int = 32,
        num_threads: int | None = None,
        pins: ElasticPins | None = None,
    ):
        self.slots = slots
        self.physics = MujocoBatch(spec, slots, CONTROL_DT, num_threads, persistent=True, pins=pins)
        self._bends = np.zeros((slots, spec.n_pins, 2))

    def attempts(
        self,
        jobs: list[tuple[CircularSocket, np.ndarray]],
        *,
        slots: list[int] | None = None,
        keep_part: list[bool] | None = None,
        start_height: float = 0.05,
        success_depth: float = 1.0,
        steps: int = 4,
        touch_force: float = 0.05,
    ) -> list[tuple[bool, np.ndarray, np.ndarray]]:
        """``(inserted, blocked, bearings)`` of each ``(workpiece, goal)``, in order.
        ``slots``: the distinct slot each job runs in (then at most :attr:`slots` jobs);
        ``keep_part`` (with ``slots``): per job, whether its part is the one its slot's last
        attempt left, pins as bent as they are (the same workpiece: the caller's word)."""
        push = (start_height, success_depth, steps, touch_force)
        if slots is not None:
            if len(set(slots)) != len(jobs) or not all(0 <= k < self.slots for k in slots):
                raise ValueError(
                    f"slots={slots!r}; allowed: {len(jobs)} distinct slots in [0, {self.slots})"
                )
            keep = [False] * len(jobs) if keep_part is None else list(keep_part)
            if len(keep) != len(jobs):
                raise ValueError(f"keep_part={keep_part!r}; allowed: one bool per job")
            return self._chunk(jobs, list(slots), keep, *push)
        if keep_part is not None:
            raise ValueError("keep_part needs slots; allowed: keep_part=None without slots")
        results: list[tuple[bool, np.ndarray, np.ndarray]] = []
        for first in range(0, len(jobs), self.slots):
            chunk = jobs[first : first + self.slots]
            results += self._chunk(chunk, list(range(len(chunk))), [False] * len(chunk), *push)
        return results

    def bend(self, slot: int) -> np.ndarray:
        """The permanent tip offset of each pin ``(n_pins, 2)`` (mm) of ``slot``'s part after
        its last attempt (zeros with rigid pins)."""
        return self._bends[slot].copy()

    def _chunk(self, chunk, slots, keep, start_height, success_depth, steps, touch_force):
        physics = self.physics
        for k, (spec, _) in zip(slots, chunk, strict=True):
            physics.set_socket(k, spec)
        poses = [[*np.asarray(goal, dtype=float), start_height] for _, goal in chunk]
        ids = np.array(slots)
        physics.reset(ids, np.array(poses), np.array(keep))
        push = np.array([0.0, 0.0, 0.0, -A_MAX[3]])
        done: dict[int, tuple[bool, np.ndarray, np.ndarray]] = {}
        active = list(range(len(chunk)))
        for _ in range(steps):
            state = physics.step(ids[active], np.tile(push, (len(active), 1)))
            if state.pin_bend is not None:
                self._bends[ids[active]] = state.pin_bend
            for row, k in enumerate(active):
                spec, goal = chunk[k]
                if state.errors[row]:
                    raise RuntimeError(f"physics attempt at {goal!r}: {state.errors[row]}")
                if in_holes(spec, state.pose[row], success_depth):
                    free = np.zeros(spec.n_pins, dtype=bool)
                    done[k] = (True, free, np.full(spec.n_pins, np.nan))
            active = [k for k in active if k not in done]
            if not active:
                break
        if active:
            forces = physics.pin_forces(ids[active])
            for row, k in enumerate(active):
                blocked = forces[row] > touch_force
                points = physics.pin_touch_points(int(ids[k]))
                done[k] = (False, blocked, _bearings(points, chunk[k][0], blocked))
        return [done[k] for k in range(len(chunk))]

    def close(self) -> None:
        self.physics.close()
