"""A first look at a Franka Panda holding the workpiece: grasp, task-space control, cost.

Usage::

    python benchmarks/panda_feasibility.py [--rate 500] [--seconds 3]

Builds the Panda of :mod:`tolins.mjcf.panda` (gymnasium-robotics' model, in mm) beside the
2*2 socket of :func:`tolins.make_mjcf`, its workpiece on a free joint with a 12 × 16 ×
20 mm handle on the carrier. Places the hand over the handle by damped-least-squares IK
(joint limits kept), welds the part to the hand while the fingers close with 20 N each,
then releases the weld: from there friction alone holds the part. An operational-space
controller written here (a unit-mass task-space law: ``Λ (Kp e + Kd (v* − v))``, with
``Λ`` the task-space inertia, null-space posture, gravity and Coriolis compensation from
``qfrc_bias``, torques clipped to the Franka's limits) runs at ``--rate`` Hz with the
physics stepping between updates: it holds the pose for half the run, then tracks a
descent at 2.5 mm/s (the paper's a_max). Printed: how far the part slipped in the hand,
the tracking error of the grip site, and the wall time per physics step (``mj_step``, and
``mj_step`` with the controller's share; the measuring itself not counted) against the
free-floating workpiece's servo model stepped side by side (goal: ≤ 2×).

Not yet in tolins: a first measurement for the robot embodiment (the Panda ids, their
control, sensing and validation are open work).
"""

from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np

import tolins
from tolins.geometry.workspace import PIN_LENGTH
from tolins.mjcf import make_mjcf
from tolins.mjcf.model import CARRIER_THICKNESS
from tolins.mjcf.panda import ARM_JOINTS, FINGER_JOINTS, GRAVITY, GRIP_SITE, panda_spec

PREFIX = "panda/"
HANDLE = np.array([6.0, 8.0, 10.0])  # half sizes (mm)
BASE = (-450.0, 0.0, -60.0)  # the arm's base relative to the board's top centre (mm)
READY = np.array([0, -0.785, 0, -2.356, 0, 1.571, 0.785])
GRIP_FORCE = 20.0e3  # per finger, mN
GAIN = 2000.0  # Kp (1/s²) on every task-space axis; Kd = 2 √Kp
POSTURE_GAIN = 20.0


def world_model(socket: tolins.CircularSocket) -> mujoco.MjModel:
    """The socket's board, its workpiece on a free joint with a handle, and the Panda."""
    world = mujoco.MjSpec.from_string(make_mjcf(socket))
    workpiece = world.body("workpiece")
    for joint in list(workpiece.joints):
        world.delete(joint)
    for actuator in list(world.actuators):
        world.delete(actuator)
    workpiece.add_freejoint(name="workpiece")
    workpiece.add_geom(
        name="handle",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=HANDLE,
        pos=[0, 0, PIN_LENGTH + CARRIER_THICKNESS + HANDLE[2]],
        contype=2,
        conaffinity=1,
        mass=0.05,
        friction=[1.0, 0.005, 0.0001],
    )
    world.add_equality(
        type=mujoco.mjtEq.mjEQ_WELD,
        name="hold",
        name1="workpiece",
        name2=PREFIX + "panda0_link7",
        objtype=mujoco.mjtObj.mjOBJ_BODY,
    )
    world.option.gravity = GRAVITY
    panda = panda_spec()
    panda.option.timestep = world.option.timestep
    for actuator in panda.actuators:
        actuator.userdata = []
    panda.nuser_actuator = -1
    for geom in panda.geoms:  # the arm touches nothing of the task; the fingers the part
        finger = geom.parent.name.endswith("finger")
        geom.contype, geom.conaffinity = (1, 2) if finger else (0, 0)
        if finger:
            geom.friction = [1.0, 0.005, 0.0001]
    world.attach(panda, prefix=PREFIX, frame=world.worldbody.add_frame(pos=BASE))
    return world.compile()


def down(yaw: float) -> np.ndarray:
    """The grip frame pointing down, its x axis at ``yaw`` (fingers close along its y)."""
    x = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    z = np.array([0.0, 0.0, -1.0])
    return np.column_stack([x, np.cross(z, x), z])


