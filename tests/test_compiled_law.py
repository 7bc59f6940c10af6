"""The Panda's law compiled (numba) against the same law in numpy, on real Panda states."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import tolins  # noqa: F401  (registers the ids)
from tolins.physics.arm import COMPILED, Gains, LawInputs, grip_rotation
from tolins.physics.law_state import STATE, STATE_SIZE, advance_target

pytestmark = pytest.mark.skipif(not COMPILED, reason="needs numba (tolins[robot])")

PANDA = "tolins/Circle2x2Panda-v3"


@pytest.fixture(scope="module")
def states():
    """The Panda's simulation after a reset and after steps pressing down and sideways."""
    env = gym.make(PANDA, measurement_noise=0.0).unwrapped
    env.reset(seed=3)
    sims = env.backend._batch.sims
    taken = [(sims.datas[0].qpos.copy(), sims.datas[0].qvel.copy())]
    for action in ([2.0, -1.0, 0.1, -3.0], [0.0, 0.0, 0.0, -3.0], [-3.0, 3.0, -0.1, -3.0]):
        env.step(np.array(action))
        taken.append((sims.datas[0].qpos.copy(), sims.datas[0].qvel.copy()))
    return sims, taken


def _law_state(target, yaw, twist, posture) -> np.ndarray:
    state = np.zeros(STATE_SIZE)
    state[STATE["target"]], state[STATE["yaw"]] = target, yaw
    state[STATE["twist"]], state[STATE["posture"]] = twist, posture
    return state


@pytest.mark.parametrize(
    "gains",
    [Gains(), Gains(stiffness=(160000.0, 160000.0, *(20000.0,) * 4), force_limit=(1.0, 1.0, 1.0))],
    ids=["default", "stiff and clipped"],
)
def test_the_compiled_law_gives_the_numpy_laws_torques(states, gains: Gains) -> None:
    sims, taken = states
    arm, model, data = sims.arm, sims.models[0], sims.datas[0]
    rng = np.random.default_rng(0)
    for qpos, qvel in taken:
        data.qpos[:], data.qvel[:] = qpos, qvel
        mujoco.mj_forward(model, data)
        target = data.site_xpos[arm.site] + rng.normal(0, 0.5, 3)
        yaw = float(np.arctan2(data.site_xmat[arm.site][3], data.site_xmat[arm.site][0]))
        yaw += rng.normal(0, 0.02)
        twist = rng.normal(0, 2.0, 6) * [1, 1, 1, 0.01, 0.01, 0.05]
        posture = data.qpos[arm.qpos] + rng.normal(0, 0.05, 7)
        payload = 0.01
        (expected,) = arm.batch_torques(
            [data],
            target[None],
            grip_rotation(yaw)[None],
            twist[None],
            posture[None],
            payload=payload,
            gains=gains,
        )
        data.ctrl[:] = 0.0
        state = _law_state(target, yaw, twist, posture)
        arm.apply_law(model, LawInputs(model, data), state, arm.law_gains(gains, payload))
        got = data.ctrl[arm.motors]
        # Rounding only: Cholesky solves here, LAPACK's LU in numpy (7 × 7, well conditioned).
        np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())
        assert not np.array_equal(got, np.zeros(7))


@pytest.mark.parametrize("compiled", [False, True], ids=["python", "compiled"])
def test_a_target_moves_along_its_twist_and_stops_at_the_workspace_edge(compiled: bool) -> None:
    if compiled:
        from tolins.physics.compiled_law import advance_target as advance
    else:
        advance = advance_target
    bounds = np.array([[-1.0, -1.0, 0.0, -0.3], [1.0, 1.0, 10.0, 0.3]])
    state = _law_state([0.9, 0.0, 5.0], 0.29, [4.0, -2.0, 0.0, 0.5, 0.0, 1.0], np.zeros(7))
    twist = advance(state, 0.05, bounds)
    np.testing.assert_array_equal(state[STATE["target"]], [1.0, -0.1, 5.0])  # x stopped
    assert state[STATE["yaw"]] == 0.3
    # This update tracks no twist along the blocked axes; the commanded twist is kept.
    np.testing.assert_array_equal(twist, [0.0, -2.0, 0.0, 0.5, 0.0, 0.0])
    np.testing.assert_array_equal(state[STATE["twist"]], [4.0, -2.0, 0.0, 0.5, 0.0, 1.0])
    still = state.copy()
    np.testing.assert_array_equal(advance(state, 0.0, bounds), state[STATE["twist"]])
    np.testing.assert_array_equal(state, still)


def test_the_numpy_law_steps_a_panda_as_the_compiled_one_does_within_rounding() -> None:
    """A few control steps with each law end at the same pose within a micrometre."""
    poses = []
    for compiled in (True, False):
        env = gym.make(PANDA, measurement_noise=0.0).unwrapped
        env.backend._batch.sims.compiled = compiled
        env.reset(seed=1)
        for _ in range(4):
            _, _, _, _, info = env.step(np.array([1.0, -1.0, 0.05, -2.5]))
        poses.append(info["pose"])
    np.testing.assert_allclose(poses[0], poses[1], atol=1e-3)
