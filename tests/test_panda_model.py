"""The Franka Panda in tolins' units: the scaled model is the metre model, in mm."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from tolins.mjcf.panda import (
    ARM_JOINTS,
    FINGER_JOINTS,
    GRIP_SITE,
    MM_PER_M,
    panda_spec,
    panda_spec_in_metres,
)

MM = MM_PER_M


@pytest.fixture(scope="module")
def models() -> tuple[mujoco.MjModel, mujoco.MjModel]:
    return panda_spec_in_metres().compile(), panda_spec().compile()


def _poses(seed: int, metres: mujoco.MjModel) -> np.ndarray:
    low, high = metres.jnt_range[:, 0], metres.jnt_range[:, 1]
    return np.random.default_rng(seed).uniform(low, high)


@pytest.mark.parametrize("seed", range(3))
def test_the_mm_model_is_the_metre_model_in_mm(models, seed: int) -> None:
    metres, mm = models
    assert [mm.joint(i).name for i in range(mm.njnt)] == [*ARM_JOINTS, *FINGER_JOINTS]
    assert mm.body_mass.sum() == pytest.approx(metres.body_mass.sum(), rel=1e-12)
    q = _poses(seed, metres)
    unit = np.r_[np.ones(7), MM, MM]  # hinges in rad, the finger slides in m → mm
    d_m, d_mm = mujoco.MjData(metres), mujoco.MjData(mm)
    d_m.qpos[:], d_mm.qpos[:] = q, q * unit
    d_m.qvel[:] = d_mm.qvel[:] = 0.0
    mujoco.mj_forward(metres, d_m)
    mujoco.mj_forward(mm, d_mm)
    np.testing.assert_allclose(d_mm.site(GRIP_SITE).xpos, d_m.site(GRIP_SITE).xpos * MM, atol=1e-9)
    np.testing.assert_allclose(d_mm.site(GRIP_SITE).xmat, d_m.site(GRIP_SITE).xmat, atol=1e-12)
    # Gravity torques: N·m → kg·mm²/s² (× 1e6) on the hinges, N → mN on the fingers.
    bias = d_m.qfrc_bias * np.r_[np.full(7, MM**2), MM, MM]
    np.testing.assert_allclose(d_mm.qfrc_bias, bias, rtol=1e-9, atol=1e-6 * np.abs(bias).max())
    # The joint-space inertia of the arm: kg·m² → kg·mm².
    full_m, full_mm = np.zeros((9, 9)), np.zeros((9, 9))
    mujoco.mj_fullM(metres, d_m, full_m)
    mujoco.mj_fullM(mm, d_mm, full_mm)
    np.testing.assert_allclose(full_mm[:7, :7], full_m[:7, :7] * MM**2, rtol=1e-9, atol=1e-3)


def test_the_arm_is_torque_driven_within_the_frankas_limits(models) -> None:
    _, mm = models
    torque_limit = np.r_[np.full(4, 87.0), np.full(3, 12.0)] * MM**2  # N·m in kg·mm²/s²
    np.testing.assert_allclose(mm.actuator_ctrlrange[:7, 1], torque_limit)
    np.testing.assert_allclose(mm.actuator_ctrlrange[7:, 1], 70.0 * MM)  # 70 N per finger
    assert np.all(mm.actuator_biastype == mujoco.mjtBias.mjBIAS_NONE)
    # A motor's force is its control: one N·m on joint 4 accelerates it as M⁻¹ says.
    data = mujoco.MjData(mm)
    data.qpos[3] = -1.5
    mujoco.mj_forward(mm, data)
    free = data.qacc.copy()
    data.ctrl[3] = 1.0 * MM**2
    mujoco.mj_forward(mm, data)
    unit = np.zeros(mm.nv)
    unit[3] = MM**2
    expected = np.zeros(mm.nv)
    mujoco.mj_solveM(mm, data, expected.reshape(1, -1), unit.reshape(1, -1))
    np.testing.assert_allclose(data.qacc - free, expected, rtol=1e-6, atol=1e-9)


def test_the_fingers_hold_the_part_by_friction_under_the_task_space_law() -> None:
    import tolins
    from tolins.mjcf.panda import WRIST_FORCE, panda_world
    from tolins.physics.arm import Arm, close_fingers, place_grasp

    model = panda_world(tolins.CircularSocket(2, 2)).compile()
    data, arm = mujoco.MjData(model), Arm(model)
    assert not model.geom_contype[model.geom_bodyid == model.body("panda/panda0_link3").id].any()
    target, rot, posture = place_grasp(model, data, arm, np.array([0.5, -0.3, 0.05, 17.0]))
    np.testing.assert_allclose(arm.error(data, target, rot), 0.0, atol=1e-6)
    part = model.joint("workpiece").qposadr[0]
    dt, every = model.opt.timestep, 2  # the law at 500 Hz
    hold = np.zeros(6)

    def law() -> None:
        data.ctrl[arm.motors] = arm.torques(data, target, rot, hold, posture)

    close_fingers(model, data, arm, 20.0, 0.2, every, law)  # 20 N each, weightless
    placed = data.qpos[part : part + 3] - data.site_xpos[arm.site]
    offsets, errors = [], []
    for k in range(1100):  # then friction alone holds it
        if k % every == 0:
            if k >= 600:  # then descend at the paper's a_max
                target = target + np.array([0.0, 0.0, -2.5]) * every * dt
            twist = np.r_[0.0, 0.0, -2.5 if k >= 600 else 0.0, 0.0, 0.0, 0.0]
            data.ctrl[arm.motors] = arm.torques(data, target, rot, twist, posture)
        mujoco.mj_step(model, data)
        offsets.append(data.qpos[part : part + 3] - data.site_xpos[arm.site])
        errors.append(np.linalg.norm(arm.error(data, target, rot)[:3]))
    assert sum(w.number for w in data.warning) == 0
    # Held in the air, the wrist reads the weight of the hand, the fingers and the part.
    hand = model.body("panda/panda0_hand").id
    below = model.body_subtreemass[hand] + model.body_subtreemass[model.body("workpiece").id]
    force = data.sensor(WRIST_FORCE).data
    wrist_frame = data.site_xmat[model.site("panda/flange").id].reshape(3, 3)
    np.testing.assert_allclose(wrist_frame @ force, [0.0, 0.0, below * 9810.0], rtol=0.02, atol=5.0)
    # The closing fingers leave the part where it was placed, under the grip site (the
    # pads meet the handle's faces square; measured: 2.4 µm and 0.1 µm).
    np.testing.assert_allclose(placed[:2], [0.0, 0.0], atol=5e-3)
    slip = np.linalg.norm(np.array(offsets[-1]) - offsets[0])
    assert slip < 0.1  # mm: the part stays in the hand under gravity (0.018 measured)
    assert max(errors) < 1.0  # mm, holding and descending at 2.5 mm/s
    # It descended with the hand: 1.25 mm commanded, less the law's lag (< 1 mm).
    assert 17.0 - 1.25 - 1.0 < data.qpos[part + 2] < 17.0 - 0.25


def test_the_wrist_tells_the_push_on_the_board_and_kinematics_the_pose() -> None:
    import tolins
    from tolins.mjcf import FORCE_SCALE
    from tolins.mjcf.panda import HANDLE_MASS, panda_world
    from tolins.physics.arm import Arm, close_fingers, nominal_pose, place_grasp, wrist_wrench

    model = panda_world(tolins.CircularSocket(2, 2)).compile()
    data, arm = mujoco.MjData(model), Arm(model)
    start = np.array([1.0, 0.0, 0.0, 2.0])  # 1 mm off the holes: the pins land on the board
    target, rot, posture = place_grasp(model, data, arm, start)
    np.testing.assert_allclose(nominal_pose(data, arm), start, atol=1e-6)
    part = model.body("workpiece").id
    held = model.body_subtreemass[part]
    assert held == pytest.approx(0.1 + 0.001 + HANDLE_MASS)
    pins = model.site("ft_site").id
    readings = []

    def hold() -> None:
        data.ctrl[arm.motors] = arm.torques(data, target, rot, np.zeros(6), posture)

    close_fingers(model, data, arm, 20.0, 0.2, 2, hold)
    for k in range(2500):
        if k % 2 == 0:
            depth = (
                min(max(k - 500, 0) / 1000, 1.0) * 3.0
            )  # 3 mm down over 1 s: 1 mm into the board
            goal = target - np.array([0.0, 0.0, depth])
            data.ctrl[arm.motors] = arm.torques(data, goal, rot, np.zeros(6), posture)
        mujoco.mj_step(model, data)
        if k >= 2000:  # held 1 mm below the contact: a quasi-static push
            frame = data.site_xmat[pins].reshape(3, 3)
            true = -(frame @ data.sensor("force").data) * FORCE_SCALE  # board on the pins (N)
            readings.append((wrist_wrench(data, arm, held)[[0, 1, 3]], true))
    wrist, true = (np.mean([r[i] for r in readings], axis=0) for i in range(2))
    assert true[2] > 1.0  # N: the pins press on the board
    np.testing.assert_allclose(wrist, true, rtol=0.05, atol=0.05)
    # The kinematics see the part where it is, up to its slip in the hand under the push.
    pose = data.qpos[model.joint("workpiece").qposadr[0] :][:3]
    slip = nominal_pose(data, arm)[[0, 1, 3]] - pose
    # (measured: 0.038 mm under a 6.2 N push, the wrist reading it to 0.01 N)
    assert np.linalg.norm(slip) < 0.1


def test_the_law_over_a_batch_is_the_law_of_each_simulation() -> None:
    import tolins
    from tolins.mjcf.panda import panda_world
    from tolins.physics.arm import Arm, place_grasp

    model = panda_world(tolins.CircularSocket(2, 2)).compile()
    arm = Arm(model)
    datas = [mujoco.MjData(model) for _ in range(3)]
    poses = ([0.5, -0.3, 0.05, 17.0], [-1.0, 0.8, -0.1, 15.0], [0.0, 0.0, 0.0, 16.0])
    targets = [
        place_grasp(model, data, arm, np.array(p)) for data, p in zip(datas, poses, strict=True)
    ]
    rng = np.random.default_rng(0)
    for data in datas:  # away from the targets, moving: every term of the law matters
        data.qpos[arm.qpos] += rng.normal(0.0, 0.02, 7)
        data.qvel[arm.dof] = rng.normal(0.0, 0.1, 7)
        mujoco.mj_forward(model, data)
    pos, rot, posture = (np.stack([t[i] for t in targets]) for i in range(3))
    twist = rng.normal(0.0, 1.0, (3, 6))
    batch = arm.batch_torques(datas, pos, rot, twist, posture)
    for i, data in enumerate(datas):
        single = arm.torques(data, pos[i], rot[i], twist[i], posture[i])
        np.testing.assert_allclose(batch[i], single, rtol=1e-9, atol=1e-6 * np.abs(single).max())
    assert not np.allclose(batch[0], batch[1])  # three different simulations
