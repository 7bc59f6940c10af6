"""A first look at a Franka Panda holding the workpiece: grasp, task-space control, cost.

Usage::

    python benchmarks/panda_feasibility.py [--rate 500] [--seconds 3]

Builds :func:`tolins.mjcf.panda.panda_world` for the 2*2 socket (gymnasium-robotics'
Panda in mm; the workpiece on a free joint with a 12 × 16 × 20 mm handle on its carrier),
places the grasp (:func:`tolins.physics.arm.place_grasp`: IK within the joint limits) and
closes the fingers on it with 20 N each, the part weightless meanwhile
(:func:`tolins.physics.arm.close_fingers`): from there friction alone holds the part. The
operational-space law of :class:`tolins.physics.arm.Arm` runs at ``--rate`` Hz with the
physics stepping between updates: it holds the pose for half the run, then tracks a
descent at 2.5 mm/s (the paper's a_max). Printed: how far the part slipped in the hand,
the tracking error of the grip site, and the wall time per physics step (``mj_step``, and
``mj_step`` with the controller's share; the measuring itself not counted) against the
free-floating workpiece's servo model stepped side by side (goal: ≤ 2×). Then pushes:
the part held over the board, 1 mm off the holes, its target lowered 0.5, 1 and 2 mm
below the contact, the board's push on the pins (their force sensor) against the wrist's
estimate, and the part's slip in the hand.

The parts of the Panda ids one at a time; ``panda_validation.py`` runs the ids themselves.
"""

from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np

import tolins
from tolins.mjcf import FORCE_SCALE, make_mjcf
from tolins.mjcf.panda import panda_world
from tolins.physics.arm import Arm, close_fingers, nominal_pose, place_grasp, wrist_wrench
from tolins.physics.panda import GRIP_FORCE, SETTLE

START = np.array([0.5, -0.3, 0.0, 17.0])  # the part's pose [x, y, theta, z] (mm, rad)


