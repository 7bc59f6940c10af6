"""The kinematic backend: the paper's move-and-stop simulator, single and batched."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tolins
from tolins.envs import GENERIC_ID, TASKS, InsertionEnv
from tolins.envs.kinematic_backend import KinematicBackend, KinematicBatch
from tolins.paper import A_MAX, CONTROL_DT, HORIZON
from tolins.tolerance import extents

CIRCLE = tolins.CircularSocket(2, 2)
SQUARE = tolins.PolygonSocket(4, 1.5, 1.65)
HEXAGON = tolins.PolygonSocket(6, 1.2, 1.26)
TRIANGLE = tolins.PolygonSocket(3, 1.5, 1.65)
DOWN = [0.0, 0.0, 0.0, -A_MAX[3]]
#: A binary search over a 0.625 mm step to 16⁻¹·2⁻²⁸ of it.
SEARCH_TOLERANCE = 1e-9


def _push_down(socket, pose, steps: int = HORIZON) -> list[dict]:
    env = InsertionEnv(socket, backend="kinematic", measurement_noise=0)
    env.reset(seed=0, options={"pose": pose})
    infos = []
    for _ in range(steps):
        *_, terminated, truncated, info = env.step(DOWN)
        infos.append(info)
        if terminated or truncated:
            break
    return infos


@pytest.mark.parametrize("gym_id", [task.gym_id for task in TASKS])
def test_check_env_on_every_registered_id(gym_id: str) -> None:
    env = gym.make(gym_id, backend="kinematic")
    assert isinstance(env.unwrapped.backend, KinematicBackend)
    check_env(env.unwrapped, skip_render_check=True)


def test_check_env_on_the_generic_id() -> None:
    env = gym.make(GENERIC_ID, socket=TRIANGLE, backend="kinematic")
    check_env(env.unwrapped, skip_render_check=True)


@pytest.mark.parametrize("socket", [CIRCLE, SQUARE, HEXAGON, TRIANGLE], ids=repr)
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_inside_the_clearance_descends_and_outside_stops_on_the_top(socket, axis) -> None:
    low, high = getattr(extents(socket), "xyz"[axis] if axis < 2 else "theta")
    for limit in (low, high):
        inside, outside = [0.0, 0.0, 0.0, 0.05], [0.0, 0.0, 0.0, 0.05]
        inside[axis], outside[axis] = limit * (1 - 1e-6), limit * (1 + 1e-6)
        infos = _push_down(socket, inside)
        assert infos[-1]["success"] and infos[-1]["n_collisions"] == 0
        assert len(infos) == math.ceil(1.05 / (A_MAX[3] * CONTROL_DT))
        infos = _push_down(socket, outside, steps=4)
        for info in infos:
            assert not info["success"] and info["collision"]
            assert np.array_equal(info["pose"], [*outside[:3], 0.0])
            assert np.array_equal(info["wrench"], [0.0, 0.0, 0.0, 1.0])
        assert infos[-1]["n_collisions"] == 4 and infos[-1]["reward_collision"] == -1.0


def test_a_diagonal_descent_stops_where_it_meets_the_top() -> None:
    """The end of the step is inside the clearance; the pins meet the top before it."""
    backend = KinematicBackend(CIRCLE, CONTROL_DT)
    backend.reset(np.array([0.5, 0.0, 0.0, 0.1]))
    state = backend.step(np.array([-A_MAX[0], 0.0, 0.0, -A_MAX[3]]))  # 0.625 mm each
    assert state.pose == pytest.approx([0.4, 0.0, 0.0, 0.0], abs=1e-12)
    assert state.peak_force == 1.0 and state.wrench[3] == 1.0


def test_walls_stop_an_inserted_workpiece_at_the_clearance() -> None:
    backend = KinematicBackend(CIRCLE, CONTROL_DT)
    start = np.array([0.0, 0.0, 0.0, -0.5])
    backend.reset(start)
    state = backend.step(np.array([A_MAX[0], 0.0, 0.0, -A_MAX[3]]))
    assert state.pose[0] == pytest.approx(0.2, abs=SEARCH_TOLERANCE) and state.pose[0] <= 0.2
    assert state.pose[3] == pytest.approx(-0.5 - 0.2, abs=SEARCH_TOLERANCE)
    assert np.array_equal(state.wrench, [-1.0, 0.0, 0.0, 0.0]) and state.peak_force == 1.0
    backend.reset(start)
    for _ in range(3):  # 0.025 rad per step against a 0.0498 rad clearance
        state = backend.step(np.array([0.0, 0.0, A_MAX[2], 0.0]))
    assert state.pose[2] == pytest.approx(extents(CIRCLE).theta[1], abs=SEARCH_TOLERANCE)
    assert np.array_equal(state.wrench, [0.0, 0.0, -1.0, 0.0])
    state = backend.step(np.array([0.0, 0.0, -A_MAX[2], 0.0]))  # back out: free again
    assert state.peak_force == 0.0 and not state.wrench.any()


def test_free_motion_is_exactly_velocity_times_dt() -> None:
    backend = KinematicBackend(SQUARE, CONTROL_DT)
    backend.reset(np.array([1.0, -2.0, 0.05, 10.0]))
    velocity = np.array([2.5, -1.0, 0.1, -2.5])
    state = backend.step(velocity)
    assert np.array_equal(state.pose, np.array([1.0, -2.0, 0.05, 10.0]) + velocity * CONTROL_DT)
    assert state.peak_force == 0.0 and not state.wrench.any()


def test_bent_pins_go_in_where_the_bend_allows() -> None:
    bent = tolins.CircularSocket(2, 1, pin_offsets=[[0.3, 0.0], [0.3, 0.0]])
    assert not _push_down(bent, [0.0, 0.0, 0.0, 0.05], steps=4)[-1]["success"]
    assert _push_down(bent, [-0.3, 0.0, 0.0, 0.05])[-1]["success"]


def _rollout(gym_id: str, seed: int) -> list[np.ndarray]:
    env = gym.make(gym_id, backend="kinematic")
    rng = np.random.default_rng(5)
    observation, _ = env.reset(seed=seed)
    observations = [observation]
    for _ in range(HORIZON):
        action = rng.uniform(-A_MAX, A_MAX) * [0.3, 0.3, 0.3, 1] - [0, 0, 0, 2.0]
        observation, _, terminated, truncated, _ = env.step(action)
        observations.append(observation)
        if terminated or truncated:
            break
    return observations


@pytest.mark.parametrize("gym_id", ["tolins/Circle2x2-v0", "tolins/Circle2x1Defective-v0"])
def test_same_seed_same_trajectory(gym_id: str) -> None:
    first, second = _rollout(gym_id, 3), _rollout(gym_id, 3)
    assert len(first) == len(second)
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
    assert not np.array_equal(first[0], _rollout(gym_id, 4)[0])


@pytest.mark.parametrize("socket", [CIRCLE, tolins.CircularSocket(2, 8), HEXAGON], ids=repr)
def test_batch_agrees_with_single_backends(socket) -> None:
    n, rng = 48, np.random.default_rng(0)
    limits = extents(socket)
    scale = np.array([limits.x[1], limits.y[1], limits.theta[1]])
    starts = np.column_stack([rng.normal(0, 1, (n, 3)) * scale, rng.uniform(0, 1, n)])
    batch = KinematicBatch(socket, n, CONTROL_DT)
    singles = [KinematicBackend(socket, CONTROL_DT) for _ in range(n)]
    batch.reset(starts)
    for single, start in zip(singles, starts, strict=True):
        single.reset(start)
    stops = 0
    for _ in range(20):
        sideways = rng.uniform(-1, 1, (n, 3)) * scale / CONTROL_DT * 0.3
        velocities = np.column_stack([sideways, rng.uniform(-A_MAX[3], 0.5, n)])
        state = batch.step(velocities)
        for i, single in enumerate(singles):
            expected = single.step(velocities[i])
            np.testing.assert_allclose(state.pose[i], expected.pose, rtol=0, atol=1e-12)
            assert np.array_equal(state.wrench[i], expected.wrench)
            assert state.peak_force[i] == expected.peak_force
        stops += int(np.count_nonzero(state.peak_force))
    assert stops > 50 and np.any(state.pose[:, 3] < -1.0)  # both stops and insertions


def test_env_on_the_batch_matches_the_env() -> None:
    env = InsertionEnv(CIRCLE, backend="kinematic", measurement_noise=0)
    batch = KinematicBatch(CIRCLE, 1, CONTROL_DT)
    _, info = env.reset(seed=1)
    batch.reset(info["pose"][None])
    for _ in range(HORIZON):
        action = -np.clip(
            np.append(info["pose"][:3], info["pose"][3] + 2) / CONTROL_DT, -A_MAX, A_MAX
        )
        *_, terminated, truncated, info = env.step(action)
        state = batch.step(action[None])
        assert np.array_equal(state.pose[0], info["pose"])
        if terminated or truncated:
            break


def test_bad_input_raises_a_clear_error() -> None:
    batch = KinematicBatch(CIRCLE, 2, CONTROL_DT)
    with pytest.raises(ValueError, match=r"poses\[1\].*inside the board"):
        batch.reset([[0.0, 0.0, 0.0, 1.0], [0.5, 0.0, 0.0, -0.1]])
    with pytest.raises(ValueError, match=r"poses has shape \(4,\)"):
        batch.reset([0.0, 0.0, 0.0, 1.0])
    batch.reset(np.zeros((2, 4)))
    with pytest.raises(ValueError, match=r"velocities.*NaN"):
        batch.step([[0.0, 0.0, 0.0, np.nan]] * 2)
    with pytest.raises(ValueError, match="n=0"):
        KinematicBatch(CIRCLE, 0, CONTROL_DT)
    env = InsertionEnv(CIRCLE, backend="kinematic")
    with pytest.raises(ValueError, match="inside the board"):
        env.reset(options={"pose": [1.0, 0.0, 0.0, -0.5]})


def test_render_draws_the_kinematic_pose() -> None:
    env = InsertionEnv(tolins.CircularSocket(2, 4), backend="kinematic", render_mode="rgb_array")
    env.reset(seed=0, options={"pose": [0.8, 0.5, 0.05, 1.0]})
    try:
        image = env.render()
    except Exception as error:  # no OpenGL (EGL) on this machine
        pytest.skip(f"headless OpenGL unavailable: {error}")
    finally:
        env.close()
    assert image.shape == (480, 640, 3) and image.dtype == np.uint8
    assert env.backend.data.qpos[env.backend.model.joint("x").qposadr[0]] == 0.8
