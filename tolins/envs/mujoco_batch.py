"""Contact physics of many workpieces at once: ``mujoco.batch`` on a native thread pool.

:class:`MujocoBatch` is the :class:`~tolins.envs.batch.BatchPhysics` of the vector env on
MuJoCo. It runs :class:`~tolins.envs.mujoco_backend.ServoStepper`'s control step (servo
set-points re-anchored, ``contact_checks`` chunks of physics steps, the summed pin force
read after each) on every simulation of a call in one ``Batch.step`` per chunk, with the
GIL released. ``mujoco.batch`` is bit-identical to a loop of ``mj_step`` over one
``MjData`` per simulation at any thread count (its documentation; tested here against
the single env), so each simulation is the single env's, bit for bit.

A simulation's workpiece may differ from the others' (a bent-pin draw): it then runs on a
model compiled from its own MJCF (``Batch.set_models``), the model the single env would
compile for it. All models of a socket family share one layout.
"""

from __future__ import annotations

import copy
import os
from numbers import Integral

import mujoco
import mujoco.batch
import numpy as np

from tolins.envs.batch import BatchState
from tolins.envs.mujoco_backend import (
    _FORCE_SCALE,
    _SWAP_Z_THETA,
    ServoStepper,
    _touch_sensors,
    board_wrench,
    contact_chunks,
    control_plan,
    pin_geom_ids,
    pin_touch_points,
    sensors_off,
    simulation_fault,
)
from tolins.envs.randomization import PhysicsDraw, apply_draw, nominal_fields
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int
from tolins.mjcf import make_mjcf


def default_threads() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def max_threads() -> int:
    """The most threads a batch may run: the machine's cores."""
    return os.cpu_count() or default_threads()


def check_threads(num_threads: object) -> int:
    """``num_threads`` as an int if it is 1 … :func:`max_threads` (more threads than cores
    only contend for them)."""
    most = max_threads()
    allowed = f"1 ≤ num_threads ≤ {most} (this machine's cores), or None for {default_threads()}"
    if isinstance(num_threads, bool) or not isinstance(num_threads, Integral):
        raise ValueError(f"num_threads={num_threads!r} is not an integer; allowed: {allowed}")
    if not 1 <= num_threads <= most:
        raise ValueError(f"num_threads={num_threads!r} is out of range; allowed: {allowed}")
    return int(num_threads)


def _sequential_sum(columns: np.ndarray) -> np.ndarray:
    """Row sums of ``columns`` ``(n, k)`` added left to right, as Python's ``sum`` of a row
    (numpy's pairwise sum rounds differently from 8 columns on)."""
    total = np.zeros(len(columns))
    for j in range(columns.shape[1]):
        total += columns[:, j]
    return total


