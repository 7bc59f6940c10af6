"""A Panda holding the workpiece: placing the grasp, and the task-space control law.

:class:`Arm` reads a world of :func:`tolins.mjcf.panda.panda_world`: the grip site's
Jacobian, damped-least-squares IK within the joint limits, and the operational-space law

    τ = Jᵀ (Λ ([clip(Kp e_p), Kp e_r] + Kd (v* − v)) − m g) + N (M (kq (q₀ − q) − 2 √kq q̇)) + b,

with ``e = [e_p, e_r]`` the grip site's position (mm) and rotation (rad) error (the
position error's pull clipped on each of x, y and z to the force limit of :class:`Gains`
over that axis's task inertia ``Λ_ii``: a blocked arm pushes with a bounded force, as the
servos do), ``v*`` the commanded twist, ``Λ = (J M⁻¹ Jᵀ)⁻¹`` the task-space inertia,
``N = I − Jᵀ J̄ᵀ`` the null space of the dynamically consistent inverse ``J̄ = M⁻¹ Jᵀ Λ``
(a posture ``q₀`` held there), ``b`` gravity and Coriolis (MuJoCo's ``qfrc_bias``) and
``m g`` the weight of the part held at the grip site (``payload``, as a real Franka is
told its load); τ is clipped to the Franka's torque limits.
:func:`place_grasp` puts the hand around the part's handle at a pose and
:func:`close_fingers` closes them on it. What a robot knows of the part: :func:`nominal_pose` (the
grip site's forward kinematics and the nominal grasp) and :func:`wrist_wrench` (the wrist
sensor with the weight of the hand and the part removed).
"""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from tolins.mjcf import FORCE_SCALE
from tolins.mjcf.model import FORCE_LIMIT
from tolins.mjcf.panda import (
    ARM_JOINTS,
    ARM_MOTORS,
    FINGER_ACTUATORS,
    FINGER_JOINTS,
    FLANGE,
    GRAVITY,
    GRIP_SITE,
    HAND,
    HANDLE,
    PREFIX,
    WRIST_FORCE,
    WRIST_TORQUE,
    handle_centre_height,
)
from tolins.physics.law_state import pack_gains
from tolins.physics.plasticity import PinPlasticity
from tolins.physics.servo import run_plan

#: The IK's start (rad): of the grasps over the board's centre reached from 300 random
#: starts within the joint limits, the one farthest from every limit (0.63 rad). Grasps
#: anywhere in the workspace lie within 0.33 rad of it, so IK stays on this branch.
READY = np.array([-1.4786, 1.0651, 1.3737, -2.4438, -1.3635, 0.5028, 0.8614])


#: Whether numba is here to compile the law (:mod:`tolins.physics.compiled_law`, imported
#: when a Panda is built); else the law runs in numpy, about 15 times slower.
COMPILED = importlib.util.find_spec("numba") is not None

#: The law's stiffness along x and y (s⁻²) where a physics version's Panda is stiff
#: sideways (:mod:`tolins.physics.versions`), eight times :class:`Gains`'s default: over
#: the grip's task inertia (7.4 kg along x, 5.7 kg along y over the board) 0.9–1.2 kN/mm,
#: against the default's 113–148 N/mm and the free body's servos' 200 N/mm. The law holds
#: it at 500 Hz and rings at 250 (:data:`~tolins.physics.panda.STIFF_SIDEWAYS_MIN_RATE`).
SIDEWAYS_STIFFNESS = 160000.0


@dataclass(frozen=True)
class Gains:
    """The law's gains: ``stiffness`` (s⁻², per task axis: x, y, z, then rotations), the
    damping critical for a unit mass (``2 √Kp``), the posture's ``null`` (s⁻²), and the
    largest spring force (mN) the law pushes with along x, y and z: down, the free body's
    servo limit (:data:`~tolins.mjcf.model.FORCE_LIMIT`, 5 N); sideways four times that,
    more than the friction of pins pressed on the board with 5 N (μ = 1), so that the arm
    can slide into a hole while it presses (at 5 N sideways it could not). Its torques are
    limited by the motors only: the wrist's inertia needs far more than the free body's
    yaw servo gives.

    ``benchmarks/panda_validation.py`` measured the defaults against other gains.
    """

    stiffness: tuple[float, ...] = (20000.0,) * 6
    null: float = 20.0
    force_limit: tuple[float, float, float] = (4 * FORCE_LIMIT, 4 * FORCE_LIMIT, FORCE_LIMIT)

    def scaled(self, stiffness: float | None, force_limit: float | None) -> Gains:
        """These gains with the stiffness and the force limit times the given factors
        (``None``: unchanged), the damping still critical: a randomised draw's
        ``servo_gain`` and ``force_limit``."""
        return Gains(
            tuple(np.asarray(self.stiffness) * (stiffness or 1.0)),
            self.null,
            tuple(np.asarray(self.force_limit) * (force_limit or 1.0)),
        )

    @property
    def damping(self) -> np.ndarray:
        return 2.0 * np.sqrt(np.asarray(self.stiffness))


