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
import copy
import dataclasses
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
from tolins.physics.plasticity import PinPlasticity, pin_states
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


#: ``opt.disableflags`` bits that a free-flight control step of elastic-plastic pins turns
#: off: their equalities, and collision detection (nothing can touch, so none is found).
_HELD_OFF = int(mujoco.mjtDisableBit.mjDSBL_EQUALITY) | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
#: A held pin's hinges' armature over their own: the workpiece's accelerations turn them by
#: less than 1e-8 rad in a control step (and :func:`pins_held` undoes even that).
HELD_ARMATURE = 1e6


@contextlib.contextmanager
def pins_held(
    models: Iterable[mujoco.MjModel],
    pins: list[tuple[PinPlasticity, np.ndarray, np.ndarray]],
) -> Iterator[None]:
    """Elastic-plastic pins held as if welded to their workpiece inside the block, for a
    control step in free flight: ``pins`` ``(plasticity, qpos, qvel)`` of each simulation
    (none: nothing is done), ``models`` theirs. Each pin stops; its model's equalities and
    collision detection are off and its hinges' armature is :data:`HELD_ARMATURE` times
    their own; after the block every pin is put back exactly where it was, at rest, and the
    models restored. In free flight nothing loads a pin: held, it costs about a rigid pin's
    step, where its equalities' rows would be solved in every step (and would need a
    calibration of their own at the longer step, whose 1 ms one diverges there)."""
    if not pins:
        yield
        return
    angles = [plasticity.hold(qpos, qvel) for plasticity, qpos, qvel in pins]
    held = [(model, model.opt.disableflags, model.dof_armature.copy()) for model in models]
    for model, flags, armature in held:
        model.opt.disableflags = flags | _HELD_OFF
        model.dof_armature[model.nu :] = armature[model.nu :] * HELD_ARMATURE
    try:
        yield
    finally:
        for model, flags, armature in held:
            model.opt.disableflags = flags
            model.dof_armature[:] = armature
        for (plasticity, qpos, qvel), at in zip(pins, angles, strict=True):
            plasticity.release(qpos, qvel, at)


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
    plasticity: PinPlasticity | None = None,
) -> None:
    """Step one simulation through ``plan``, segments ``(steps, update, read)`` of physics
    steps: ``update()`` (a control law writing ``data.ctrl``) before each segment marked
    so, ``read()`` after each segment marked so (the Panda's control step and its
    fingers' closing). With elastic-plastic pins (``plasticity``) the return mapping
    follows every physics step."""
    for steps, law, reads in plan:
        if law:
            update()
        if plasticity is None:
            mujoco.mj_step(model, data, nstep=steps)
        else:
            for _ in range(steps):
                mujoco.mj_step(model, data)
                plasticity.update(data.qpos)
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

    A model with elastic-plastic pins (:mod:`tolins.mjcf.elastic_pins`) is stepped in chunks
    in which no pin can reach yield, the return mapping after each
    (:class:`~tolins.physics.plasticity.PinPlasticity`, :attr:`plasticity`). A control step
    in free flight holds its pins as they are (:func:`pins_held`: nothing loads them
    there), its window included, and the pins' reach grows by their tip offsets now
    (:func:`bent_limits`).

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
        pins = self.layout.elastic
        self.plasticity = None if pins is None else PinPlasticity(model, pins)

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
        # What the servos' activations follow: the workpiece's joints (then pin hinges).
        self._servo_q = data.qpos if layout.elastic is None else data.qpos[: model.nu]

    #: Attributes that view MjData's buffers: pickled, they would become frozen copies.
    _VIEWS = ("_touch", "_wrench", "_warnings", "_servo_q")

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
        state = BackendState(
            pose=d.qpos[layout.pose_joint], wrench=wrench, peak_force=peak_force, error=error
        )
        if self.plasticity is None:
            return state
        bend, deflection = self.plasticity.bend(), self.plasticity.deflection(d.qpos)
        return dataclasses.replace(state, pin_bend=bend, pin_deflection=deflection)

    def contact_force(self) -> float:
        """Summed normal contact force on all pins now (N)."""
        return sum(self._touch.tolist()) * FORCE_SCALE

    def pin_forces(self) -> np.ndarray:
        """Summed normal contact force on each pin now (N), ``(n_pins,)``."""
        return self._touch * FORCE_SCALE

    def pin_touch_points(self) -> np.ndarray:
        """Where each pin presses on the board now (see :func:`pin_touch_points`)."""
        return pin_touch_points(self.model, self.data, self.layout.pin_by_geom)

    def reset(self, pose: np.ndarray, keep_part: bool = False) -> BackendState:
        """Reset the data and place the workpiece at ``pose`` ``[x, y, theta, z]`` at rest
        (the model's parameters are read anew: a randomised-physics draw applies from here).
        Elastic-plastic pins start straight, or with ``keep_part`` as bent as they are."""
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
        self._servo_q[:] = np.asarray(pose, dtype=float)[self.layout.joint_pose]
        d.act[:] = self._servo_q
        if self.plasticity is not None:
            self.plasticity.assign(self.plasticity.plastic if keep_part else None)
            self.plasticity.place(d.qpos, d.qvel)
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
        self.data.act[:] = self._servo_q

    def choose_steps(self, chunks: list[int]) -> None:
        self.step_window, self.step_factor = 0, 1
        if self.free_flight and self._limits is not None:
            d, timestep = self.data, self.model.opt.timestep
            limits, q = self._limits, slice(0, self.model.nu)  # the workpiece's joints
            if self.plasticity is not None:
                limits = bent_limits(limits, [self.plasticity], [d.qpos])
            window, factor = free_flight_plan(
                limits,
                d.qpos[None, q],
                d.qvel[None, q],
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
        m, d, plasticity = self.model, self.data, self.plasticity
        segments, self._window_left = chunk_segments(n, self._window_left, self.step_factor)
        step = functools.partial(mujoco.mj_step, m, d)
        if plasticity is not None and self.step_factor == 1:
            plastic_chunks(
                n,
                [0],
                lambda _, left: plasticity.steps(d.qpos, d.qvel, d.ctrl, left),
                lambda k, last, _: run_chunk(step, [m], k, last),
                lambda _: plasticity.update(d.qpos),
            )
            return
        pins = [] if plasticity is None else [(plasticity, d.qpos, d.qvel)]
        with pins_held([m], pins):
            run_segments(step, [m], segments, self.lazy_sensors)

    def higher_force(self, peak: float) -> float:
        return max(peak, sum(self._touch.tolist()))

    def faults(self, warnings_before: list[int]) -> tuple[str | None]:
        d = self.data
        return (simulation_fault(warnings_before[0], self._warnings.tolist(), d.qpos, d.qvel),)

    def step(self, velocity: np.ndarray, nstep: int) -> BackendState:
        """Command ``velocity`` ``[ux, uy, utheta, uz]`` for ``nstep`` physics steps."""
        self.command(velocity)
        return self.advance(nstep)


def run_chunk(
    step: Callable[[int], None], models: list[mujoco.MjModel], k: int, last: bool
) -> None:
    """``step(k)`` on ``models`` on the contact step (a chunk in which no elastic-plastic pin
    can reach yield: :meth:`PinPlasticity.steps`), the sensors computed only in its last
    step when it ends the chunk of contact steps (``last``), else not at all (with
    :attr:`ServoStepper.lazy_sensors`)."""
    lazy = ServoStepper.lazy_sensors
    if last or not lazy:
        run_segments(step, models, [(1, k)], lazy)
        return
    with sensors_off(models):
        step(k)


def plastic_chunks(
    n: int,
    sims: list[int],
    allowed: Callable[[int, int], int],
    run: Callable[[int, bool, list[int]], None],
    update: Callable[[int], None],
) -> None:
    """``n`` contact steps of simulations ``sims`` with elastic-plastic pins, in chunks that
    no pin can yield within: each simulation takes the chunk its own state allows
    (``allowed(sim, steps_left)``, :meth:`PinPlasticity.steps`), the simulations with the
    same chunk length and end are stepped together (``run(k, last, sims)``), then each one's
    return mapping runs (``update(sim)``)."""
    left = dict.fromkeys(sims, n)
    while left:
        chunks = {i: allowed(i, rest) for i, rest in left.items()}
        groups: dict[tuple[int, bool], list[int]] = {}
        for i, k in chunks.items():
            left[i] -= k
            groups.setdefault((k, not left[i]), []).append(i)
        for (k, last), members in groups.items():
            run(k, last, members)
        for i in chunks:
            update(i)
        left = {i: rest for i, rest in left.items() if rest}


def bent_limits(
    limits: ServoLimits, plasticity: list[PinPlasticity], qpos: list[np.ndarray]
) -> ServoLimits:
    """``limits`` (stacked, one row per simulation) with each pin's radius and the
    workpiece's lowest point grown by the largest tip offset now in its simulation, elastic
    included, and a micrometre: a bent pin reaches that much farther from its axis, and its
    tilted rim no deeper (the rim drops by r·sin φ, less than the tip's offset L·sin φ)."""
    grow = np.array(
        [np.max(np.hypot(*p.deflection(q).T)) + 1e-3 for p, q in zip(plasticity, qpos, strict=True)]
    )
    return dataclasses.replace(
        limits, pin_radius=limits.pin_radius + grow[:, None], lowest=limits.lowest + grow
    )


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

    With elastic-plastic pins each simulation runs on its own model, whose ``eq_data`` holds
    its plastic set (:class:`~tolins.physics.plasticity.PinPlasticity`), in the chunks and
    with the return mapping of :class:`ServoStepper`, simulation by simulation, so each is
    the single env's bit for bit, and in free flight with their pins held, as there.
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
        self.elastic = self.layout.elastic is not None
        self.free_flight = free_flight
        self._limits_of: dict[int, tuple[mujoco.MjModel, ServoLimits]] = {}
        self.models: list[mujoco.MjModel] = []
        self.plasticity: list[PinPlasticity] = []
        if self.elastic:
            self.set_models([copy.copy(model) for _ in range(num_envs)])
        else:
            self.set_models([model] * num_envs)
        self.qpos, self.qvel = b.bind("qpos"), b.bind("qvel")
        self.act, self.ctrl = b.bind("act"), b.bind("ctrl")
        self.sensordata = b.bind("sensordata")
        self.ids = np.zeros(0, dtype=np.intp)
        self.step_windows = np.zeros(0, dtype=np.intp)
        self.step_factors = np.ones(0, dtype=np.intp)

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        """Run simulation ``i`` on ``models[i]`` (one layout; read live by the batch; a
        model's parameters are read anew here, so set it again after changing them). With
        elastic-plastic pins every simulation needs a model of its own; one whose model
        changes takes its plastic set along (its next reset keeps it or straightens it)."""
        if self.elastic:
            if len({id(model) for model in models}) != len(models):
                raise ValueError("elastic-plastic pins need a model of its own per simulation")
            old = self.plasticity
            self.plasticity = [
                old[i].on(model) if i < len(old) else PinPlasticity(model, self.layout.elastic)
                for i, model in enumerate(models)
            ]
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

    def reset(
        self, ids: np.ndarray, poses: np.ndarray, keep_part: np.ndarray | None = None
    ) -> BatchState:
        """Reset simulations ``ids`` and place their workpieces at ``poses`` at rest, as
        :meth:`ServoStepper.reset` one (``keep_part``: per simulation, its elastic-plastic
        pins as bent as they are)."""
        self.batch.reset(ids, stage=mujoco.mjtStage.mjSTAGE_NONE)
        self.act[ids] = np.asarray(poses, dtype=float)[:, self.layout.joint_pose]
        self.qpos[ids, : self.act.shape[1]] = self.act[ids]
        if self.elastic:
            keep = np.zeros(len(ids), bool) if keep_part is None else keep_part
            for i, kept in zip(ids.tolist(), keep.tolist(), strict=True):
                plasticity = self.plasticity[i]
                plasticity.assign(plasticity.plastic if kept else None)
                plasticity.place(self.qpos[i], self.qvel[i])
            self.batch.set_models(self.models)  # the plastic sets in eq_data, read anew
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
        state = BatchState(qpos[:, layout.pose_joint], wrench, peak_force, errors)
        if not self.elastic:
            return state
        rows = [self.plasticity[i] for i in ids.tolist()]
        bends, deflections = pin_states(rows, list(qpos), layout.n_pins)
        return dataclasses.replace(state, pin_bend=bends, pin_deflection=deflections)

    def step(self, ids: np.ndarray, nstep: int, checks: int) -> tuple[np.ndarray, tuple]:
        """:func:`servo_control_step` of simulations ``ids`` under their commands."""
        self.ids = ids
        return servo_control_step(self, nstep, checks)

    # The ServoSimulations of the simulations ``self.ids``.

    def warning_counts(self) -> list[int]:
        warning = self.batch.warning
        return [sum(warning[i, :, 1].tolist()) for i in self.ids.tolist()]

    def anchor(self) -> None:
        # The servos follow the workpiece's joints, the first in qpos (pin hinges after).
        self.act[self.ids] = self.qpos[self.ids, : self.act.shape[1]]

    def choose_steps(self, chunks: list[int]) -> None:
        ids = self.ids
        self.step_windows = np.zeros(len(ids), dtype=np.intp)
        self.step_factors = np.ones(len(ids), dtype=np.intp)
        if self.free_flight and len(ids):
            timestep = self.models[0].opt.timestep
            limits, qpos, qvel = self._limits.rows(ids), self.qpos[ids], self.qvel[ids]
            if self.elastic:
                pins = [self.plasticity[i] for i in ids.tolist()]
                limits = bent_limits(limits, pins, list(qpos))
                nu = self.act.shape[1]  # the workpiece's joints, before the pin hinges
                qpos, qvel = qpos[:, :nu], qvel[:, :nu]
            self.step_windows, self.step_factors = free_flight_plan(
                limits,
                qpos,
                qvel,
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
        flying = self.step_factors > 1
        if self.elastic:
            self._plastic_steps(n, self.ids[~flying])
        rows = np.flatnonzero(flying) if self.elastic else np.arange(len(self.ids))
        plans = np.stack([self._windows_left[rows], self.step_factors[rows]], axis=1)
        for window, factor in np.unique(plans, axis=0).tolist():
            chosen = rows[(plans[:, 0] == window) & (plans[:, 1] == factor)]
            ids = self.ids[chosen]
            models = list({id(self.models[i]): self.models[i] for i in ids.tolist()}.values())
            segments, self._windows_left[chosen] = chunk_segments(n, window, factor)
            pins = (
                [(self.plasticity[i], self.qpos[i], self.qvel[i]) for i in ids.tolist()]
                if self.elastic
                else []
            )
            with pins_held(models, pins):
                run_segments(
                    lambda k, ids=ids: self.batch.step(ids, nstep=k),
                    models,
                    segments,
                    ServoStepper.lazy_sensors,
                )

    def _plastic_steps(self, n: int, ids: np.ndarray) -> None:
        """As :meth:`ServoStepper.physics_steps` on the contact step with elastic-plastic
        pins, for simulations ``ids``: :func:`plastic_chunks`, one ``Batch.step`` per chunk
        length and end."""

        def run(k: int, last: bool, members: list[int]) -> None:
            chosen = np.array(members, dtype=np.intp)
            models = [self.models[i] for i in members]
            run_chunk(lambda j: self.batch.step(chosen, nstep=j), models, k, last)

        plastic_chunks(
            n,
            ids.tolist(),
            lambda i, rest: self.plasticity[i].steps(
                self.qpos[i], self.qvel[i], self.ctrl[i], rest
            ),
            run,
            lambda i: self.plasticity[i].update(self.qpos[i]),
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
