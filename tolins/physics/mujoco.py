"""MuJoCo contact physics: the single env's backend and the vector env's batch.

:class:`MujocoBackend` is one compiled socket model and its
:class:`~tolins.physics.servo.ServoStepper`. :class:`MujocoBatch` runs the same control step
(servo set-points re-anchored, ``contact_checks`` chunks of physics steps, the summed pin
force read after each) on every simulation of a call in one ``mujoco.batch`` ``Batch.step``
per chunk, with the GIL released, on a native thread pool. ``mujoco.batch`` is
bit-identical to a loop of ``mj_step`` over one ``MjData`` per simulation at any thread
count (its documentation; tested against the single env), so each simulation is the single
env's, bit for bit. Both step through one control step,
:func:`~tolins.physics.servo.servo_control_step` (:class:`~tolins.physics.servo.BatchServo`
for the batch).

A simulation's workpiece may differ from the others' (a bent-pin draw): it then runs on a
model compiled from its own MJCF (``Batch.set_models``), the model the single env would
compile for it. All models of a socket family share one layout (:func:`tolins.mjcf.model_layout`).
Both classes take a new workpiece by ``set_socket`` and compile through one cache
(:class:`~tolins.physics.compiled.SocketCache`).
"""

from __future__ import annotations

import copy
import os
from numbers import Integral

import mujoco
import numpy as np

from tolins.geometry.defects import DEFECT_KINDS
from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int
from tolins.mjcf import FORCE_SCALE
from tolins.physics.compiled import SocketCache, model_builder, simulation_model
from tolins.physics.protocol import BackendState, BatchState, Capabilities
from tolins.physics.randomization import PhysicsDraw, apply_draw, nominal_fields
from tolins.physics.schedule import control_plan
from tolins.physics.servo import BatchServo, ServoStepper, pin_touch_points
from tolins.physics.versions import PhysicsVersion
from tolins.physics.versions import physics_version as physics_version_of


class MujocoBackend(Capabilities):
    """The gymnasium env's contact physics: a compiled socket model and its :class:`ServoStepper`.

    ``model`` and ``data`` are the simulation itself (drawn by ``InsertionEnv.render``);
    :meth:`set_socket` replaces both, so read them from the backend each time.

    Args:
        spec: The socket.
        control_dt: Control period (s), any that
            :func:`~tolins.physics.schedule.check_control_dt` allows.
        contact_checks: How many times per control step the contact force is read, for
            ``peak_force`` (chunks as in :class:`ServoStepper`), 1 … the physics steps;
            default :func:`~tolins.physics.schedule.default_contact_checks` of the physics
            steps.
        physics_version: 1 or 2, or that :class:`~tolins.physics.versions.PhysicsVersion`
            (:mod:`tolins.physics.versions`).
        pins: Elastic-plastic pins (``pins="elastic-plastic"``), or ``None``: rigid pins.
    """

    supports_render = True
    supports_randomization = True
    supports_touch_points = True
    supports_elastic_pins = True
    defect_kinds = frozenset(DEFECT_KINDS)

    def __init__(
        self,
        spec: SocketSpec,
        control_dt: float,
        contact_checks: int | None = None,
        physics_version: int | PhysicsVersion = 1,
        pins: ElasticPins | None = None,
    ) -> None:
        self.control_dt = control_dt
        self.version = physics_version_of(physics_version)
        self._contact_checks = contact_checks  # as asked: None for the default
        # The nominal model and the workpiece's now; a model is left here at its nominal
        # physics, so a workpiece that comes back starts from its compiled values.
        self._compiled = SocketCache(model_builder(self.version, pins), spec, size=1)
        self._load(spec)

    def _load(self, spec: SocketSpec) -> None:
        """Simulate ``spec``: its compiled model, a new data and a stepper of the two."""
        self.spec = spec
        self.model = self._compiled.get(spec)
        self.data = mujoco.MjData(self.model)
        self.substeps, checks = control_plan(self.model, self.control_dt, self._contact_checks)
        self.stepper = ServoStepper(self.model, self.data, checks, self.version.free_flight)
        self._nominal: dict[str, np.ndarray] | None = None

    def set_socket(self, socket: SocketSpec) -> None:
        """Simulate ``socket`` (any workpiece: its own model and data, so every defect kind)
        from the next reset on; the model left behind goes back to its nominal physics."""
        if socket is self.spec:
            return
        if self._nominal is not None:
            apply_draw(self.model, self._nominal, PhysicsDraw())
        self._load(socket)

    def set_physics(self, draw: PhysicsDraw | None) -> None:
        """Apply a randomised-physics ``draw`` to the model (from its nominal values;
        ``None``: nominal), before a reset."""
        if self._nominal is None:
            if draw is None:
                return
            self._nominal = nominal_fields(self.model)
        apply_draw(self.model, self._nominal, draw or PhysicsDraw())

    def pin_forces(self) -> np.ndarray:
        """Summed normal contact force on each pin now (N), ``(n_pins,)``."""
        return self.stepper.pin_forces()

    def pin_touch_points(self) -> np.ndarray:
        """Where each pin presses on the board now (see :meth:`ServoStepper.pin_touch_points`)."""
        return self.stepper.pin_touch_points()

    def reset(self, pose: np.ndarray, keep_part: bool = False) -> BackendState:
        """Place the workpiece at ``pose`` at rest; with ``keep_part`` its elastic-plastic
        pins keep the bends of the last episode (see :meth:`ServoStepper.reset`)."""
        return self.stepper.reset(pose, keep_part)

    def step(self, velocity: np.ndarray) -> BackendState:
        return self.stepper.step(velocity, self.substeps)


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


