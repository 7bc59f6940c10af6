"""A Franka Panda holding the workpiece: the ``robot="panda"`` simulations of the envs.

Each simulation is a world of :func:`tolins.mjcf.panda.panda_world`: the socket's board,
the workpiece on a free joint with a handle, and the arm holding it by friction between
its fingers. A control step takes the free body's action ``[ux, uy, uθ, uz]`` (mm/s, rad/s)
as a twist of the grip site and tracks it with the operational-space law of
:class:`~tolins.physics.arm.Arm`, updated every :data:`LAW_RATE`-th of a second (the joint
torques held between updates while MuJoCo steps on).

The law's target moves with the commanded twist and is kept within one control step's
travel at full speed (:data:`~tolins.paper.A_MAX` × the control period, per axis) of where
the robot's forward kinematics put the grip site and within the workspace
(:func:`target_range`: it stops at the edge, as the free body's joints do), and the law's
spring force is clipped (:attr:`~tolins.physics.arm.Gains.force_limit`): a blocked arm
pushes with at most that force, as the free body's servos push with at most their force
limit. Unlike the
servos, the arm is compliant: it does not stop at the first contact but presses until
the law's force balances the board's, and it lags its target while it moves
(``benchmarks/panda_validation.py`` measures both).

A reset puts the hand around the handle where the part is meant to be (IK) and closes the
fingers on it for :data:`SETTLE` s with gravity off (:func:`~tolins.physics.arm.close_fingers`):
from there friction alone holds it. A grasp error (``set_grasp``) puts the part off in the hand
by ``[dx, dy, dyaw]`` (mm, rad, in the grip frame) where the robot believes it nominal.

What a simulation reports (:class:`~tolins.physics.protocol.BatchState`): the part's true
pose and the board's true push on its pins (``pose``, ``wrench``, ``peak_force``, as the
free body's), and what the robot senses: the pose from the grip site's forward kinematics
and the nominal grasp (``sensed_pose``) and the wrist sensor's wrench with the weight of
the hand and the part removed (``sensed_wrench``); the observation measures the sensed.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import itertools
import math
from concurrent.futures import ThreadPoolExecutor

import mujoco
import numpy as np

from tolins.geometry.defects import DEFECT_KINDS
from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int
from tolins.geometry.workspace import POSE_HIGH, POSE_LOW
from tolins.mjcf import FORCE_SCALE
from tolins.mjcf.layout import elastic_pin_layout, touch_addresses
from tolins.mjcf.model import FORCE_SENSOR, TORQUE_SENSOR
from tolins.mjcf.panda import GRAVITY, handle_centre_height, panda_world
from tolins.paper import A_MAX
from tolins.physics.arm import (
    COMPILED,
    SIDEWAYS_STIFFNESS,
    Arm,
    Gains,
    LawInputs,
    close_fingers,
    grip_rotation,
    nominal_pose,
    place_grasp,
    wrist_wrench,
)
from tolins.physics.compiled import SocketCache, simulation_model
from tolins.physics.law_state import STATE, STATE_SIZE, advance_target
from tolins.physics.mujoco import check_threads, default_threads
from tolins.physics.plasticity import PinPlasticity, pin_states
from tolins.physics.protocol import BackendState, BatchState, Capabilities
from tolins.physics.randomization import PhysicsDraw, apply_draw, nominal_fields
from tolins.physics.schedule import contact_chunks, control_plan
from tolins.physics.servo import run_plan, simulation_fault
from tolins.physics.versions import PhysicsVersion
from tolins.physics.versions import physics_version as physics_version_of

#: A batch of one's simulation ids.
_ONE = np.zeros(1, dtype=np.intp)
#: How often the law is updated (Hz); the real Panda's torque interface runs at 1 kHz.
LAW_RATE = 500
#: The closing force of each finger (N).
GRIP_FORCE = 20.0
#: Seconds the fingers close on the weightless part at a reset (they hold it after 0.1 s).
SETTLE = 0.3
#: How far (mm, on any of x, y, z) the part may be from where the robot believes it before
#: a step reports it lost from the hand (a fault: the episode ends).
DROPPED = 3.0


def compile_panda_world(
    socket: SocketSpec,
    physics_version: int | PhysicsVersion = 2,
    pins: ElasticPins | None = None,
) -> mujoco.MjModel:
    """The compiled Panda world of ``socket`` for a physics version (its board in the world
    body from version 2 on, a firm grip from version 3, :mod:`tolins.physics.versions`);
    ``pins``: elastic-plastic pins (``None``: rigid)."""
    version = physics_version_of(physics_version)
    world = panda_world(
        socket,
        board_body=not version.board_in_world,
        firm_grip=version.firm_grip,
        elastic=pins,
    )
    return world.compile()


def default_gains(physics_version: int | PhysicsVersion = 2) -> Gains:
    """The law's gains in a physics version: :class:`~tolins.physics.arm.Gains`'s defaults,
    along x and y :data:`~tolins.physics.arm.SIDEWAYS_STIFFNESS` from version 3."""
    gains = Gains()
    if physics_version_of(physics_version).stiff_sideways:
        stiffness = (SIDEWAYS_STIFFNESS, SIDEWAYS_STIFFNESS, *gains.stiffness[2:])
        gains = dataclasses.replace(gains, stiffness=stiffness)
    return gains


def check_law_rate(model: mujoco.MjModel, law_rate: object) -> int:
    """The physics steps between two updates of the law at ``law_rate`` Hz; ``ValueError``
    unless the law's period is a whole number of the model's physics steps."""
    allowed = "a rate whose period is a whole number of physics steps, e.g. 250, 500, 1000"
    if isinstance(law_rate, bool) or not isinstance(law_rate, int) or law_rate <= 0:
        raise ValueError(f"law_rate={law_rate!r}; allowed: {allowed}")
    steps = 1.0 / (law_rate * model.opt.timestep)
    if abs(steps - round(steps)) > 1e-9 or round(steps) < 1:
        raise ValueError(
            f"law_rate={law_rate} Hz is not a whole number of {model.opt.timestep * 1e3:g} ms "
            f"physics steps; allowed: {allowed}"
        )
    return round(steps)


@functools.lru_cache(maxsize=64)
def update_plan(nstep: int, checks: int, every: int) -> tuple[tuple[int, bool, bool], ...]:
    """One control step of ``nstep`` physics steps as segments ``(steps, update, read)``:
    the law updated before a segment that starts on a multiple of ``every`` steps, the
    contacts read after one that ends a contact chunk (:func:`contact_chunks`)."""
    ends = np.cumsum(contact_chunks(nstep, checks)).tolist()
    bounds = sorted(set(range(0, nstep, every)) | set(ends))  # ends holds nstep
    return tuple(
        (end - start, start % every == 0, end in ends) for start, end in itertools.pairwise(bounds)
    )


#: The slowest update rate (Hz) of a law stiff sideways: at 250 Hz it rings and loses the
#: part within the first control steps of every episode; 500 and 1000 Hz agree.
STIFF_SIDEWAYS_MIN_RATE = 500
#: The largest randomised ``servo_gain`` of a version whose law is stiff sideways: its
#: stiffness times 2 still holds the part (measured on the 2*2 and the square at 50 µm);
#: times 2.5 the law, held for 2 ms between updates, rings and the part is lost.
STIFF_SIDEWAYS_MAX_GAIN = 2.0


def check_gain_range(
    physics_version: int | PhysicsVersion, servo_gain: tuple[float, float] | None
) -> None:
    """``ValueError`` if a randomised ``servo_gain`` range reaches beyond what the law of a
    physics version stays stable with (:data:`STIFF_SIDEWAYS_MAX_GAIN` where it is stiff
    sideways)."""
    version = physics_version_of(physics_version)
    too_stiff = servo_gain is not None and servo_gain[1] > STIFF_SIDEWAYS_MAX_GAIN
    if too_stiff and version.stiff_sideways:
        raise ValueError(
            f"randomization.servo_gain={tuple(servo_gain)!r}: the Panda's law of "
            f"physics_version={version.number} is unstable beyond "
            f"{STIFF_SIDEWAYS_MAX_GAIN:g} times its stiffness; allowed: an upper bound of "
            f"at most {STIFF_SIDEWAYS_MAX_GAIN:g}, or physics_version=2"
        )


def check_version_rate(physics_version: int | PhysicsVersion, law_rate: int) -> None:
    """``ValueError`` if a physics version's law is unstable at ``law_rate`` Hz (below
    :data:`STIFF_SIDEWAYS_MIN_RATE` where it is stiff sideways)."""
    version = physics_version_of(physics_version)
    if version.stiff_sideways and law_rate < STIFF_SIDEWAYS_MIN_RATE:
        raise ValueError(
            f"law_rate={law_rate} Hz: the Panda's law of physics_version={version.number} "
            f"rings below {STIFF_SIDEWAYS_MIN_RATE} Hz and loses the part; allowed: "
            f"{STIFF_SIDEWAYS_MIN_RATE} Hz or more, or physics_version=2"
        )


def split_draw(draw: PhysicsDraw, gains: Gains) -> tuple[PhysicsDraw, Gains]:
    """A randomised draw for a Panda world: its contact terms (friction, stiffness: for the
    model) and ``gains`` scaled by its servo terms (``servo_gain`` the stiffness, the
    damping staying critical; ``force_limit`` the spring force limit)."""
    contact = dataclasses.replace(draw, servo_gain=None, force_limit=None)
    return contact, gains.scaled(draw.servo_gain, draw.force_limit)


def target_range() -> tuple[np.ndarray, np.ndarray]:
    """The law's target range ``[x, y, z, yaw]`` (mm, rad): the grip site where the robot
    believes the part within the workspace (:data:`~tolins.geometry.workspace.POSE_LOW`,
    ``POSE_HIGH``; the site holds the handle's centre, that far above the pin tips)."""
    lift = handle_centre_height()
    order = [0, 1, 3, 2]  # a pose is [x, y, theta, z]
    low, high = POSE_LOW[order].copy(), POSE_HIGH[order].copy()
    low[2] += lift
    high[2] += lift
    return low, high


class PandaSimulations:
    """Panda worlds of one socket family, each a model and a data it does not own, reset
    and stepped together.

    A control step runs each simulation on its own (:func:`~tolins.physics.servo.run_plan`:
    the compiled law, then MuJoCo's physics steps, in chunks), the simulations of a batch
    split over ``num_threads`` threads: both release the GIL, and a simulation steps the
    same bits on any thread and in a batch of any size.

    Args:
        arm: The arm of the family's nominal model (every model of the family has its
            addresses and kinematic tree).
        models: Each simulation's model.
        datas: Each simulation's data.
        control_dt: Control period (s).
        law_rate: Updates of the law per second (:func:`check_law_rate`).
        contact_checks: Contact-force reads per control step, as the free body's.
        num_threads: Threads a control step of several simulations runs on.
    """

    def __init__(
        self,
        arm: Arm,
        models: list[mujoco.MjModel],
        datas: list[mujoco.MjData],
        control_dt: float,
        law_rate: int = LAW_RATE,
        contact_checks: int | None = None,
        num_threads: int = 1,
    ) -> None:
        self.arm, self.models, self.datas = arm, models, datas
        model = arm.model
        self.every = check_law_rate(model, law_rate)
        self.nstep, self.checks = control_plan(model, control_dt, contact_checks)
        self.plan = update_plan(self.nstep, self.checks, self.every)
        self.num_threads = num_threads
        n = len(datas)
        #: Each simulation's law state (:data:`~tolins.physics.law_state.STATE`); the
        #: target, yaw, twist and posture below are views of it.
        self.law_state = np.zeros((n, STATE_SIZE))
        self.target = self.law_state[:, STATE["target"]]
        self.yaw = self.law_state[:, STATE["yaw"]]
        self.twist = self.law_state[:, STATE["twist"]]
        self.posture = self.law_state[:, STATE["posture"]]
        self.grasp = np.zeros((n, 3))
        #: Each simulation's gains (a randomised draw scales them).
        self.gains = [arm.gains] * n
        touch = touch_addresses(model)
        self._touch = slice(touch[0], touch[-1] + 1)
        self._force = int(model.sensor(FORCE_SENSOR).adr[0])
        self._torque = int(model.sensor(TORQUE_SENSOR).adr[0])
        self._site = model.site("ft_site").id
        self._pins_weight = -float(model.body_subtreemass[model.body("pins").id]) * GRAVITY
        workpiece = model.body("workpiece").id
        self._held_mass = float(model.body_subtreemass[workpiece])
        self._part = int(model.joint("workpiece").qposadr[0])
        self._lag = A_MAX[[0, 1, 3]] * control_dt
        self._turn_lag = float(A_MAX[2]) * control_dt
        self._bounds = np.stack(target_range())
        self._span = self.every * model.opt.timestep
        self._inputs: list[LawInputs | None] = [None] * n
        self._packed_gains: list[dict[float, tuple[Gains, np.ndarray]]] = [{} for _ in range(n)]
        self._pool: ThreadPoolExecutor | None = None
        self._pins = elastic_pin_layout(model)
        #: Each simulation's elastic-plastic pins (made for its model when first needed).
        self.plasticity: list[PinPlasticity | None] = [None] * n
        #: Whether the law runs compiled (numba), else in numpy: the same law within
        #: rounding (:mod:`tolins.physics.compiled_law`), the numpy one about 15 times slower.
        self.compiled = COMPILED

    def __getstate__(self) -> dict[str, object]:
        # Threads and the law's bindings to the datas' memory are this process's own.
        return {**self.__dict__, "_pool": None, "_inputs": [None] * len(self.datas)}

    def reset(
        self, ids: np.ndarray, poses: np.ndarray, keep_part: np.ndarray | None = None
    ) -> BatchState:
        """Grasp each part of ``ids`` at ``poses[k]`` (off by its grasp error) and close
        the fingers on it: the state then (``keep_part[k]``: its elastic-plastic pins as
        bent as they are, else straight). One simulation after another: the fingers close
        with gravity off in the model, which simulations may share."""
        keep = np.zeros(len(ids), dtype=bool) if keep_part is None else keep_part
        for k, i in enumerate(ids.tolist()):
            model, data = self.models[i], self.datas[i]
            pins = self._plasticity(i)
            if pins is not None:
                pins.assign(pins.plastic if keep[k] else None)
            target, rot, posture = place_grasp(model, data, self.arm, poses[k], self.grasp[i], pins)
            self.target[i], self.posture[i] = target, posture
            self.yaw[i] = math.atan2(rot[1, 0], rot[0, 0])
            self.twist[i] = 0.0
            close_fingers(
                model,
                data,
                self.arm,
                GRIP_FORCE,
                SETTLE,
                self.every,
                functools.partial(self._update_law, i, 0.0, payload=0.0),
                pins,
            )
        return self.state(ids, self.summed_touch(ids), None)

    def _plasticity(self, i: int) -> PinPlasticity | None:
        """Simulation ``i``'s elastic-plastic pins on its model now (``None``: rigid pins):
        made anew when its model changed, taking the plastic set along."""
        if self._pins is None:
            return None
        pins = self.plasticity[i]
        model = self.models[i]
        pins = PinPlasticity(model, self._pins) if pins is None else pins.on(model)
        self.plasticity[i] = pins
        return pins

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        """Track ``velocities[k]`` ``[ux, uy, uθ, uz]`` with simulation ``ids[k]`` for one
        control period."""
        v = np.asarray(velocities, dtype=float)
        twist = np.zeros((len(ids), 6))
        twist[:, :2], twist[:, 2], twist[:, 5] = v[:, :2], v[:, 3], v[:, 2]
        self.twist[ids] = twist
        before = [self._warnings(i) for i in ids.tolist()]
        self._anchor(ids)
        peak = self._run(ids.tolist())
        state = self.state(ids, peak, None)
        faults = []
        for k, (count, i) in enumerate(zip(before, ids.tolist(), strict=True)):
            data = self.datas[i]
            fault = simulation_fault(count, data.warning.number.tolist(), data.qpos, data.qvel)
            slip = float(np.max(np.abs(state.sensed_pose[k] - state.pose[k])[[0, 1, 3]]))
            if fault is None and slip > DROPPED:
                fault = f"the part slipped {slip:.1f} mm from where the hand holds it"
            faults.append(fault)
        return dataclasses.replace(state, errors=tuple(faults))

    def _run(self, ids: list[int]) -> np.ndarray:
        """Each simulation of ``ids`` through one control step: its peak summed pin force."""
        threads = min(self.num_threads, len(ids))
        if threads <= 1:
            return np.array([self._step_one(i) for i in ids])
        if self._pool is None:
            self._pool = ThreadPoolExecutor(self.num_threads, thread_name_prefix="panda")
        shares = np.array_split(np.arange(len(ids)), threads)
        groups = [[ids[k] for k in share.tolist()] for share in shares]
        peaks = self._pool.map(lambda group: [self._step_one(i) for i in group], groups)
        return np.array([peak for group in peaks for peak in group])

    def _step_one(self, i: int) -> float:
        """Simulation ``i`` through one control step (the law moving its target along its
        twist): its peak summed pin force."""
        peak = 0.0

        def read() -> None:
            nonlocal peak
            force = self._touch_of(i)
            if not force <= peak:  # a NaN force is the peak, as with numpy's maximum
                peak = force

        law = functools.partial(self._update_law, i, self._span)
        run_plan(self.models[i], self.datas[i], self.plan, law, read, self._plasticity(i))
        return peak

    def close(self) -> None:
        """Stop the threads."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    def _warnings(self, i: int) -> int:
        return sum(self.datas[i].warning.number.tolist())

    def _anchor(self, ids: np.ndarray) -> None:
        """Keep each target within one control step's travel of the grip site now."""
        for i in ids.tolist():
            data = self.datas[i]
            site = data.site_xpos[self.arm.site]
            self.target[i] = np.clip(self.target[i], site - self._lag, site + self._lag)
            frame = data.site_xmat[self.arm.site].reshape(3, 3)
            yaw = math.atan2(frame[1, 0], frame[0, 0])
            turn = math.remainder(self.yaw[i] - yaw, math.tau)
            self.yaw[i] = yaw + min(max(turn, -self._turn_lag), self._turn_lag)

    def _update_law(self, i: int, advance: float, payload: float | None = None) -> None:
        """Simulation ``i``'s law: its target moved ``advance`` s along its twist and kept
        in the workspace (:func:`target_range`, as the free body's joint ranges hold its
        pose: a target beyond it is put back on its edge and the twist along that axis
        dropped for this update), then its torques (:meth:`~tolins.physics.arm.Arm.apply_law`).
        ``payload``: the mass (kg) it compensates at the grip site (default: the part's)."""
        payload = self._held_mass if payload is None else payload
        if not self.compiled:
            self._numpy_law(i, advance, payload)
            return
        inputs = self._inputs[i]
        if inputs is None or inputs.data is not self.datas[i]:
            inputs = self._inputs[i] = LawInputs(self.models[i], self.datas[i])
        gains = self._law_gains(i, payload)
        self.arm.apply_law(self.models[i], inputs, self.law_state[i], gains, advance, self._bounds)

    def _numpy_law(self, i: int, advance: float, payload: float) -> None:
        """:meth:`_update_law` in numpy (:meth:`~tolins.physics.arm.Arm.batch_torques`)."""
        state, data = self.law_state[i], self.datas[i]
        twist = advance_target(state, advance, self._bounds)
        (data.ctrl[self.arm.motors],) = self.arm.batch_torques(
            [data],
            self.target[i : i + 1],
            grip_rotation(self.yaw[i])[None],
            twist[None],
            self.posture[i : i + 1],
            payload=payload,
            gains=self.gains[i],
        )

    def _law_gains(self, i: int, payload: float) -> np.ndarray:
        """Simulation ``i``'s gains with ``payload`` as the compiled law reads them (kept
        while its gains stay the same)."""
        gains, packed = self.gains[i], self._packed_gains[i]
        entry = packed.get(payload)
        if entry is None or entry[0] is not gains:
            entry = packed[payload] = (gains, self.arm.law_gains(gains, payload))
        return entry[1]

    def _touch_of(self, i: int) -> float:
        return sum(self.datas[i].sensordata[self._touch].tolist()) * FORCE_SCALE

    def summed_touch(self, ids: np.ndarray) -> np.ndarray:
        """Summed normal contact force on the pins of each of ``ids`` now (N)."""
        return np.array([self._touch_of(i) for i in ids.tolist()])

    def state(
        self, ids: np.ndarray, peak_force: np.ndarray, errors: tuple[str | None, ...] | None
    ) -> BatchState:
        """Simulations ``ids`` now: the part's true pose and the board's push on its pins,
        the given peak forces, and what the robot senses of both."""
        n = len(ids)
        pose, wrench = np.zeros((n, 4)), np.zeros((n, 4))
        sensed_pose, sensed_wrench = np.zeros((n, 4)), np.zeros((n, 4))
        for k, i in enumerate(ids.tolist()):
            data = self.datas[i]
            qpos = data.qpos[self._part : self._part + 7]
            frame = data.site_xmat[self._site].reshape(3, 3)
            pose[k] = qpos[0], qpos[1], math.atan2(frame[1, 0], frame[0, 0]), qpos[2]
            force = self._pins_weight - frame @ data.sensordata[self._force : self._force + 3]
            torque = -(frame @ data.sensordata[self._torque : self._torque + 3])
            wrench[k] = np.array([force[0], force[1], torque[2], force[2]]) * FORCE_SCALE
            sensed_pose[k] = nominal_pose(data, self.arm)
            sensed_wrench[k] = wrist_wrench(data, self.arm, self._held_mass)
        state = BatchState(pose, wrench, peak_force, errors, sensed_pose, sensed_wrench)
        if self._pins is None:
            return state
        bends, deflections = pin_states(
            [self._plasticity(i) for i in ids.tolist()],
            [self.datas[i].qpos for i in ids.tolist()],
            len(self._pins.length),
        )
        return dataclasses.replace(state, pin_bend=bends, pin_deflection=deflections)


class PandaBatch(Capabilities):
    """``num_envs`` Panda worlds of one socket family (see the module docstring).

    Every defect kind but a plugged hole (which adds a board piece and so moves the
    addresses the arm's law reads) can be a simulation's workpiece: it then runs on the
    world compiled for it. A randomised draw (``set_physics``) scales the contact terms of
    the simulation's model copy and the law's gains (:func:`split_draw`).

    Args:
        socket: The nominal socket; every simulation starts with it.
        num_envs: Number of simulations.
        control_dt: Control period (s), as the free body's.
        physics_version: 1, 2 or 3 (:mod:`tolins.physics.versions`): the board in a body
            of its own or in the world body, a firm grip and a law stiff sideways from 3;
            the arm always steps on the contact step.
        law_rate: Updates of the law per second (:data:`LAW_RATE`; at least
            :data:`STIFF_SIDEWAYS_MIN_RATE` in a version stiff sideways).
        gains: The law's gains (default: the version's, :func:`default_gains`).
        contact_checks: Contact-force reads per control step, as the free body's.
        num_threads: Threads a control step runs the simulations on, at most the
            machine's cores (:func:`~tolins.physics.mujoco.check_threads`); default: the
            cores this process may run on. Results do not depend on it.
        pins: Elastic-plastic pins (``pins="elastic-plastic"``), or ``None``: rigid. Then
            each simulation runs on a model of its own, which holds its plastic set.
    """

    supports_render = True
    supports_randomization = True
    supports_touch_points = False
    supports_elastic_pins = True
    defect_kinds = frozenset(DEFECT_KINDS) - {"blocked"}
    batch_options = frozenset({"num_threads"})

    def __init__(
        self,
        socket: SocketSpec,
        num_envs: int,
        control_dt: float,
        physics_version: int | PhysicsVersion = 2,
        law_rate: int = LAW_RATE,
        gains: Gains | None = None,
        contact_checks: int | None = None,
        num_threads: int | None = None,
        pins: ElasticPins | None = None,
    ) -> None:
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        threads = check_threads(default_threads() if num_threads is None else num_threads)
        self.version = physics_version_of(physics_version)
        self.elastic = pins is not None
        build = functools.partial(compile_panda_world, physics_version=self.version, pins=pins)
        self.model = build(socket)
        self._compiled = SocketCache(build, socket, 2 * self.num_envs, own=self.model)
        self._sockets = [socket] * self.num_envs
        models = [simulation_model(self.model, self.elastic) for _ in range(self.num_envs)]
        datas = [mujoco.MjData(self.model) for _ in range(self.num_envs)]
        self.arm = Arm(self.model, gains or default_gains(self.version))
        self.sims = PandaSimulations(
            self.arm, models, datas, control_dt, law_rate, contact_checks, threads
        )
        check_version_rate(self.version, law_rate)

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        if socket is self._sockets[index]:
            return
        model = simulation_model(self._compiled.get(socket), self.elastic)
        self._sockets[index] = socket
        self.sims.models[index] = model
        self.sims.datas[index] = mujoco.MjData(model)

    def set_physics(self, index: int, draw: PhysicsDraw | None) -> None:
        """Run simulation ``index`` with a randomised-physics ``draw`` (``None``: nominal):
        friction and contact stiffness on a copy of its world's model, as the free body's;
        the servo terms on the law: ``servo_gain`` scales its stiffness (its damping stays
        critical), ``force_limit`` its spring force limit."""
        base = self._compiled.get(self._sockets[index])
        sims = self.sims
        if draw is None or not draw.changes_model:
            sims.models[index] = simulation_model(base, self.elastic)
            sims.gains[index] = self.arm.gains
            return
        contact, sims.gains[index] = split_draw(draw, self.arm.gains)
        model = copy.copy(base)
        apply_draw(model, nominal_fields(base), contact)
        sims.models[index] = model

    def set_grasp(self, index: int, offset: np.ndarray) -> None:
        """Hold simulation ``index``'s part off by ``offset`` ``[dx, dy, dyaw]`` (mm, rad,
        the grip frame) from its next reset on."""
        self.sims.grasp[index] = offset

    def reset(
        self, ids: np.ndarray, poses: np.ndarray, keep_part: np.ndarray | None = None
    ) -> BatchState:
        keep = None if keep_part is None else np.asarray(keep_part, dtype=bool)
        ids = np.asarray(ids, dtype=np.intp)
        return self.sims.reset(ids, np.asarray(poses, dtype=float), keep)

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        return self.sims.step(np.asarray(ids, dtype=np.intp), velocities)

    def drawing(self, index: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Simulation ``index``'s model and data (the batch's own: draw before stepping)."""
        return self.sims.models[index], self.sims.datas[index]

    def close(self) -> None:
        """Release the simulations, the compiled models and the threads."""
        self.sims.close()
        self.sims.datas, self.sims.models = [], []
        self._compiled.clear()


class PandaBackend(Capabilities):
    """The single env's Panda: a :class:`PandaBatch` of one (``model`` and ``data`` are the
    simulation's, for drawing; :meth:`set_socket` replaces both; a plugged hole, which adds
    a board piece, is the one defect kind it cannot take)."""

    supports_render = True
    supports_randomization = True
    supports_touch_points = False
    supports_elastic_pins = True
    defect_kinds = PandaBatch.defect_kinds

    def __init__(
        self,
        spec: SocketSpec,
        control_dt: float,
        physics_version: int | PhysicsVersion = 2,
        law_rate: int = LAW_RATE,
        gains: Gains | None = None,
        pins: ElasticPins | None = None,
    ) -> None:
        self.spec = spec
        self._batch = PandaBatch(spec, 1, control_dt, physics_version, law_rate, gains, pins=pins)

    @property
    def model(self) -> mujoco.MjModel:
        return self._batch.sims.models[0]

    @property
    def data(self) -> mujoco.MjData:
        return self._batch.sims.datas[0]

    def set_socket(self, socket: SocketSpec) -> None:
        """Simulate ``socket`` (any workpiece, its own world) from the next reset on."""
        self._batch.set_socket(0, socket)
        self.spec = socket

    def set_physics(self, draw: PhysicsDraw | None) -> None:
        self._batch.set_physics(0, draw)

    def set_grasp(self, offset: np.ndarray) -> None:
        """As :meth:`PandaBatch.set_grasp`."""
        self._batch.set_grasp(0, offset)

    def reset(self, pose: np.ndarray, keep_part: bool = False) -> BackendState:
        return self._batch.reset(_ONE, np.reshape(pose, (1, 4)), np.array([keep_part])).row(0)

    def step(self, velocity: np.ndarray) -> BackendState:
        return self._batch.step(_ONE, np.reshape(velocity, (1, 4))).row(0)


class PandaStepper:
    """One Panda world's control step on a model and data it does not own (dm_control's
    physics): what :class:`~tolins.physics.servo.ServoStepper` is to the free body.

    Args:
        model: A model of :func:`compile_panda_world`.
        data: Its data; read and written in place.
        control_dt: The control period (s) its steps take (``advance(nstep)`` of another
            number of physics steps sets another).
        gains: The law's gains (default :class:`~tolins.physics.arm.Gains`'s; a physics
            version's: :func:`default_gains`).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        control_dt: float,
        gains: Gains | None = None,
    ) -> None:
        self.model, self.data = model, data
        self.arm = Arm(model, gains)
        self.velocity = np.zeros(4)
        self._sims = PandaSimulations(self.arm, [model], [data], control_dt)

    def set_grasp(self, offset: np.ndarray) -> None:
        """As :meth:`PandaBatch.set_grasp`."""
        self._sims.grasp[0] = offset

    def set_gains(self, gains: Gains | None) -> None:
        """The law's gains from the next step on (``None``: the arm's own)."""
        self._sims.gains[0] = gains or self.arm.gains

    def reset(self, pose: np.ndarray, keep_part: bool = False) -> BackendState:
        """Grasp the part at ``pose`` ``[x, y, theta, z]`` (as :meth:`PandaSimulations.reset`;
        ``keep_part``: its elastic-plastic pins as bent as they are)."""
        pose = np.reshape(np.asarray(pose, dtype=float), (1, 4))
        return self._sims.reset(_ONE, pose, np.array([keep_part])).row(0)

    def command(self, velocity: np.ndarray) -> None:
        """Set the velocity ``[ux, uy, utheta, uz]`` (mm/s, rad/s) of the next steps."""
        self.velocity = np.asarray(velocity, dtype=float).copy()

    def advance(self, nstep: int) -> BackendState:
        """Track the commanded velocity for ``nstep`` physics steps (one control step)."""
        if nstep != self._sims.nstep:
            old = self._sims
            control_dt = nstep * self.model.opt.timestep
            self._sims = PandaSimulations(self.arm, [self.model], [self.data], control_dt)
            self._sims.grasp[:], self._sims.gains = old.grasp, old.gains
            self._sims.plasticity = old.plasticity
        return self._sims.step(_ONE, self.velocity[None]).row(0)

    def state(self, peak_force: float) -> BackendState:
        """The part now, with ``peak_force`` (as :meth:`PandaSimulations.state`)."""
        return self._sims.state(_ONE, np.array([peak_force]), None).row(0)

    def contact_force(self) -> float:
        """Summed normal contact force on all pins now (N)."""
        return float(self._sims.summed_touch(_ONE)[0])
