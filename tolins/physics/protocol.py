"""What a simulator offers the envs, whatever simulates it: one workpiece or a batch of them.

A :class:`Backend` simulates one workpiece over one board (the single env's); a
:class:`BatchPhysics` holds ``num_envs`` simulations of one socket family (the same model
layout; each simulation may have its own workpiece, e.g. a bent-pin draw) and resets and
steps any subset of them per call (the vector env's). Every row a batch gives back means
what a :class:`BackendState` means for one workpiece, so the task logic (noise, reward,
success) is the same over both.

Each simulator class declares what it can do as class attributes (:class:`Capabilities`),
so the envs ask the class, never its name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from tolins.geometry.specs import SocketSpec

if TYPE_CHECKING:
    from tolins.physics.randomization import PhysicsDraw


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
        sensed_pose: What the robot's own sensing says the pose is (a robot's forward
            kinematics and nominal grasp), or ``None``: the true ``pose``.
        sensed_wrench: What its wrist sensor says ``wrench`` is, or ``None``: the true one.
        pin_bend: Each pin's permanent tip offset ``(n_pins, 2)`` (mm, workpiece frame) with
            elastic-plastic pins, or ``None`` (rigid pins).
        pin_deflection: Each pin's tip offset now, elastic included ``(n_pins, 2)`` (mm,
            workpiece frame), or ``None``.
    """

    pose: np.ndarray
    wrench: np.ndarray
    peak_force: float
    error: str | None = None
    sensed_pose: np.ndarray | None = None
    sensed_wrench: np.ndarray | None = None
    pin_bend: np.ndarray | None = None
    pin_deflection: np.ndarray | None = None

    @property
    def observed_pose(self) -> np.ndarray:
        """The pose the observation measures: the sensed one where a robot senses it."""
        return self.pose if self.sensed_pose is None else self.sensed_pose

    @property
    def observed_wrench(self) -> np.ndarray:
        """The wrench the observation measures: the sensed one where a robot senses it."""
        return self.wrench if self.sensed_wrench is None else self.sensed_wrench


@dataclass(frozen=True)
class BatchState:
    """The workpieces of the simulations a call touched, one row each, in the call's order.

    Attributes:
        pose: ``(n, 4)`` true poses ``[x, y, theta, z]`` (mm, rad).
        wrench: ``(n, 4)`` ``[Fx, Fy, q_theta, Fz]`` (N, N·mm), as ``BackendState.wrench``.
        peak_force: ``(n,)`` largest summed normal pin force during the step (N).
        errors: ``n`` entries: ``None``, or what went wrong in that simulation (its row
            is then invalid, as ``BackendState.error``).
        sensed_pose: ``(n, 4)``, as ``BackendState.sensed_pose``, or ``None``.
        sensed_wrench: ``(n, 4)``, as ``BackendState.sensed_wrench``, or ``None``.
        pin_bend: ``(n, n_pins, 2)``, as ``BackendState.pin_bend``, or ``None``.
        pin_deflection: ``(n, n_pins, 2)``, as ``BackendState.pin_deflection``, or ``None``.
    """

    pose: np.ndarray
    wrench: np.ndarray
    peak_force: np.ndarray
    errors: tuple[str | None, ...] | None = None
    sensed_pose: np.ndarray | None = None
    sensed_wrench: np.ndarray | None = None
    pin_bend: np.ndarray | None = None
    pin_deflection: np.ndarray | None = None

    def row(self, i: int) -> BackendState:
        """Row ``i`` as the single env's :class:`BackendState`."""
        error = None if self.errors is None else self.errors[i]
        rows = (self.sensed_pose, self.sensed_wrench, self.pin_bend, self.pin_deflection)
        extra = (None if a is None else a[i] for a in rows)
        return BackendState(self.pose[i], self.wrench[i], float(self.peak_force[i]), error, *extra)


class Capabilities:
    """What a simulator class can do, as class attributes (every simulator sets each).

    Attributes:
        supports_render: Its simulations can be drawn: the model and a posed data of one
            (``model``/``data`` of a backend, ``drawing(index)`` of a batch).
        supports_randomization: It takes randomised-physics draws (``set_physics``; a
            simulator without friction, stiffness or servos ignores their terms).
        supports_touch_points: It reports each pin's contact force and touch point
            (``pin_forces``, ``pin_touch_points``).
        defect_kinds: The defect kinds (:data:`~tolins.geometry.defects.DEFECT_KINDS`) a
            simulation takes as its workpiece (``set_socket``; a single backend swaps its
            whole model and data, so every kind).
        batch_options: The keywords of the vector env it takes besides the socket, the
            number of simulations and the control period (``num_threads``, ``device``,
            ``persistent``).
        supports_elastic_pins: It simulates ``pins="elastic-plastic"`` (pins that bend and
            stay bent, :mod:`tolins.physics.plasticity`); ``False`` unless a class says so.
    """

    supports_render: ClassVar[bool]
    supports_randomization: ClassVar[bool]
    supports_touch_points: ClassVar[bool]
    defect_kinds: ClassVar[frozenset[str]]
    batch_options: ClassVar[frozenset[str]] = frozenset()
    supports_elastic_pins: ClassVar[bool] = False


class Backend(Protocol):
    """A simulator of one workpiece over one board."""

    spec: SocketSpec

    def set_socket(self, socket: SocketSpec) -> None:
        """Simulate ``socket`` (``spec`` from now on) from the next reset on."""

    def set_physics(self, draw: PhysicsDraw | None) -> None:
        """Apply a randomised-physics ``draw`` (``None``: nominal) before the next reset."""

    def reset(self, pose: np.ndarray, keep_part: bool = False) -> BackendState:
        """Place the workpiece at ``pose`` ``[x, y, theta, z]`` at rest; with ``keep_part``
        its pins as bent as they are (only a class that ``supports_elastic_pins`` is given
        ``True``: the settings refuse it elsewhere)."""

    def step(self, velocity: np.ndarray) -> BackendState:
        """Command ``velocity`` ``[ux, uy, utheta, uz]`` for one control period."""


class BatchPhysics(Protocol):
    """``num_envs`` simulations of one socket family, reset and stepped by index."""

    num_envs: int

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        """Simulate ``socket`` (a workpiece of the batch's family) in simulation ``index``
        from its next reset on."""

    def reset(
        self, ids: np.ndarray, poses: np.ndarray, keep_part: np.ndarray | None = None
    ) -> BatchState:
        """Place simulation ``ids[k]``'s workpiece at ``poses[k]`` ``[x, y, theta, z]`` at
        rest (``poses``: ``(len(ids), 4)``); ``keep_part[k]``: its pins as bent as they are
        (as :meth:`Backend.reset`; ``None``: none kept)."""

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        """Command ``velocities[k]`` ``[ux, uy, utheta, uz]`` to simulation ``ids[k]`` for
        one control period; the other simulations do not move."""

    def close(self) -> None:
        """Release threads, devices and buffers."""