class MujocoBatch:
    """``num_envs`` MuJoCo simulations of one socket family (see the module docstring).

    Args:
        socket: The nominal socket; every simulation starts with it.
        num_envs: Number of simulations.
        control_dt: Control period (s), as the single env's.
        num_threads: Threads of the batch (including the caller's), at most the machine's
            cores (:func:`max_threads`); default: the cores this process may run on.
        contact_checks: Contact-force reads per control step; default as the single env.
        persistent: One ``MjData`` per simulation (``mujoco.batch``'s ``persistent``), so
            that :meth:`pin_touch_points` can read a simulation's contacts and
            :meth:`drawing` its whole data.
    """

    def __init__(
        self,
        socket: SocketSpec,
        num_envs: int,
        control_dt: float,
        num_threads: int | None = None,
        contact_checks: int | None = None,
        persistent: bool = False,
    ) -> None:
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        threads = default_threads() if num_threads is None else num_threads
        self.num_threads = check_threads(threads)
        self.socket = socket
        self.model = mujoco.MjModel.from_xml_string(make_mjcf(socket))
        self.substeps, self.checks = control_plan(self.model, control_dt, contact_checks)
        self.batch = mujoco.batch.Batch(
            self.model, self.num_envs, nthread=self.num_threads, persistent=persistent
        )
        # Caller models throughout (the batch reads them live): a bent-pin draw replaces its
        # simulation's, and the sensors are switched off on each for the steps before a read.
        self._models = [self.model] * self.num_envs
        self.batch.set_models(self._models)
        self._sockets: list[SocketSpec] = [socket] * self.num_envs
        self._compiled: dict[int, tuple[SocketSpec, mujoco.MjModel]] = {}
        self._models_changed = False
        b = self.batch
        self._qpos, self._qvel = b.bind("qpos"), b.bind("qvel")
        self._act, self._ctrl = b.bind("act"), b.bind("ctrl")
        self._sensordata = b.bind("sensordata")
        touch, n_pins = _touch_sensors(self.model)
        self._touch = slice(touch, touch + n_pins)
        force = self.model.sensor("force").adr[0]
        self._force = slice(force, force + 3)
        self._torque_z = self.model.sensor("torque").adr[0] + 2
        self._pin_geoms = pin_geom_ids(self.model)
        self._drawing: mujoco.MjData | None = None

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        if socket is self._sockets[index]:
            return
        self._sockets[index] = socket
        self._models[index] = self._compile(socket)
        self._models_changed = True

    def set_physics(self, index: int, draw: PhysicsDraw | None) -> None:
        """Run simulation ``index`` on its workpiece's model with a randomised-physics
        ``draw`` applied (a copy of its own; ``None``: the workpiece's model)."""
        base = self._compile(self._sockets[index])
        if draw is None or not draw.changes_model:
            self._models[index] = base
        else:
            model = copy.copy(base)
            apply_draw(model, nominal_fields(base), draw)
            self._models[index] = model
        self._models_changed = True

    def _compile(self, socket: SocketSpec) -> mujoco.MjModel:
        """The model of ``socket``: the batch's own, or one compiled from its MJCF (the last
        ``2 num_envs`` kept, by identity of the spec, for workpieces that come back)."""
        if socket is self.socket:
            return self.model
        key = id(socket)
        if key in self._compiled and self._compiled[key][0] is socket:
            return self._compiled[key][1]
        model = mujoco.MjModel.from_xml_string(make_mjcf(socket))
        if len(self._compiled) >= 2 * self.num_envs:
            self._compiled.pop(next(iter(self._compiled)))
        self._compiled[key] = (socket, model)
        return model

    def _sync_models(self) -> None:
        if self._models_changed:
            self.batch.set_models(self._models)
            self._models_changed = False

    def reset(self, ids: np.ndarray, poses: np.ndarray) -> BatchState:
        ids = np.asarray(ids, dtype=np.intp)
        self._sync_models()
        self.batch.reset(ids, stage=mujoco.mjtStage.mjSTAGE_NONE)
        self._qpos[ids] = np.asarray(poses, dtype=float)[:, _SWAP_Z_THETA]
        self._act[ids] = self._qpos[ids]
        self.batch.forward(ids)
        force = _sequential_sum(self._sensordata[ids, self._touch]) * _FORCE_SCALE
        return self._state(ids, force, None)

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        ids = np.asarray(ids, dtype=np.intp)
        self._sync_models()
        warning = self.batch.warning
        before = [sum(warning[i, :, 1].tolist()) for i in ids.tolist()]
        self._ctrl[ids] = np.asarray(velocities, dtype=float)[:, _SWAP_Z_THETA]
        self._act[ids] = self._qpos[ids]
        peak = np.zeros(len(ids))
        for n in contact_chunks(self.substeps, self.checks):
            self._physics_steps(ids, n)
            touch = _sequential_sum(self._sensordata[ids, self._touch])
            peak = np.where(touch > peak, touch, peak)  # max(peak, touch), as Python's
        errors = tuple(
            simulation_fault(b, warning[i, :, 1].tolist(), self._qpos[i], self._qvel[i])
            for b, i in zip(before, ids.tolist(), strict=True)
        )
        return self._state(ids, peak * _FORCE_SCALE, errors)

    def _physics_steps(self, ids: np.ndarray, n: int) -> None:
        """``n`` physics steps of simulations ``ids``, the sensors computed only in the last
        (as :class:`~tolins.envs.mujoco_backend.ServoStepper` with ``lazy_sensors``; the
        sensor data read after it are the same bit for bit)."""
        if ServoStepper.lazy_sensors and n > 1:
            models = {id(self._models[i]): self._models[i] for i in ids.tolist()}.values()
            with sensors_off(models):
                self.batch.step(ids, nstep=n - 1)
            n = 1
        self.batch.step(ids, nstep=n)

    def _state(
        self, ids: np.ndarray, peak_force: np.ndarray, errors: tuple[str | None, ...] | None
    ) -> BatchState:
        qpos, sensordata = self._qpos[ids], self._sensordata[ids]
        wrench = np.array(
            [
                board_wrench(q[3], s[self._force].tolist(), s[self._torque_z])
                for q, s in zip(qpos, sensordata, strict=True)
            ]
        ).reshape(len(ids), 4)
        return BatchState(qpos[:, _SWAP_Z_THETA], wrench, peak_force, errors)

    def pin_forces(self, ids: np.ndarray) -> np.ndarray:
        """Summed normal contact force on each pin (N) of simulations ``ids``, ``(n, pins)``,
        as ``ServoStepper.pin_forces`` after the last step."""
        return self._sensordata[np.asarray(ids, dtype=np.intp), self._touch] * _FORCE_SCALE

    def pin_touch_points(self, index: int) -> np.ndarray:
        """Where each pin of simulation ``index`` presses on the board after its last step,
        as ``ServoStepper.pin_touch_points`` (a persistent batch only)."""
        if not self.batch.persistent:
            raise RuntimeError("pin_touch_points needs MujocoBatch(..., persistent=True)")
        data = self.batch.get_data(index)
        return pin_touch_points(self._models[index], data, self._pin_geoms)

    def simulation(self, index: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Simulation ``index``'s model and a data at its state (forward kinematics run),
        for rendering or inspection."""
        model = self._models[index]
        data = self.batch.get_data(index)
        mujoco.mj_forward(model, data)
        return model, data

    def drawing(self, index: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Simulation ``index``'s model and its whole data as its last call left it (a
        persistent batch only): what the single env's ``MujocoBackend`` holds after the same
        calls, for drawing. The data is shared: draw it before asking for the next."""
        if not self.batch.persistent:
            raise RuntimeError("drawing needs MujocoBatch(..., persistent=True)")
        if self._drawing is None:
            self._drawing = mujoco.MjData(self.model)
        return self._models[index], self.batch.get_data(index, self._drawing)

    def close(self) -> None:
        """Release the simulations: the batch (its threads end with it), the arrays bound to
        it and the compiled models. The batch is not used afterwards."""
        self.batch = None
        self._qpos = self._qvel = self._act = self._ctrl = self._sensordata = None
        self._models, self._compiled, self._drawing = [], {}, None
