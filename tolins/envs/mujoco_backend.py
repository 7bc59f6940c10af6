"""Contact physics: one MuJoCo model of a socket, stepped one control period at a time.

:class:`ServoStepper` is the control step itself, on any ``MjModel``/``MjData`` pair
built by :func:`tolins.make_mjcf`; the gymnasium backend (:class:`MujocoBackend`) and
the dm_control physics (:class:`tolins.dmc.InsertionPhysics`) both step through it.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterable, Iterator

import mujoco
import numpy as np

from tolins.envs.backend import BackendState
from tolins.envs.episode import check_control_dt
from tolins.envs.randomization import PhysicsDraw, apply_draw, nominal_fields
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int
from tolins.mjcf import make_mjcf

#: Model units (mN, µN·m) to the API's N and N·mm.
_FORCE_SCALE = 1e-3
#: Pose ``[x, y, theta, z]`` ↔ joint order ``x, y, z, theta`` (qpos, act and ctrl); the
#: swap is its own inverse.
_SWAP_Z_THETA = np.array([0, 1, 3, 2])


def _touch_sensors(model: mujoco.MjModel) -> tuple[int, int]:
    """Address and count of the contiguous ``pin{i}_touch`` sensors in ``sensordata``."""
    addresses = []
    while True:
        try:
            addresses.append(model.sensor(f"pin{len(addresses)}_touch").adr[0])
        except KeyError:
            break
    if not addresses or addresses != list(range(addresses[0], addresses[0] + len(addresses))):
        raise RuntimeError("the pins' touch sensors are missing or not stored contiguously")
    return addresses[0], len(addresses)


def physics_steps(model: mujoco.MjModel, control_dt: float) -> int:
    """How many physics steps make one control period; ``ValueError`` for a ``control_dt``
    that :func:`~tolins.envs.episode.check_control_dt` refuses (the rule of every backend)."""
    return round(check_control_dt(control_dt) / model.opt.timestep)


#: ``opt.disableflags`` bit that turns off every sensor.
_SENSORS_OFF = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)

#: Contact-force reads per control step: five, as long as a step has five physics steps.
CONTACT_CHECKS = 5


def default_contact_checks(substeps: int) -> int:
    """Contact-force reads per control step of ``substeps`` physics steps: ``min(5, substeps)``
    (the 250 steps of the paper's 0.25 s: five reads, 50 steps apart)."""
    return min(CONTACT_CHECKS, substeps)


def control_plan(
    model: mujoco.MjModel, control_dt: float, contact_checks: int | None = None
) -> tuple[int, int]:
    """``(physics steps, contact reads)`` of one control step of ``model``: the steps of
    ``control_dt`` (:func:`physics_steps`) and ``contact_checks`` reads, default
    :func:`default_contact_checks`, checked to lie in 1 … the steps."""
    substeps = physics_steps(model, control_dt)
    if contact_checks is None:
        contact_checks = default_contact_checks(substeps)
    return substeps, check_int("contact_checks", contact_checks, minimum=1, maximum=substeps)


def contact_chunks(nstep: int, checks: int) -> list[int]:
    """The physics steps between the contact reads of one control step: ``checks`` chunks
    of ``nstep // checks`` steps, the first ``nstep % checks`` one step longer, empty ones
    dropped (every MuJoCo stepper's schedule)."""
    chunk, extra = divmod(nstep, checks)
    return [n for n in (chunk + (i < extra) for i in range(checks)) if n]


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


def board_wrench(theta: float, force: list[float], torque_z: float) -> np.ndarray:
    """``[Fx, Fy, q_theta, Fz]`` (N, N·mm, world axes) the board exerts on the workpiece,
    from the force sensor's ``force`` (workpiece axes, rotated by ``theta``) and the z
    torque (model units); the one conversion of every MuJoCo stepper."""
    fx, fy, fz = force
    c, s = math.cos(theta), math.sin(theta)
    wrench = np.array([s * fy - c * fx, -s * fx - c * fy, -torque_z, -fz])
    return wrench * _FORCE_SCALE


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


def pin_geom_ids(model: mujoco.MjModel) -> dict[int, int]:
    """Pin index by geom id of a model made by :func:`tolins.make_mjcf`."""
    _, n_pins = _touch_sensors(model)
    return {model.geom(f"pin{i}").id: i for i in range(n_pins)}


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

    Args:
        model: A model made by :func:`tolins.make_mjcf`.
        data: Its data; read and written in place.
        contact_checks: Contact-force reads per control step (at most).
    """

    def __init__(
        self, model: mujoco.MjModel, data: mujoco.MjData, contact_checks: int = CONTACT_CHECKS
    ) -> None:
        contact_checks = check_int("contact_checks", contact_checks, minimum=1)
        self.checks = contact_checks
        self._bind(model, data)

    def _bind(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Hold ``model`` and ``data`` and the views into ``data`` that the steps read."""
        self.model = model
        self.data = data
        self._force = model.sensor("force").adr[0]
        self._torque = model.sensor("torque").adr[0]
        touch, n_pins = _touch_sensors(model)
        # Views into MjData's buffers (valid for its lifetime): the hot loop reads them
        # without building new arrays.
        self._touch = data.sensordata[touch : touch + n_pins]
        self._wrench = data.sensordata[self._force : self._force + 3]
        self._warnings = data.warning.number
        self._pin_geoms = pin_geom_ids(model)

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
        d = self.data
        wrench = board_wrench(d.qpos[3], self._wrench.tolist(), d.sensordata[self._torque + 2])
        return BackendState(
            pose=d.qpos[_SWAP_Z_THETA], wrench=wrench, peak_force=peak_force, error=error
        )

    def contact_force(self) -> float:
        """Summed normal contact force on all pins now (N)."""
        return sum(self._touch.tolist()) * _FORCE_SCALE

    def pin_forces(self) -> np.ndarray:
        """Summed normal contact force on each pin now (N), ``(n_pins,)``."""
        return self._touch * _FORCE_SCALE

    def pin_touch_points(self) -> np.ndarray:
        """Where each pin presses on the board now (see :func:`pin_touch_points`)."""
        return pin_touch_points(self.model, self.data, self._pin_geoms)

    def reset(self, pose: np.ndarray) -> BackendState:
        """Reset the data and place the workpiece at ``pose`` ``[x, y, theta, z]`` at rest."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[:] = np.asarray(pose, dtype=float)[_SWAP_Z_THETA]
        d.act[:] = d.qpos
        mujoco.mj_forward(m, d)
        return self.state(self.contact_force())

    def command(self, velocity: np.ndarray) -> None:
        """Set the servos' velocity ``[ux, uy, utheta, uz]`` (mm/s, rad/s)."""
        self.data.ctrl[:] = np.asarray(velocity, dtype=float)[_SWAP_Z_THETA]

    def advance(self, nstep: int) -> BackendState:
        """Re-anchor the servos and run ``nstep`` physics steps under the current command."""
        d = self.data
        warnings_before = sum(self._warnings.tolist())
        d.act[:] = d.qpos
        touch, peak = self._touch, 0.0
        for n in contact_chunks(nstep, self.checks):
            self._physics_steps(n)
            peak = max(peak, sum(touch.tolist()))
        return self.state(peak * _FORCE_SCALE, self._fault(warnings_before))

    #: Compute the sensors only in the last physics step before each read of them: the
    #: state and every value read are the same bit for bit (sensors do not act on the
    #: state), and the touch sensors cost O(pins × contacts) per step. ``False``: in
    #: every step, as before issue 19 (for side-by-side benchmarks).
    lazy_sensors = True

    def _physics_steps(self, n: int) -> None:
        """``n`` physics steps. With :attr:`lazy_sensors` the model's sensors are switched
        off for all but the last, so the model must not be stepped elsewhere meanwhile."""
        m, d = self.model, self.data
        if self.lazy_sensors and n > 1:
            with sensors_off([m]):
                mujoco.mj_step(m, d, nstep=n - 1)
            n = 1
        mujoco.mj_step(m, d, nstep=n)

    def step(self, velocity: np.ndarray, nstep: int) -> BackendState:
        """Command ``velocity`` ``[ux, uy, utheta, uz]`` for ``nstep`` physics steps."""
        self.command(velocity)
        return self.advance(nstep)

    def _fault(self, warnings_before: int) -> str | None:
        d = self.data
        return simulation_fault(warnings_before, self._warnings.tolist(), d.qpos, d.qvel)


class MujocoBackend:
    """The gymnasium env's contact physics: a compiled socket model and its :class:`ServoStepper`.

    Args:
        spec: The socket.
        control_dt: Control period (s), any that
            :func:`~tolins.envs.episode.check_control_dt` allows.
        contact_checks: How many times per control step the contact force is read, for
            ``peak_force`` (chunks as in :class:`ServoStepper`), 1 … the physics steps;
            default :func:`default_contact_checks` of the physics steps.
    """

    def __init__(
        self, spec: SocketSpec, control_dt: float, contact_checks: int | None = None
    ) -> None:
        self.spec = spec
        self.model = mujoco.MjModel.from_xml_string(make_mjcf(spec))
        self.data = mujoco.MjData(self.model)
        self.substeps, contact_checks = control_plan(self.model, control_dt, contact_checks)
        self.stepper = ServoStepper(self.model, self.data, contact_checks)
        self._nominal: dict[str, np.ndarray] | None = None

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

    def reset(self, pose: np.ndarray) -> BackendState:
        return self.stepper.reset(pose)

    def step(self, velocity: np.ndarray) -> BackendState:
        return self.stepper.step(velocity, self.substeps)