def grasp_run(rate: int, seconds: float) -> dict[str, float]:
    model = panda_world(tolins.CircularSocket(2, 2)).compile()
    data, arm = mujoco.MjData(model), Arm(model)
    target, rot, posture = place_grasp(model, data, arm, START)
    part = model.joint("workpiece").qposadr[0]
    dt = model.opt.timestep
    steps, every = round(seconds / dt), round(1 / (rate * dt))
    settle, descend = round(SETTLE / dt), steps // 2
    twist, offsets, errors = np.zeros(6), [], {"hold": [], "descend": []}

    def hold() -> None:
        data.ctrl[arm.motors] = arm.torques(data, target, rot, twist, posture)

    close_fingers(model, data, arm, GRIP_FORCE, SETTLE, every, hold)
    physics = control = 0.0
    for k in range(settle, steps):
        if k % every == 0:
            if k >= descend:
                twist = np.array([0, 0, -2.5, 0, 0, 0])
                target = target + twist[:3] * every * dt
            tick = time.perf_counter()
            data.ctrl[arm.motors] = arm.torques(data, target, rot, twist, posture)
            control += time.perf_counter() - tick
        tick = time.perf_counter()
        mujoco.mj_step(model, data)
        physics += time.perf_counter() - tick
        offsets.append(data.qpos[part : part + 3] - data.site_xpos[arm.site])
        phase = "descend" if k >= descend else "hold"
        errors[phase].append(np.linalg.norm(arm.error(data, target, rot)[:3]))
    timed = steps - settle
    return {
        "us_per_step": (physics + control) / timed * 1e6,
        "physics_us_per_step": physics / timed * 1e6,
        "slip_mm": float(np.linalg.norm(offsets[-1] - offsets[0])),
        "hold_error_mm": float(np.max(errors["hold"][len(errors["hold"]) // 2 :])),
        "descend_error_mm": float(np.max(errors["descend"])),
        "warnings": int(sum(w.number for w in data.warning)),
    }


def push_run(depth: float, rate: int = 500) -> dict[str, float]:
    """The part held 1 mm off the 2*2's holes, 2 mm over the board, then its target
    ``depth`` mm lower over 1 s and held there for 1 s: the board's push on the pins
    (their force sensor) against what the wrist tells (:func:`wrist_wrench`), averaged
    over the last 0.5 s, and the part's slip in the hand (its true pose against
    :func:`nominal_pose`)."""
    model = panda_world(tolins.CircularSocket(2, 2)).compile()
    data, arm = mujoco.MjData(model), Arm(model)
    target, rot, posture = place_grasp(model, data, arm, np.array([1.0, 0.0, 0.0, 2.0]))
    held = model.body_subtreemass[model.body("workpiece").id]
    pins = model.site("ft_site").id
    part = model.joint("workpiece").qposadr[0]
    dt = model.opt.timestep
    every, true, wrist = round(1 / (rate * dt)), [], []

    def hold() -> None:
        data.ctrl[arm.motors] = arm.torques(data, target, rot, np.zeros(6), posture)

    close_fingers(model, data, arm, GRIP_FORCE, SETTLE, every, hold)
    for k in range(round(SETTLE / dt), round(2.5 / dt)):
        if k % every == 0:
            lowered = min(max(k * dt - 0.5, 0.0), 1.0) * depth
            goal = target - np.array([0.0, 0.0, lowered])
            data.ctrl[arm.motors] = arm.torques(data, goal, rot, np.zeros(6), posture)
        mujoco.mj_step(model, data)
        if k * dt >= 2.0:
            frame = data.site_xmat[pins].reshape(3, 3)
            true.append(-(frame @ data.sensor("force").data) * FORCE_SCALE)
            wrist.append(wrist_wrench(data, arm, held)[[0, 1, 3]])
    slip = nominal_pose(data, arm)[[0, 1, 3]] - data.qpos[part : part + 3]
    true_mean, wrist_mean = np.mean(true, axis=0), np.mean(wrist, axis=0)
    return {
        "true_z": float(true_mean[2]),
        "wrist_z": float(wrist_mean[2]),
        "largest_difference": float(np.max(np.abs(np.array(wrist) - np.array(true)))),
        "slip_mm": float(np.linalg.norm(slip)),
    }


def law_cost(n: int, repeats: int = 2000) -> float:
    """µs per simulation of one update of the law over a batch of ``n`` grasped Pandas
    (:meth:`~tolins.physics.arm.Arm.batch_torques`)."""
    model = panda_world(tolins.CircularSocket(2, 2)).compile()
    arm, datas = Arm(model), [mujoco.MjData(model) for _ in range(n)]
    targets = [place_grasp(model, data, arm, START) for data in datas]
    pos, rot, posture = (np.stack([t[i] for t in targets]) for i in range(3))
    twist, rounds = np.zeros((n, 6)), max(repeats // n, 20)
    began = time.perf_counter()
    for _ in range(rounds):
        arm.batch_torques(datas, pos, rot, twist, posture)
    return (time.perf_counter() - began) / rounds / n * 1e6


def free_body_run(seconds: float) -> float:
    """Wall time per physics step (µs) of the 2*2's servo-driven workpiece descending."""
    model = mujoco.MjModel.from_xml_string(make_mjcf(tolins.CircularSocket(2, 2)))
    data = mujoco.MjData(model)
    data.qpos[2] = data.act[2] = 17.0
    data.ctrl[2] = -2.5
    steps = round(seconds / model.opt.timestep)
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
        "\n| target below the contact (mm) | board's push Fz (N) | wrist's Fz (N) | largest "
        "difference, any axis (N) | slip in the hand (mm) |\n|--:|--:|--:|--:|--:|"
    )
    for depth in (2.5, 3.0, 4.0):
        push = push_run(depth, args.rate)
        print(
            f"| {depth - 2.0:.1f} | {push['true_z']:.3f} | {push['wrist_z']:.3f} "
            f"| {push['largest_difference']:.3f} | {push['slip_mm']:.3f} |"
        )
    print("\n| simulations in the batch | µs per simulation and update of the law |\n|--:|--:|")
    for n in (1, 8, 32, 128):
        print(f"| {n} | {law_cost(n):.1f} |")
    print(
        f"\nslip of the part in the hand once the fingers hold it: {panda['slip_mm']:.3f} mm; "
        f"grip-site error holding: {panda['hold_error_mm']:.3f} mm, descending at 2.5 mm/s: "
        f"{panda['descend_error_mm']:.3f} mm; MuJoCo warnings: {panda['warnings']}"
    )


if __name__ == "__main__":
    main()