class MujocoBatch(Capabilities):
    """``num_envs`` MuJoCo simulations of one socket family (see the module docstring).

    A plugged hole (``"blocked"``) adds a board piece, which changes the model's layout, so
    it is the one defect kind a simulation of the batch cannot take.

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
        physics_version: 1 or 2, or that ``PhysicsVersion`` (:mod:`tolins.physics.versions`),
            as the single env's.
        pins: Elastic-plastic pins, or ``None`` (rigid), as the single env's: then every
            simulation runs on a model of its own (a copy), which holds its plastic set.
    """

    supports_render = True
    supports_randomization = True
    supports_touch_points = True
    supports_elastic_pins = True
    defect_kinds = frozenset(DEFECT_KINDS) - {"blocked"}
    batch_options = frozenset({"num_threads", "persistent"})

    def __init__(
        self,
        socket: SocketSpec,
        num_envs: int,
        control_dt: float,
        num_threads: int | None = None,
        contact_checks: int | None = None,
        persistent: bool = False,
        physics_version: int | PhysicsVersion = 1,
        pins: ElasticPins | None = None,
    ) -> None:
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        threads = default_threads() if num_threads is None else num_threads
        self.num_threads = check_threads(threads)
        self.version = physics_version_of(physics_version)
        self.socket = socket
        self.elastic = pins is not None
        build = model_builder(self.version, pins)
        self.model = build(socket)
        self.substeps, self.checks = control_plan(self.model, control_dt, contact_checks)
        # The batch and the arrays bound to it. The models a simulation runs on are read
        # live; ``_models`` holds what the next call applies (a bent-pin draw replaces its
        # simulation's).
        self._servo = BatchServo(
            self.model, self.num_envs, self.num_threads, persistent, self.version.free_flight
        )
        self.batch = self._servo.batch
        self._models = list(self._servo.models)
        self._sockets: list[SocketSpec] = [socket] * self.num_envs
        # The workpieces' models: the nominal one and the last 2 num_envs others.
        self._compiled = SocketCache(build, socket, 2 * self.num_envs, own=self.model)
        self._models_changed = False
        self.layout = self._servo.layout
        self._drawing: mujoco.MjData | None = None

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        if socket is self._sockets[index]:
            return
        self._sockets[index] = socket
        self._models[index] = simulation_model(self._compiled.get(socket), self.elastic)
        self._models_changed = True

    def set_physics(self, index: int, draw: PhysicsDraw | None) -> None:
        """Run simulation ``index`` on its workpiece's model with a randomised-physics
        ``draw`` applied (a copy of its own; ``None``: the workpiece's model)."""
        base = self._compiled.get(self._sockets[index])
        if draw is None or not draw.changes_model:
            self._models[index] = simulation_model(base, self.elastic)
        else:
            model = copy.copy(base)
            apply_draw(model, nominal_fields(base), draw)
            self._models[index] = model
        self._models_changed = True

    def _sync_models(self) -> None:
        if self._models_changed:
            self._servo.set_models(list(self._models))
            self._models_changed = False

    def reset(
        self, ids: np.ndarray, poses: np.ndarray, keep_part: np.ndarray | None = None
    ) -> BatchState:
        """Place simulations ``ids`` at ``poses`` at rest (``keep_part``: per simulation, its
        elastic-plastic pins as bent as they are)."""
        ids = np.asarray(ids, dtype=np.intp)
        self._sync_models()
        keep = None if keep_part is None else np.asarray(keep_part, dtype=bool)
        return self._servo.reset(ids, poses, keep)

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        ids = np.asarray(ids, dtype=np.intp)
        self._sync_models()
        self._servo.ctrl[ids] = np.asarray(velocities, dtype=float)[:, self.layout.joint_pose]
        peak, errors = self._servo.step(ids, self.substeps, self.checks)
        return self._servo.state(ids, peak * FORCE_SCALE, errors)

    def pin_forces(self, ids: np.ndarray) -> np.ndarray:
        """Summed normal contact force on each pin (N) of simulations ``ids``, ``(n, pins)``,
        as ``ServoStepper.pin_forces`` after the last step."""
        touch = self._servo.sensordata[np.asarray(ids, dtype=np.intp), self.layout.touch]
        return touch * FORCE_SCALE

    def pin_touch_points(self, index: int) -> np.ndarray:
        """Where each pin of simulation ``index`` presses on the board after its last step,
        as ``ServoStepper.pin_touch_points`` (a persistent batch only)."""
        if not self.batch.persistent:
            raise RuntimeError("pin_touch_points needs MujocoBatch(..., persistent=True)")
        data = self.batch.get_data(index)
        return pin_touch_points(self._models[index], data, self.layout.pin_by_geom)

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
        self.batch = self._servo = None
        self._models, self._drawing = [], None
        self._compiled.clear()