def grip_rotation(yaw: float) -> np.ndarray:
    """The grip frame pointing down with its x axis at ``yaw`` (the fingers close along y)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])  # columns x, z × x, z


class Arm:
    """The arm of a Panda world: its addresses, the grip site's Jacobian, IK and the law."""

    def __init__(self, model: mujoco.MjModel, gains: Gains | None = None) -> None:
        self.model, self.gains = model, gains or Gains()
        self.site = model.site(PREFIX + GRIP_SITE).id
        joints = [model.joint(PREFIX + name) for name in ARM_JOINTS]
        self.qpos = np.array([joint.qposadr[0] for joint in joints])
        self.dof = np.array([joint.dofadr[0] for joint in joints])
        self.range = model.jnt_range[[joint.id for joint in joints]]
        self.fingers = np.array([model.joint(PREFIX + name).qposadr[0] for name in FINGER_JOINTS])
        self.finger_motors = np.array([model.actuator(name).id for name in FINGER_ACTUATORS])
        self.motors = np.array([model.actuator(name).id for name in ARM_MOTORS])
        self.limit = model.actuator_ctrlrange[self.motors, 1]
        self.flange = model.site(PREFIX + FLANGE).id
        self.hand_mass = float(model.body_subtreemass[model.body(PREFIX + HAND).id])
        self.wrist_sensors = [model.sensor(name).adr[0] for name in (WRIST_FORCE, WRIST_TORQUE)]
        #: What the compiled law reads of the arm: the site, then qpos, dof and motor ids.
        self.index = np.concatenate([[self.site], self.qpos, self.dof, self.motors]).astype(np.intp)
        self._jac = np.zeros((6, model.nv))  # translation rows, then rotation rows
        self._kernels = None
        self._mass = np.zeros((model.nv, model.nv))
        self._block = np.ix_(self.dof, self.dof)
        self._identity = np.eye(len(self.dof))

    def error(self, data: mujoco.MjData, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """``[position error (mm), rotation error (rad)]`` of the grip site to ``pos``, ``rot``."""
        # Σᵢ cᵢ × rᵢ / 2 over the columns of the current and target frames: the vee of
        # the skew part of R* Rᵀ.
        turn = rot @ data.site_xmat[self.site].reshape(3, 3).T
        error = np.empty(6)
        error[:3] = pos - data.site_xpos[self.site]
        error[3:] = turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0], turn[1, 0] - turn[0, 1]
        error[3:] *= 0.5
        return error

    def jacobian(self, data: mujoco.MjData) -> np.ndarray:
        """The grip site's ``(6, 7)`` Jacobian over the arm's joints (mm and rad)."""
        mujoco.mj_jacSite(self.model, data, self._jac[:3], self._jac[3:], self.site)
        return self._jac[:, self.dof]

    def solve_ik(
        self, data: mujoco.MjData, pos: np.ndarray, rot: np.ndarray, iterations: int = 300
    ) -> np.ndarray:
        """Joint angles (from :data:`READY`, within the joint limits) that put the grip site
        at ``pos``, ``rot``; written into ``data.qpos`` and returned."""
        data.qpos[self.qpos] = READY
        scale = np.r_[np.full(3, 0.01), np.ones(3)]  # 100 mm weigh as 1 rad
        for _ in range(iterations):
            mujoco.mj_kinematics(self.model, data)
            mujoco.mj_comPos(self.model, data)
            error = self.error(data, pos, rot) * scale
            if np.linalg.norm(error) < 1e-12:
                return data.qpos[self.qpos].copy()
            jac = self.jacobian(data) * scale[:, None]
            step = jac.T @ np.linalg.solve(jac @ jac.T + 1e-8 * np.eye(6), error)
            data.qpos[self.qpos] = np.clip(data.qpos[self.qpos] + step, *self.range.T)
        mujoco.mj_kinematics(self.model, data)
        left = np.linalg.norm(self.error(data, pos, rot) * scale)
        if left > 1e-6:
            raise RuntimeError(
                f"no joint angles within the limits put the hand at {pos.tolist()} "
                f"(IK left {left:.3g}); allowed: a grasp inside the workspace"
            )
        return data.qpos[self.qpos].copy()

    def torques(
        self,
        data: mujoco.MjData,
        pos: np.ndarray,
        rot: np.ndarray,
        twist: np.ndarray,
        posture: np.ndarray,
    ) -> np.ndarray:
        """The law's joint torques (model units) toward ``pos``, ``rot`` moving at ``twist``
        (mm/s, rad/s), holding ``posture`` in the null space; within the torque limits (a
        batch of one: :meth:`batch_torques`)."""
        stacked = (np.asarray(v, dtype=float)[None] for v in (pos, rot, twist, posture))
        return self.batch_torques([data], *stacked)[0]

    def batch_torques(
        self,
        datas: list[mujoco.MjData],
        pos: np.ndarray,
        rot: np.ndarray,
        twist: np.ndarray,
        posture: np.ndarray,
        payload: float = 0.0,
        gains: Gains | None = None,
    ) -> np.ndarray:
        """:meth:`torques` of every simulation in ``datas`` (of this arm's model) at once,
        ``(n, 7)``: the Jacobians, mass matrices and errors read per simulation, the law's
        algebra in one stacked numpy pass (``pos`` ``(n, 3)``, ``rot`` ``(n, 3, 3)``,
        ``twist`` ``(n, 6)``, ``posture`` ``(n, 7)``); ``payload``: the mass (kg) held at
        the grip site, whose weight the law holds up; ``gains``: other than the arm's."""
        jac = np.stack([self.jacobian(data) for data in datas])
        mass = np.stack([self._arm_mass(data) for data in datas])
        error = np.stack(
            [self.error(data, p, r) for data, p, r in zip(datas, pos, rot, strict=True)]
        )
        q = np.stack([data.qpos[self.qpos] for data in datas])
        qdot = np.stack([data.qvel[self.dof] for data in datas])
        bias = np.stack([data.qfrc_bias[self.dof] for data in datas])
        inverse = np.linalg.inv(mass)
        jac_t = jac.transpose(0, 2, 1)
        task = np.linalg.inv(jac @ inverse @ jac_t)
        velocity = np.einsum("nij,nj->ni", jac, qdot)
        gains = gains or self.gains
        stiffness = np.asarray(gains.stiffness)
        pull = stiffness * error
        # The position error's pull along each axis within the limit over that axis's
        # task inertia; Λ then maps the clipped pull as a whole, so its cross terms still
        # keep the hand's orientation.
        most = np.asarray(gains.force_limit) / np.diagonal(task, axis1=1, axis2=2)[:, :3]
        pull[:, :3] = np.clip(pull[:, :3], -most, most)
        spring = np.einsum("nij,nj->ni", task, pull)
        damper = np.einsum("nij,nj->ni", task, gains.damping * (twist - velocity))
        held = np.zeros(6)
        held[:3] = -payload * GRAVITY
        consistent = inverse @ jac_t @ task
        null = self._identity - jac_t @ consistent.transpose(0, 2, 1)
        rate = gains.null
        hold = np.einsum("nij,nj->ni", mass, rate * (posture - q) - 2.0 * np.sqrt(rate) * qdot)
        tau = (
            np.einsum("nij,nj->ni", jac_t, spring + damper + held)
            + np.einsum("nij,nj->ni", null, hold)
            + bias
        )
        return np.clip(tau, -self.limit, self.limit)

    def law_gains(self, gains: Gains, payload: float) -> np.ndarray:
        """``gains`` and the weight of ``payload`` (kg) as the compiled law reads them."""
        stiffness = np.asarray(gains.stiffness, dtype=float)
        held = -payload * GRAVITY
        return pack_gains(stiffness, gains.damping, np.asarray(gains.force_limit), gains.null, held)

    def apply_law(
        self,
        model: mujoco.MjModel,
        inputs: LawInputs,
        state: np.ndarray,
        gains: np.ndarray,
        advance: float = 0.0,
        bounds: np.ndarray | None = None,
    ) -> None:
        """Set the simulation's motors to the compiled law's torques (:meth:`batch_torques`
        within rounding, :func:`~tolins.physics.compiled_law.law_torques`): ``state`` its
        target, yaw, twist and posture (:data:`STATE`), first
        moved ``advance`` s along the twist within ``bounds``; ``gains`` of
        :meth:`law_gains`."""
        data = inputs.data
        mujoco.mj_jacSite(model, data, inputs.jacp, inputs.jacr, self.site)
        mujoco.mj_fullM(model, data, inputs.full)
        bounds = _UNBOUNDED if bounds is None else bounds
        if self._kernels is None:
            from tolins.physics import compiled_law

            self._kernels = compiled_law
        self._kernels.law_torques(
            inputs.jac,
            inputs.full,
            *inputs.arrays,
            self.index,
            gains,
            state,
            self.limit,
            advance,
            bounds,
        )

    def _arm_mass(self, data: mujoco.MjData) -> np.ndarray:
        """The arm's ``(7, 7)`` block of the joint-space inertia (a copy)."""
        mujoco.mj_fullM(self.model, data, self._mass)
        return self._mass[self._block]