class Arm:
    """The arm's addresses, its grip-site Jacobian, IK and the task-space control law."""

    def __init__(self, model: mujoco.MjModel) -> None:
        self.model = model
        self.site = model.site(PREFIX + GRIP_SITE).id
        joints = [model.joint(PREFIX + name) for name in ARM_JOINTS]
        self.qpos = np.array([j.qposadr[0] for j in joints])
        self.dof = np.array([j.dofadr[0] for j in joints])
        self.range = model.jnt_range[[j.id for j in joints]]
        self.fingers = np.array([model.joint(PREFIX + n).qposadr[0] for n in FINGER_JOINTS])
        self.limit = model.actuator_ctrlrange[:7, 1]
        self._jp, self._jr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
        self._mass = np.zeros((model.nv, model.nv))

    def error(self, data: mujoco.MjData, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """``[position error (mm), rotation error (rad)]`` of the grip site."""
        current = data.site_xmat[self.site].reshape(3, 3)
        spin = 0.5 * sum(np.cross(current[:, i], rot[:, i]) for i in range(3))
        return np.r_[pos - data.site_xpos[self.site], spin]

    def jacobian(self, data: mujoco.MjData) -> np.ndarray:
        mujoco.mj_jacSite(self.model, data, self._jp, self._jr, self.site)
        return np.vstack([self._jp[:, self.dof], self._jr[:, self.dof]])

    def solve_ik(self, data: mujoco.MjData, pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
        """Joint angles putting the grip site at ``pos``, ``rot`` (from :data:`READY`)."""
        data.qpos[self.qpos] = READY
        scale = np.r_[np.full(3, 0.01), np.ones(3)]  # mm against rad
        for _ in range(300):
            mujoco.mj_kinematics(self.model, data)
            mujoco.mj_comPos(self.model, data)
            error = self.error(data, pos, rot) * scale
            if np.linalg.norm(error) < 1e-12:
                break
            jac = self.jacobian(data) * scale[:, None]
            step = jac.T @ np.linalg.solve(jac @ jac.T + 1e-8 * np.eye(6), error)
            data.qpos[self.qpos] = np.clip(data.qpos[self.qpos] + step, *self.range.T)
        return data.qpos[self.qpos].copy()

    def torques(
        self, data: mujoco.MjData, pos: np.ndarray, rot: np.ndarray, vel: np.ndarray, posture
    ) -> np.ndarray:
        """The operational-space law: ``Jᵀ Λ (Kp e + Kd (v* − v)) + N (posture) + bias``."""
        jac = self.jacobian(data)
        mujoco.mj_fullM(self.model, data, self._mass)
        mass = self._mass[np.ix_(self.dof, self.dof)]
        inverse = np.linalg.inv(mass)
        task = np.linalg.inv(jac @ inverse @ jac.T + 1e-9 * np.eye(6))
        velocity = jac @ data.qvel[self.dof]
        wrench = GAIN * self.error(data, pos, rot) + 2 * np.sqrt(GAIN) * (vel - velocity)
        dynamic = inverse @ jac.T @ task  # the dynamically consistent pseudo-inverse
        null = np.eye(7) - jac.T @ dynamic.T
        qerr, qdot = posture - data.qpos[self.qpos], data.qvel[self.dof]
        hold = mass @ (POSTURE_GAIN * qerr - 2 * np.sqrt(POSTURE_GAIN) * qdot)
        tau = jac.T @ (task @ wrench) + null @ hold + data.qfrc_bias[self.dof]
        return np.clip(tau, -self.limit, self.limit)


def grasp_run(rate: int, seconds: float) -> dict[str, float]:
    model = world_model(tolins.CircularSocket(2, 2))
    data, arm = mujoco.MjData(model), Arm(model)
    part = model.joint("workpiece").qposadr[0]
    start = np.array([0.5, -0.3, 17.0])  # the pin tips' pose (mm)
    data.qpos[part : part + 3], data.qpos[part + 3 : part + 7] = start, [1, 0, 0, 0]
    target = start + [0, 0, PIN_LENGTH + CARRIER_THICKNESS + HANDLE[2]]
    rot = down(0.0)
    posture = arm.solve_ik(data, target, rot)
    data.qpos[arm.fingers] = HANDLE[1] + 1.0
    mujoco.mj_forward(model, data)
    hold = model.equality("hold").id
    hand, body = model.body(PREFIX + "panda0_link7").id, model.body("workpiece").id
    inverse, relative = np.zeros(4), np.zeros(4)
    mujoco.mju_negQuat(inverse, data.xquat[hand])
    mujoco.mju_mulQuat(relative, inverse, data.xquat[body])
    hand_frame = data.xmat[hand].reshape(3, 3)
    model.eq_data[hold, 3:6] = hand_frame.T @ (data.xpos[body] - data.xpos[hand])
    model.eq_data[hold, 6:10], model.eq_data[hold, 10] = relative, 1.0
    fingers = [
        model.actuator(PREFIX + n).id for n in ("r_gripper_finger_joint", "l_gripper_finger_joint")
    ]
    steps = int(round(seconds / model.opt.timestep))
    every = int(round(1 / (rate * model.opt.timestep)))
    settle, descend = int(0.6 / model.opt.timestep), steps // 2
    vel, offsets, errors = np.zeros(6), [], {"hold": [], "descend": []}
    physics = control = 0.0
    for k in range(steps):
        if k % every == 0:
            if k >= descend:
                vel = np.array([0, 0, -2.5, 0, 0, 0])
                target = target + vel[:3] * every * model.opt.timestep
            tick = time.perf_counter()
            data.ctrl[:7] = arm.torques(data, target, rot, vel, posture)
            control += time.perf_counter() - tick
        data.ctrl[fingers] = -GRIP_FORCE if k > 100 else 0.0
        data.eq_active[hold] = k < settle
        tick = time.perf_counter()
        mujoco.mj_step(model, data)
        physics += time.perf_counter() - tick
        if k >= settle:
            offsets.append(data.qpos[part : part + 3] - data.site_xpos[arm.site])
            phase = "descend" if k >= descend else "hold"
            errors[phase].append(np.linalg.norm(arm.error(data, target, rot)[:3]))
    offsets = np.array(offsets)
    return {
        "us_per_step": (physics + control) / steps * 1e6,
        "physics_us_per_step": physics / steps * 1e6,
        "slip_mm": float(np.linalg.norm(offsets[-1] - offsets[0])),
        "hold_error_mm": float(np.max(errors["hold"][len(errors["hold"]) // 2 :])),
        "descend_error_mm": float(np.max(errors["descend"])),
        "warnings": int(sum(w.number for w in data.warning)),
    }


def free_body_run(seconds: float) -> float:
    """Wall time per physics step (µs) of the 2*2's servo-driven workpiece descending."""
    model = mujoco.MjModel.from_xml_string(make_mjcf(tolins.CircularSocket(2, 2)))
    data = mujoco.MjData(model)
    data.qpos[2] = data.act[2] = 17.0
    data.ctrl[2] = -2.5
    steps = int(round(seconds / model.opt.timestep))
    began = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(model, data)
    return (time.perf_counter() - began) / steps * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=int, default=500, help="controller updates per second")
    parser.add_argument("--seconds", type=float, default=3.0)
    args = parser.parse_args()
    free = free_body_run(args.seconds)
    panda = grasp_run(args.rate, args.seconds)
    rows = [
        ("free workpiece on servos (2*2, free flight)", free),
        ("Panda holding it: mj_step only", panda["physics_us_per_step"]),
        (f"Panda holding it: mj_step and the controller at {args.rate} Hz", panda["us_per_step"]),
    ]
    print("| model | µs per physics step | ratio |\n|---|--:|--:|")
    for name, value in rows:
        print(f"| {name} | {value:.1f} | {value / free:.2f} |")
    print(
        f"\nslip of the part in the hand after the weld's release: {panda['slip_mm']:.3f} mm; "
        f"grip-site error holding: {panda['hold_error_mm']:.3f} mm, descending at 2.5 mm/s: "
        f"{panda['descend_error_mm']:.3f} mm; MuJoCo warnings: {panda['warnings']}"
    )


if __name__ == "__main__":
    main()
