"""The MuJoCo control step: socket models stepped one control period at a time.

:func:`servo_control_step` is the control step of every MuJoCo stepper, written once:
re-anchor the servos, run the physics steps in chunks with the summed pin force read after
each, report the peak and any fault. It drives :class:`ServoSimulations`, implemented by
:class:`ServoStepper` (one ``MjModel``/``MjData`` pair: the single env's
:class:`~tolins.physics.mujoco.MujocoBackend` and the dm_control physics) and by
:class:`BatchServo` (many simulations on ``mujoco.batch``, for
:class:`~tolins.physics.mujoco.MujocoBatch`). :func:`run_plan` steps a simulation whose
control law runs between chunks of physics steps (the Panda, :mod:`tolins.physics.panda`).
This is the one module that calls ``mj_step`` or builds a ``mujoco.batch.Batch``. The
helpers here (wrench, faults, touch points) are shared by every MuJoCo stepper.
"""

from __future__ import annotations

import contextlib
import functools
import math
from collections.abc import Callable, Collection, Iterable, Iterator
from typing import Protocol

import mujoco
import mujoco.batch
import numpy as np

from tolins.geometry.validation import check_int
from tolins.mjcf import FORCE_SCALE, model_layout
from tolins.physics.free_flight import (
    FreeStep,
    ServoLimits,
    free_flight_plan,
    free_steps,
    servo_limits,
)
from tolins.physics.protocol import BackendState, BatchState
from tolins.physics.schedule import CONTACT_CHECKS, contact_chunks

#: ``opt.disableflags`` bit that turns off every sensor.
_SENSORS_OFF = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)


@contextlib.contextmanager
def sensors_off(models: Iterable[mujoco.MjModel]) -> Iterator[None]:
    """The models' sensors switched off inside the block (lazy sensors: the state and every
    value read later are the same bit for bit), their flags restored after it."""
    flags = [(model, model.opt.disableflags) for model in models]
    for model, value in flags:
        model.opt.disableflags = value | _SENSORS_OFF
    try:
        yield
    finally:
        for model, value in flags:
            model.opt.disableflags = value


@contextlib.contextmanager
def longer_steps(models: Iterable[mujoco.MjModel], factor: int) -> Iterator[None]:
    """The models' physics step ``factor`` times as long inside the block (free flight,
    :mod:`tolins.physics.free_flight`), restored after it."""
    steps = [(model, model.opt.timestep) for model in models] if factor > 1 else []
    for model, value in steps:
        model.opt.timestep = value * factor
    try:
        yield
    finally:
        for model, value in steps:
            model.opt.timestep = value


def run_segments(
    step: Callable[[int], None],
    models: Collection[mujoco.MjModel],
    segments: list[tuple[int, int]],
    lazy_sensors: bool,
) -> None:
    """Run ``segments``, ``(factor, steps)`` each, through ``step(nstep)`` on ``models``: each
    segment's physics steps ``factor`` contact steps long; with ``lazy_sensors`` the sensors
    computed in the very last step only."""
    segments = [(factor, steps) for factor, steps in segments if steps]
    for i, (factor, steps) in enumerate(segments):
        last = i == len(segments) - 1
        with longer_steps(models, factor):
            quiet = steps - 1 if last else steps
            if lazy_sensors and quiet:
                with sensors_off(models):
                    step(quiet)
                steps -= quiet
            if steps:
                step(steps)


def run_plan(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    plan: Iterable[tuple[int, bool, bool]],
    update: Callable[[], None],
    read: Callable[[], None],
) -> None:
    """Step one simulation through ``plan``, segments ``(steps, update, read)`` of physics
    steps: ``update()`` (a control law writing ``data.ctrl``) before each segment marked
    so, ``read()`` after each segment marked so (the Panda's control step and its
    fingers' closing)."""
    for steps, law, reads in plan:
        if law:
            update()
        mujoco.mj_step(model, data, nstep=steps)
        if reads:
            read()