_UNBOUNDED = np.array([[-np.inf] * 4, [np.inf] * 4])


class LawInputs:
    """What the compiled law reads and writes of one simulation's data, bound once (MuJoCo's
    arrays are views of the data's memory), with the law's scratch matrices."""

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        self.data = data
        self.arrays = (data.qpos, data.qvel, data.site_xpos, data.site_xmat, data.qfrc_bias)
        self.arrays += (data.ctrl,)
        self.jac = np.zeros((6, model.nv))
        self.jacp, self.jacr = self.jac[:3], self.jac[3:]
        self.full = np.zeros((model.nv, model.nv))


def place_grasp(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    arm: Arm,
    pose: np.ndarray,
    offset: np.ndarray | None = None,
    plasticity: PinPlasticity | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reset ``data`` with the hand around the handle of a part at ``pose`` ``[x, y, theta,
    z]`` (tips' height z; fingers 1 mm off each side), the fingers open. With ``offset``
    ``[dx, dy, dyaw]`` (mm, rad, in the grip frame) the part sits that far off in the hand:
    at ``pose`` moved by the offset, where the robot believes it at ``pose``; its
    elastic-plastic pins (``plasticity``) at rest at their plastic set. Returns the grip
    site's target position, rotation and the posture (the IK's joint angles)."""
    mujoco.mj_resetData(model, data)
    if plasticity is not None:
        plasticity.place(data.qpos, data.qvel)
    x, y, theta, z = (float(v) for v in pose)
    dx, dy, dyaw = (0.0, 0.0, 0.0) if offset is None else (float(v) for v in offset)
    c, s = np.cos(theta), np.sin(theta)
    part = model.joint("workpiece").qposadr[0]
    data.qpos[part : part + 3] = x + c * dx - s * dy, y + s * dx + c * dy, z
    yaw = theta + dyaw
    data.qpos[part + 3 : part + 7] = np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)
    target = np.array([x, y, z + handle_centre_height()])
    rot = grip_rotation(theta)
    posture = arm.solve_ik(data, target, rot)
    data.qpos[arm.fingers] = HANDLE[1] + 1.0
    mujoco.mj_forward(model, data)
    return target, rot, posture


def close_fingers(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    arm: Arm,
    force: float,
    seconds: float,
    every: int,
    law: Callable[[], None],
    plasticity: PinPlasticity | None = None,
) -> None:
    """Close the fingers on the part with ``force`` (N) each for ``seconds``, ``law()``
    setting the arm's torques before every ``every`` physics steps, with gravity off: the
    part floats where :func:`place_grasp` put it until the pads hold it, so the grasp
    starts where the robot believes it (a part held by a soft constraint instead is
    pushed tens of µm off by the closing fingers and keeps the offset). Gravity, in
    ``model``, is back on when it returns; ``law`` must not compensate the part's weight
    meanwhile. ``plasticity``: the part's elastic-plastic pins (:func:`run_plan`'s)."""
    gravity = model.opt.gravity.copy()
    model.opt.gravity[:] = 0.0
    try:
        data.ctrl[arm.finger_motors] = -force / FORCE_SCALE
        steps = round(seconds / model.opt.timestep)
        plan = [(min(every, steps - start), True, False) for start in range(0, steps, every)]
        run_plan(model, data, plan, law, _nothing, plasticity)
    finally:
        model.opt.gravity[:] = gravity
    mujoco.mj_forward(model, data)


def _nothing() -> None:
    pass


def nominal_pose(data: mujoco.MjData, arm: Arm) -> np.ndarray:
    """The part's pose ``[x, y, theta, z]`` (mm, rad) as the robot believes it: the grip
    site's forward kinematics, the part held as :func:`place_grasp` put it (its handle's
    centre at the site, its z axis against the site's)."""
    frame = data.site_xmat[arm.site].reshape(3, 3)
    tips = data.site_xpos[arm.site] + frame @ np.array([0.0, 0.0, handle_centre_height()])
    theta = float(np.arctan2(frame[1, 0], frame[0, 0]))
    return np.array([tips[0], tips[1], theta, tips[2]])


def wrist_wrench(data: mujoco.MjData, arm: Arm, held_mass: float) -> np.ndarray:
    """``[Fx, Fy, q_theta, Fz]`` (N, N·mm, world axes) the board exerts on the part, as a
    wrist sensor tells it: the flange's force and torque in world axes, less the weight of
    the hand, its fingers and ``held_mass`` (kg) (in equilibrium, what the flange does not
    hold up the board does)."""
    frame = data.site_xmat[arm.flange].reshape(3, 3)
    force_at, torque_at = arm.wrist_sensors
    force = (
        -(arm.hand_mass + held_mass) * GRAVITY - frame @ data.sensordata[force_at : force_at + 3]
    )
    torque = -(frame @ data.sensordata[torque_at : torque_at + 3])
    return np.array([force[0], force[1], torque[2], force[2]]) * FORCE_SCALE
