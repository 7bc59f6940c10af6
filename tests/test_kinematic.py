"""The kinematic backend: the paper's move-and-stop simulator, single and batched."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from rollouts import push_down, random_rollout

import tolins
from tolins.envs import GENERIC_ID, TASKS, InsertionEnv
from tolins.paper import A_MAX, CONTROL_DT, HORIZON
from tolins.physics.kinematic import KinematicBackend, KinematicBatch
from tolins.policies.experts import EfficientExpert
from tolins.tolerance import contains, extents

CIRCLE = tolins.CircularSocket(2, 2)
SQUARE = tolins.PolygonSocket(4, 1.5, 1.65)
HEXAGON = tolins.PolygonSocket(6, 1.2, 1.26)
TRIANGLE = tolins.PolygonSocket(3, 1.5, 1.65)
DOWN = [0.0, 0.0, 0.0, -A_MAX[3]]
#: A binary search over a 0.625 mm step to 16⁻¹·2⁻²⁸ of it.
SEARCH_TOLERANCE = 1e-9


def _push_down(socket, pose, steps: int = HORIZON) -> list[dict]:
    return push_down(socket, pose, steps, backend="kinematic")


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


def test_a_diagonal_descent_lands_on_the_top_and_slides() -> None:
    """The pins meet the top outside the clearance at 0.4 mm; x goes on along the top."""
    backend = KinematicBackend(CIRCLE, CONTROL_DT)
    backend.reset(np.array([0.5, 0.0, 0.0, 0.1]))
    state = backend.step(np.array([-A_MAX[0], 0.0, 0.0, -A_MAX[3]]))  # 0.625 mm each
    assert np.array_equal(state.pose, [0.5 - 0.625, 0.0, 0.0, 0.0])
    assert state.peak_force == 1.0 and np.array_equal(state.wrench, [0.0, 0.0, 0.0, 1.0])
    state = backend.step(np.array(DOWN))  # now over the holes: in, freely
    assert np.array_equal(state.pose, [-0.125, 0.0, 0.0, -0.625]) and state.peak_force == 0.0


@pytest.mark.parametrize("socket", [CIRCLE, SQUARE, HEXAGON, TRIANGLE], ids=repr)
def test_landing_beside_the_hole_slides_over_it_then_descends(socket) -> None:
    env = InsertionEnv(socket, backend="kinematic", measurement_noise=0)
    start = np.array([0.6, -0.4, 0.02, 0.05])
    env.reset(seed=0, options={"pose": start})
    *_, info = env.step(DOWN)  # lands beside the hole
    assert np.array_equal(info["pose"], [*start[:3], 0.0]) and info["collision"]
    pose = info["pose"]
    for velocity in ([-1.2, 0.8, 0.0, -A_MAX[3]], [-1.2, 0.8, -0.08, -A_MAX[3]]):
        *_, info = env.step(velocity)  # still beside: slides on the top by the whole step
        expected = pose + np.array(velocity) * CONTROL_DT
        assert np.array_equal(info["pose"][:3], expected[:3]) and info["pose"][3] == 0.0
        assert info["collision"] and np.array_equal(info["wrench"], [0, 0, 0, 1.0])
        pose = info["pose"]
    assert np.allclose(pose[:3], 0.0, atol=1e-15)  # over the hole, on the top
    assert info["n_collisions"] == 3
    for _ in range(2):  # 0.625 mm a step: 1 mm deep after the second
        *_, terminated, _, info = env.step(DOWN)
        assert not info["collision"]
    assert terminated and info["success"] and info["n_collisions"] == 3


def test_pushing_into_a_wall_while_descending_still_descends() -> None:
    env = InsertionEnv(CIRCLE, backend="kinematic", measurement_noise=0, success_depth=1.8)
    env.reset(seed=0, options={"pose": [0.15, 0.0, 0.0, -0.1]})
    for k in range(1, 4):
        *_, terminated, _, info = env.step([A_MAX[0], 0.0, A_MAX[2], -A_MAX[3]])
        assert info["collision"] and info["n_collisions"] == k
        assert np.array_equal(info["wrench"], [-1.0, 0.0, -1.0, 0.0])
        assert info["pose"][3] == -0.1 - k * 0.625  # z is not blocked by the wall
        beyond = info["pose"][:3] + np.array([1e-8, 0.0, 0.0])
        assert contains(CIRCLE, info["pose"][:3]) and not contains(CIRCLE, beyond)  # at the wall
    assert terminated and info["success"]
    backend = KinematicBackend(CIRCLE, CONTROL_DT)  # ascending against a wall
    backend.reset(np.array([0.15, 0.0, 0.0, -0.5]))
    state = backend.step(np.array([A_MAX[0], 0.0, 0.0, A_MAX[3]]))
    assert state.pose[0] == pytest.approx(0.2, abs=SEARCH_TOLERANCE) and state.pose[0] <= 0.2
    assert state.pose[3] == -0.5 + 0.625 and state.peak_force == 1.0


def test_the_efficient_expert_slides_in_from_beside_the_hole() -> None:
    env = InsertionEnv(CIRCLE, backend="kinematic", measurement_noise=0)
    expert = EfficientExpert()
    observation, _ = env.reset(seed=0, options={"pose": [2.0, -1.5, 0.05, 1.0]})
    for _ in range(HORIZON):
        observation, _, terminated, truncated, info = env.step(expert(observation))
        if terminated or truncated:
            break
    assert info["success"] and info["n_collisions"] >= 1


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


def _mostly_down(action: np.ndarray) -> np.ndarray:
    return action * [0.3, 0.3, 0.3, 1] - [0, 0, 0, 2.0]


def _rollout(gym_id: str, seed: int) -> list[np.ndarray]:
    return random_rollout(gym.make(gym_id, backend="kinematic"), seed, shape=_mostly_down)


@pytest.mark.parametrize("gym_id", ["tolins/Circle2x2-v1", "tolins/Circle2x1Defective-v1"])
def test_same_seed_same_trajectory(gym_id: str) -> None:
    first, second = _rollout(gym_id, 3), _rollout(gym_id, 3)
    assert len(first) == len(second)
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
    assert not np.array_equal(first[0], _rollout(gym_id, 4)[0])


@pytest.mark.parametrize("socket", [CIRCLE, tolins.CircularSocket(2, 8), HEXAGON], ids=repr)
def test_batch_agrees_with_single_backends(socket) -> None:
    """Random walks in the air, on the top (landing, sliding) and in the holes (walls)."""
    n, rng = 60, np.random.default_rng(0)
    limits = extents(socket)
    scale = np.array([limits.x[1], limits.y[1], limits.theta[1]])
    starts = np.column_stack([rng.normal(0, 1, (n, 3)) * scale, rng.uniform(0, 1, n)])
    starts[:12, 3] = 0.0  # on the top, most of them beside the holes
    starts[12:24, :3] = rng.uniform(-0.3, 0.3, (12, 3)) * scale
    starts[12:24, 3] = -rng.uniform(0.0, 0.5, 12)  # in the holes
    batch, ids = KinematicBatch(socket, n, CONTROL_DT), np.arange(n)
    singles = [KinematicBackend(socket, CONTROL_DT) for _ in range(n)]
    batch.reset(ids, starts)
    for single, start in zip(singles, starts, strict=True):
        single.reset(start)
    top_slides = wall_descents = 0
    previous = starts
    for _ in range(20):
        sideways = rng.uniform(-1, 1, (n, 3)) * scale / CONTROL_DT * 0.3
        velocities = np.column_stack([sideways, rng.uniform(-A_MAX[3], 0.5, n)])
        state = batch.step(ids, velocities)
        for i, single in enumerate(singles):
            expected = single.step(velocities[i])
            np.testing.assert_allclose(state.pose[i], expected.pose, rtol=0, atol=1e-12)
            assert np.array_equal(state.wrench[i], expected.wrench)
            assert state.peak_force[i] == expected.peak_force
        on_top = (state.peak_force > 0) & (state.wrench[:, 3] > 0)
        moved = np.any(state.pose[:, :3] != previous[:, :3], axis=1)
        assert np.all(state.pose[on_top, 3] == 0.0)
        top_slides += int(np.count_nonzero(on_top & moved))
        at_wall = (state.peak_force > 0) & (state.wrench[:, 3] == 0)
        wall_descents += int(np.count_nonzero(at_wall & (state.pose[:, 3] < previous[:, 3])))
        previous = state.pose
    assert top_slides > 200 and wall_descents > 50 and np.any(state.pose[:, 3] < -1.0)


def test_env_on_the_batch_matches_the_env() -> None:
    env = InsertionEnv(CIRCLE, backend="kinematic", measurement_noise=0)
    batch, ids = KinematicBatch(CIRCLE, 1, CONTROL_DT), np.zeros(1, dtype=int)
    _, info = env.reset(seed=1)
    batch.reset(ids, info["pose"][None])
    for _ in range(HORIZON):
        action = -np.clip(
            np.append(info["pose"][:3], info["pose"][3] + 2) / CONTROL_DT, -A_MAX, A_MAX
        )
        *_, terminated, truncated, info = env.step(action)
        state = batch.step(ids, action[None])
        assert np.array_equal(state.pose[0], info["pose"])
        if terminated or truncated:
            break


def test_bad_input_raises_a_clear_error() -> None:
    batch = KinematicBatch(CIRCLE, 2, CONTROL_DT)
    with pytest.raises(ValueError, match=r"poses\[1\].*inside the board"):
        batch.reset([0, 1], [[0.0, 0.0, 0.0, 1.0], [0.5, 0.0, 0.0, -0.1]])
    assert np.array_equal(batch.pose, np.zeros((2, 4)))  # a refused reset moves nothing
    with pytest.raises(ValueError, match="num_envs=0"):
        KinematicBatch(CIRCLE, 0, CONTROL_DT)
    env = InsertionEnv(CIRCLE, backend="kinematic")
    with pytest.raises(ValueError, match="inside the board"):
        env.reset(options={"pose": [1.0, 0.0, 0.0, -0.5]})