def chunk_segments(n: int, window: int, factor: int) -> tuple[list[tuple[int, int]], int]:
    """The segments of a chunk of ``n`` contact steps when ``window`` contact steps are left
    before the longer ``factor`` steps, and the window left after it."""
    first = min(window, n)
    return [(1, first), (factor, (n - first) // factor)], window - first


def board_wrench(theta: float, force: list[float], torque_z: float) -> np.ndarray:
    """``[Fx, Fy, q_theta, Fz]`` (N, N·mm, world axes) the board exerts on the workpiece,
    from the force sensor's ``force`` (workpiece axes, rotated by ``theta``) and the z
    torque (model units); the one conversion of every MuJoCo stepper."""
    fx, fy, fz = force
    c, s = math.cos(theta), math.sin(theta)
    wrench = np.array([s * fy - c * fx, -s * fx - c * fy, -torque_z, -fz])
    return wrench * FORCE_SCALE


def simulation_fault(
    warnings_before: int, warnings: list[int], qpos: np.ndarray, qvel: np.ndarray
) -> str | None:
    """What went wrong in a control step, or ``None``: a MuJoCo warning raised during it
    (``warnings``: the counter of each ``mjtWarning`` now, their sum was
    ``warnings_before``), else a non-finite state."""
    if sum(warnings) != warnings_before:
        raised = [mujoco.mjtWarning(i).name for i, number in enumerate(warnings) if number > 0]
        return f"MuJoCo warning during the step: {', '.join(raised)}"
    if not math.isfinite(sum(qpos.tolist()) + sum(qvel.tolist())):
        return "non-finite MuJoCo state"
    return None


def pin_touch_points(
    model: mujoco.MjModel, data: mujoco.MjData, pin_geoms: dict[int, int]
) -> np.ndarray:
    """Where each pin presses on the board in ``data``: ``(n_pins, 2)`` world ``(x, y)`` (mm),
    the normal-force-weighted mean of its contact points; NaN for a pin without contact
    force. ``pin_geoms``: pin index by geom id."""
    n_pins = len(pin_geoms)
    weighted, total = np.zeros((n_pins, 2)), np.zeros(n_pins)
    force = np.zeros(6)
    for k in range(data.ncon):
        contact = data.contact[k]
        pin = pin_geoms.get(contact.geom1, pin_geoms.get(contact.geom2))
        if pin is None:
            continue
        mujoco.mj_contactForce(model, data, k, force)
        weighted[pin] += force[0] * contact.pos[:2]
        total[pin] += force[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(total[:, None] > 0, weighted / total[:, None], np.nan)


class ServoSimulations(Protocol):
    """The simulations one :func:`servo_control_step` drives (one, or a batch's subset)."""

    def warning_counts(self) -> list[int]:
        """Each simulation's number of MuJoCo warnings so far."""

    def anchor(self) -> None:
        """Reset every servo's integrated set-point to its joint's position."""

    def choose_steps(self, chunks: list[int]) -> None:
        """Choose each simulation's physics step for this control step of ``chunks``
        (contact steps between the reads): the contact step, or a longer one in free flight
        (:mod:`tolins.physics.free_flight`)."""

    def no_force(self) -> float | np.ndarray:
        """The peak force before the first read (zero per simulation)."""

    def physics_steps(self, n: int) -> None:
        """``n`` contact steps' time under the current command, in the physics steps
        chosen, the sensors computed in the last."""

    def higher_force(self, peak: float | np.ndarray) -> float | np.ndarray:
        """``max(peak, the summed touch force now)`` per simulation (model units)."""

    def faults(self, warnings_before: list[int]) -> tuple[str | None, ...]:
        """What went wrong in each simulation since ``warnings_before`` (see
        :func:`simulation_fault`)."""


def servo_control_step(
    sims: ServoSimulations, nstep: int, checks: int
) -> tuple[float | np.ndarray, tuple[str | None, ...]]:
    """One control step of ``nstep`` physics steps under the commanded velocities: the
    servos re-anchored (so a blocked workpiece stops at the first contact and pushes with
    at most the servo's force limit instead of winding up), then ``checks`` chunks of
    physics steps (:func:`~tolins.physics.schedule.contact_chunks`), the summed normal pin
    force read after each; in free flight (with ``-v2`` physics) on longer physics steps.
    Returns the peak force (model units) and the faults."""
    before = sims.warning_counts()
    sims.anchor()
    chunks = contact_chunks(nstep, checks)
    sims.choose_steps(chunks)
    peak = sims.no_force()
    for n in chunks:
        sims.physics_steps(n)
        peak = sims.higher_force(peak)
    return peak, sims.faults(before)


class ServoStepper:
    """The control step of a socket model, on a ``MjModel``/``MjData`` pair it does not own.

    At the start of every control step each servo's integrated set-point is reset to
    the joint's current position, then the commanded velocity is integrated over the
    step. A blocked workpiece so stops at the first contact and pushes with at most
    the servo's force limit instead of winding up. The summed normal force of the
    pins' contacts is read after each of ``contact_checks`` chunks of physics steps per
    control step, for ``peak_force``: chunks of ``nstep // contact_checks`` steps, the first
    ``nstep % contact_checks`` one step longer, so ``min(contact_checks, nstep)`` reads
    (evenly spaced whenever ``contact_checks`` divides ``nstep``: 5 reads 50 steps apart
    at the default 0.25 s).

    With ``free_flight``, a control step in which nothing can touch runs on longer physics
    steps (:mod:`tolins.physics.free_flight`; ``-v2`` physics); :attr:`step_factor` says by
    how much the last one did (after a window of contact steps).

    Args:
        model: A model made by :func:`tolins.make_mjcf`.
        data: Its data; read and written in place.
        contact_checks: Contact-force reads per control step (at most).
        free_flight: Take the longer step where nothing can touch.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        contact_checks: int = CONTACT_CHECKS,
        free_flight: bool = False,
    ) -> None:
        contact_checks = check_int("contact_checks", contact_checks, minimum=1)
        self.checks = contact_checks
        self.free_flight = free_flight
        self.step_window, self.step_factor = 0, 1
        self._window_left = 0
        self._limits: ServoLimits | None = None
        self._limits_key: tuple | None = None
        self._bind(model, data)

    def _bind(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Hold ``model`` and ``data`` and the views into ``data`` that the steps read."""
        self.model = model
        self.data = data
        self.layout = layout = model_layout(model)
        # Views into MjData's buffers (valid for its lifetime): the hot loop reads them
        # without building new arrays.
        self._touch = data.sensordata[layout.touch]
        self._wrench = data.sensordata[layout.force]
        self._warnings = data.warning.number

    #: Attributes that view MjData's buffers: pickled, they would become frozen copies.
    _VIEWS = ("_touch", "_wrench", "_warnings")

    def __getstate__(self) -> dict[str, object]:
        # A copy keeps the model, the data (MjData pickles its whole state, the solver's
        # warm start included) and the settings, and binds new views into its own data.
        return {k: v for k, v in self.__dict__.items() if k not in self._VIEWS}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._bind(self.model, self.data)

    def state(self, peak_force: float, error: str | None = None) -> BackendState:
        """The workpiece now: pose, wrench (N, N·mm, world axes) and the given peak force."""
        d, layout = self.data, self.layout
        theta = d.qpos[layout.pose_joint[2]]
        wrench = board_wrench(theta, self._wrench.tolist(), d.sensordata[layout.torque_z])
        return BackendState(
            pose=d.qpos[layout.pose_joint], wrench=wrench, peak_force=peak_force, error=error
        )

    def contact_force(self) -> float:
        """Summed normal contact force on all pins now (N)."""
        return sum(self._touch.tolist()) * FORCE_SCALE

    def pin_forces(self) -> np.ndarray:
        """Summed normal contact force on each pin now (N), ``(n_pins,)``."""
        return self._touch * FORCE_SCALE

    def pin_touch_points(self) -> np.ndarray:
        """Where each pin presses on the board now (see :func:`pin_touch_points`)."""
        return pin_touch_points(self.model, self.data, self.layout.pin_by_geom)

    def reset(self, pose: np.ndarray) -> BackendState:
        """Reset the data and place the workpiece at ``pose`` ``[x, y, theta, z]`` at rest
        (the model's parameters are read anew: a randomised-physics draw applies from here)."""
        m, d = self.model, self.data
        if self.free_flight:
            # Read anew only for another model (held here, so never a reused id) or other
            # servo parameters (a randomised draw changes them in place).
            key = (
                m,
                *(
                    a.tobytes()
                    for a in (m.actuator_gainprm, m.actuator_biasprm, m.actuator_forcerange)
                ),
            )
            if (
                self._limits_key is None
                or key[0] is not self._limits_key[0]
                or key[1:] != self._limits_key[1:]
            ):
                self._limits, self._limits_key = ServoLimits.stack([servo_limits(m)]), key
        mujoco.mj_resetData(m, d)
        d.qpos[:] = np.asarray(pose, dtype=float)[self.layout.joint_pose]
        d.act[:] = d.qpos
        mujoco.mj_forward(m, d)
        return self.state(self.contact_force())

    def command(self, velocity: np.ndarray) -> None:
        """Set the servos' velocity ``[ux, uy, utheta, uz]`` (mm/s, rad/s)."""
        self.data.ctrl[:] = np.asarray(velocity, dtype=float)[self.layout.joint_pose]

    def advance(self, nstep: int) -> BackendState:
        """Re-anchor the servos and run ``nstep`` physics steps under the current command
        (:func:`servo_control_step`)."""
        peak, (fault,) = servo_control_step(self, nstep, self.checks)
        return self.state(peak * FORCE_SCALE, fault)

    #: Compute the sensors only in the last physics step before each read of them: the
    #: state and every value read are the same bit for bit (sensors do not act on the
    #: state), and the touch sensors cost O(pins × contacts) per step. ``False``: in
    #: every step (for side-by-side benchmarks). :class:`BatchServo` follows it too.
    lazy_sensors = True

    # The ServoSimulations of one simulation.

    def warning_counts(self) -> list[int]:
        return [sum(self._warnings.tolist())]

    def anchor(self) -> None:
        self.data.act[:] = self.data.qpos

    def choose_steps(self, chunks: list[int]) -> None:
        self.step_window, self.step_factor = 0, 1
        if self.free_flight and self._limits is not None:
            d, timestep = self.data, self.model.opt.timestep
            window, factor = free_flight_plan(
                self._limits,
                d.qpos[None],
                d.qvel[None],
                d.ctrl[None],
                sum(chunks) * timestep,
                _free_steps(timestep, tuple(chunks)),
            )
            self.step_window, self.step_factor = int(window[0]), int(factor[0])
        self._window_left = self.step_window

    def no_force(self) -> float:
        return 0.0

    def physics_steps(self, n: int) -> None:
        """``n`` contact steps' time in the chosen physics steps. With :attr:`lazy_sensors`
        the model's sensors are switched off for all but the last step, so the model must
        not be stepped elsewhere meanwhile."""
        m, d = self.model, self.data
        segments, self._window_left = chunk_segments(n, self._window_left, self.step_factor)
        run_segments(lambda k: mujoco.mj_step(m, d, nstep=k), [m], segments, self.lazy_sensors)

    def higher_force(self, peak: float) -> float:
        return max(peak, sum(self._touch.tolist()))

    def faults(self, warnings_before: list[int]) -> tuple[str | None]:
        d = self.data
        return (simulation_fault(warnings_before[0], self._warnings.tolist(), d.qpos, d.qvel),)

    def step(self, velocity: np.ndarray, nstep: int) -> BackendState:
        """Command ``velocity`` ``[ux, uy, utheta, uz]`` for ``nstep`` physics steps."""
        self.command(velocity)
        return self.advance(nstep)


@functools.lru_cache(maxsize=64)
def _free_steps(timestep: float, chunks: tuple[int, ...]) -> list[FreeStep]:
    """:func:`~tolins.physics.free_flight.free_steps`, kept per control-step schedule."""
    return free_steps(timestep, list(chunks))


def sequential_sum(columns: np.ndarray) -> np.ndarray:
    """Row sums of ``columns`` ``(n, k)`` added left to right, as Python's ``sum`` of a row
    (numpy's pairwise sum rounds differently from 8 columns on)."""
    total = np.zeros(len(columns))
    for j in range(columns.shape[1]):
        total += columns[:, j]
    return total


class BatchServo:
    """``num_envs`` simulations on one ``mujoco.batch.Batch`` (a native thread pool, the GIL
    released), stepped by :func:`servo_control_step` as :class:`ServoStepper` steps one:
    ``mujoco.batch`` is bit-identical to a loop of ``mj_step`` over one ``MjData`` per
    simulation at any thread count.

    Args:
        model: The model every simulation starts on (:meth:`set_models` replaces them).
        num_envs: Number of simulations.
        num_threads: Threads of the batch, including the caller's.
        persistent: One ``MjData`` per simulation (``mujoco.batch``'s ``persistent``).
        free_flight: Take the longer step where nothing can touch, per simulation, as
            :class:`ServoStepper` does.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        num_envs: int,
        num_threads: int,
        persistent: bool,
        free_flight: bool = False,
    ) -> None:
        self.batch = b = mujoco.batch.Batch(
            model, num_envs, nthread=num_threads, persistent=persistent
        )
        self.layout = model_layout(model)
        self.free_flight = free_flight
        self._limits_of: dict[int, tuple[mujoco.MjModel, ServoLimits]] = {}
        self.set_models([model] * num_envs)
        self.qpos, self.qvel = b.bind("qpos"), b.bind("qvel")
        self.act, self.ctrl = b.bind("act"), b.bind("ctrl")
        self.sensordata = b.bind("sensordata")
        self.ids = np.zeros(0, dtype=np.intp)
        self.step_windows = np.zeros(0, dtype=np.intp)
        self.step_factors = np.ones(0, dtype=np.intp)

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        """Run simulation ``i`` on ``models[i]`` (one layout; read live by the batch; a
        model's parameters are read anew here, so set it again after changing them)."""
        self.models = models
        self.batch.set_models(models)
        if self.free_flight:
            known, self._limits_of = self._limits_of, {}
            for model in models:
                if id(model) not in self._limits_of:
                    # A model is never changed once a batch runs on it (a randomised draw
                    # is a new copy), so the limits of one seen before still hold.
                    entry = known.get(id(model))
                    limits = entry[1] if entry is not None else servo_limits(model)
                    self._limits_of[id(model)] = (model, limits)
            self._limits = ServoLimits.stack([self._limits_of[id(m)][1] for m in models])

    def reset(self, ids: np.ndarray, poses: np.ndarray) -> BatchState:
        """Reset simulations ``ids`` and place their workpieces at ``poses`` at rest, as
        :meth:`ServoStepper.reset` one."""
        self.batch.reset(ids, stage=mujoco.mjtStage.mjSTAGE_NONE)
        self.qpos[ids] = np.asarray(poses, dtype=float)[:, self.layout.joint_pose]
        self.act[ids] = self.qpos[ids]
        self.batch.forward(ids)
        force = sequential_sum(self.sensordata[ids, self.layout.touch]) * FORCE_SCALE
        return self.state(ids, force, None)

    def state(
        self, ids: np.ndarray, peak_force: np.ndarray, errors: tuple[str | None, ...] | None
    ) -> BatchState:
        """Simulations ``ids`` now, as :meth:`ServoStepper.state` one: poses, wrenches and
        the given peak forces and faults."""
        layout = self.layout
        qpos, sensordata = self.qpos[ids], self.sensordata[ids]
        theta = layout.pose_joint[2]
        wrench = np.array(
            [
                board_wrench(q[theta], s[layout.force].tolist(), s[layout.torque_z])
                for q, s in zip(qpos, sensordata, strict=True)
            ]
        ).reshape(len(ids), 4)
        return BatchState(qpos[:, layout.pose_joint], wrench, peak_force, errors)

    def step(self, ids: np.ndarray, nstep: int, checks: int) -> tuple[np.ndarray, tuple]:
        """:func:`servo_control_step` of simulations ``ids`` under their commands."""
        self.ids = ids
        return servo_control_step(self, nstep, checks)

    # The ServoSimulations of the simulations ``self.ids``.

    def warning_counts(self) -> list[int]:
        warning = self.batch.warning
        return [sum(warning[i, :, 1].tolist()) for i in self.ids.tolist()]

    def anchor(self) -> None:
        self.act[self.ids] = self.qpos[self.ids]

    def choose_steps(self, chunks: list[int]) -> None:
        ids = self.ids
        self.step_windows = np.zeros(len(ids), dtype=np.intp)
        self.step_factors = np.ones(len(ids), dtype=np.intp)
        if self.free_flight and len(ids):
            timestep = self.models[0].opt.timestep
            self.step_windows, self.step_factors = free_flight_plan(
                self._limits.rows(ids),
                self.qpos[ids],
                self.qvel[ids],
                self.ctrl[ids],
                sum(chunks) * timestep,
                _free_steps(timestep, tuple(chunks)),
            )
        self._windows_left = self.step_windows.copy()

    def no_force(self) -> np.ndarray:
        return np.zeros(len(self.ids))

    def physics_steps(self, n: int) -> None:
        """As :meth:`ServoStepper.physics_steps`, on every simulation of ``self.ids``: one
        ``Batch.step`` per physics step length chosen."""
        plans = np.stack([self._windows_left, self.step_factors], axis=1)
        for window, factor in np.unique(plans, axis=0).tolist():
            chosen = (self._windows_left == window) & (self.step_factors == factor)
            ids = self.ids[chosen]
            models = list({id(self.models[i]): self.models[i] for i in ids.tolist()}.values())
            segments, left = chunk_segments(n, window, factor)
            self._windows_left[chosen] = left
            run_segments(
                lambda k, ids=ids: self.batch.step(ids, nstep=k),
                models,
                segments,
                ServoStepper.lazy_sensors,
            )

    def higher_force(self, peak: np.ndarray) -> np.ndarray:
        touch = sequential_sum(self.sensordata[self.ids, self.layout.touch])
        return np.where(touch > peak, touch, peak)  # max(peak, touch), as Python's

    def faults(self, warnings_before: list[int]) -> tuple[str | None, ...]:
        warning = self.batch.warning
        return tuple(
            simulation_fault(b, warning[i, :, 1].tolist(), self.qpos[i], self.qvel[i])
            for b, i in zip(warnings_before, self.ids.tolist(), strict=True)
        )
