"""Reward modes: sparse unchanged, terms that sum up, rise along the expert's path, no gaming."""

from __future__ import annotations

import numpy as np
import pytest

import tolins
from tolins import dmc
from tolins.envs import TASKS, InsertionEnv
from tolins.envs.initial_pose import InitialPoseDistribution
from tolins.envs.reward import (
    DENSE_WEIGHTS,
    REWARD_MODES,
    approach_distance,
    clearance_use,
    is_aligned,
    shaping_terms,
    sparse_return_ceiling,
)
from tolins.paper import A_MAX, COLLISION_REWARD, CONTROL_DT, HORIZON, SUCCESS_REWARD
from tolins.policies.experts import SafeExpert

BACKENDS = ("mujoco", "kinematic")
SOCKET = tolins.CircularSocket(2, 2)
TERMS = ("success", "collision", "approach", "height", "alignment", "depth", "offset")


def _descending_actions(seed: int) -> np.ndarray:
    """Small random horizontal moves while descending at full speed: reaches the board,
    collides, and sometimes inserts."""
    rng = np.random.default_rng(seed)
    horizontal = rng.uniform(-A_MAX[:3], A_MAX[:3], (HORIZON, 3)) * 0.3
    return np.column_stack([horizontal, np.full(HORIZON, -A_MAX[3])])


def _rollout(env: InsertionEnv, seed: int, policy) -> list[tuple[float, dict]]:
    """``(reward, info)`` of every step; ``policy(observation, step)``."""
    observation, _ = env.reset(seed=seed)
    steps = []
    for k in range(HORIZON):
        observation, reward, terminated, truncated, info = env.step(policy(observation, k))
        steps.append((reward, info))
        if terminated or truncated:
            break
    return steps


def _open_loop(actions: np.ndarray):
    return lambda observation, k: actions[k]


def _expert(observation: np.ndarray, k: int) -> np.ndarray:
    return SafeExpert()(observation)


@pytest.mark.parametrize("backend", BACKENDS)
def test_sparse_is_the_default_and_the_papers_reward_bit_for_bit(backend: str) -> None:
    collisions = 0
    for seed, policy in ((1, _open_loop(_descending_actions(1))), (2, _expert)):
        default = _rollout(InsertionEnv(SOCKET, backend=backend), seed, policy)
        collisions += sum(info["collision"] for _, info in default)
        sparse = _rollout(InsertionEnv(SOCKET, backend=backend, reward_mode="sparse"), seed, policy)
        assert [r for r, _ in default] == [r for r, _ in sparse]
        for k, (reward, info) in enumerate(sparse, start=1):
            paper = SUCCESS_REWARD * (1 - k / HORIZON) if info["success"] else 0.0
            paper += COLLISION_REWARD if info["collision"] else 0.0
            assert reward == paper
            assert info["reward_approach"] == info["reward_offset"] == 0.0
    assert collisions > 0  # the collision reward was compared too
    assert sparse[-1][1]["success"]  # the expert inserts: the success reward was compared


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_mode_has_the_same_physics_success_and_collisions(backend: str) -> None:
    policy = _open_loop(_descending_actions(4))
    runs = {
        m: _rollout(InsertionEnv(SOCKET, backend=backend, reward_mode=m), 4, policy)
        for m in REWARD_MODES
    }
    sparse = runs["sparse"]
    assert any(info["collision"] for _, info in sparse)
    for mode in ("dense", "normalized_dense"):
        assert len(runs[mode]) == len(sparse)
        for (reward, info), (_, other) in zip(sparse, runs[mode], strict=True):
            assert np.array_equal(info["pose"], other["pose"])
            assert (info["success"], info["collision"]) == (other["success"], other["collision"])
            if mode == "dense":
                assert other["reward_success"] + other["reward_collision"] == reward


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("mode", REWARD_MODES)
def test_terms_sum_to_the_reward(backend: str, mode: str) -> None:
    env = InsertionEnv(SOCKET, backend=backend, reward_mode=mode)
    for seed, policy in ((5, _open_loop(_descending_actions(5))), (6, _expert)):
        for reward, info in _rollout(env, seed, policy):
            assert sum(info[f"reward_{t}"] for t in TERMS) == pytest.approx(reward, abs=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_normalized_dense_is_the_dense_reward_mapped_into_the_unit_interval(backend: str) -> None:
    envs = {m: InsertionEnv(SOCKET, backend=backend, reward_mode=m) for m in REWARD_MODES[1:]}
    low = -DENSE_WEIGHTS.total + COLLISION_REWARD
    random_actions = np.random.default_rng(0).uniform(-A_MAX, A_MAX, (HORIZON, 4))
    normalized = []
    for seed in range(3):
        for policy in (_open_loop(random_actions), _open_loop(_descending_actions(seed)), _expert):
            runs = {m: [r for r, _ in _rollout(env, seed, policy)] for m, env in envs.items()}
            expected = (np.array(runs["dense"]) - low) / (SUCCESS_REWARD - low)
            assert np.allclose(runs["normalized_dense"], expected, rtol=0, atol=1e-12)
            normalized += runs["normalized_dense"]
    assert min(normalized) >= 0.0 and max(normalized) <= 1.0
    assert max(normalized) > 0.1  # the expert's successes are in there


@pytest.mark.parametrize("backend", BACKENDS)
def test_dense_reward_rises_along_the_safe_experts_path(backend: str) -> None:
    exact = InsertionEnv(SOCKET, backend=backend, reward_mode="dense", measurement_noise=0)
    noisy = InsertionEnv(SOCKET, backend=backend, reward_mode="dense")
    for seed in range(3):
        rewards = np.array([r for r, _ in _rollout(exact, seed, _expert)])
        assert np.all(np.diff(rewards) > 0), rewards
        # Noisy measurements make the expert's corrections jitter within the clearance.
        rewards = np.array([r for r, _ in _rollout(noisy, seed, _expert)])
        assert rewards.argmax() == len(rewards) - 1
        thirds = [part.mean() for part in np.array_split(rewards[:-1], 3)]
        assert thirds[0] < thirds[1] < thirds[2]
        assert np.corrcoef(np.arange(len(rewards) - 1), rewards[:-1])[0, 1] > 0.8


@pytest.mark.parametrize("task", TASKS, ids=lambda t: t.name)
def test_clearance_use_is_at_most_1_exactly_inside_the_tolerance(task) -> None:
    poses = np.random.default_rng(0).normal(0, [0.15, 0.15, 0.05], (2000, 3))
    inside = np.array([is_aligned(task.socket, p) for p in poses])
    use = np.array([clearance_use(task.socket, p) for p in poses])
    assert 0.01 < inside.mean() < 0.99
    assert np.array_equal(use <= 1.0, inside)
    assert clearance_use(task.socket, [0, 0, 0]) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("task", TASKS, ids=lambda t: t.name)
def test_below_the_board_top_pays_only_for_aligned_pins(task) -> None:
    """A dive off the board or a pin pressed into it earns what resting on the top does."""
    rng = np.random.default_rng(1)
    for _ in range(300):
        pose = np.append(rng.normal(0, [1.0, 1.0, 0.1]), -rng.uniform(0, 30))
        if task.name == "Square" and rng.random() < 0.5:
            pose[:3] = [40.0, -40.0, 0.3]  # far off the board
        below = shaping_terms(task.socket, pose, 1.0)
        on_top = shaping_terms(task.socket, np.append(pose[:3], 0.0), 1.0)
        if is_aligned(task.socket, pose):
            assert below["depth"] >= on_top["depth"]
        else:
            assert below == on_top
        assert all(value <= 0 for value in below.values())


def test_polygon_approach_is_zero_at_every_symmetric_rotation() -> None:
    square = tolins.PolygonSocket(4, 1.5, 1.65)
    for theta in (0.0, np.pi / 2, -np.pi, 3 * np.pi / 2):
        assert approach_distance(square, [0, 0, theta, 0]) == pytest.approx(0, abs=1e-12)
    assert approach_distance(square, [0, 0, np.pi / 4, 0]) > 1.0


def _hover_then(action_z: float, pose: list[float], backend: str, mode: str) -> float:
    """Dense return of holding x, y, theta at ``pose`` while commanding ``action_z``, then
    (for hovering) stopping 0.05 mm over the board."""
    env = InsertionEnv(SOCKET, backend=backend, reward_mode=mode, measurement_noise=0)
    env.reset(seed=0, options={"pose": pose})
    total, height = 0.0, pose[3]
    for _ in range(HORIZON):
        uz = action_z if action_z < 0 else -np.clip((height - 0.05) / 0.25, 0, A_MAX[3])
        _, reward, terminated, truncated, info = env.step([0, 0, 0, uz])
        total, height = total + reward, info["pose"][3]
        if terminated or truncated:
            break
    assert not info["success"]
    return total


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("mode", ["dense", "normalized_dense"])
def test_pushing_on_the_board_top_earns_no_more_than_hovering_over_it(
    backend: str, mode: str
) -> None:
    pose = [0.8, -0.6, 0.02, 2.0]  # pins over the board, not over their holes
    assert _hover_then(-A_MAX[3], pose, backend, mode) <= _hover_then(0.0, pose, backend, mode)


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_open_loop_dive_earns_less_dense_reward_than_the_expert(backend: str) -> None:
    env = InsertionEnv(SOCKET, backend=backend, reward_mode="dense")
    for seed in range(3):
        dive = _rollout(env, seed, lambda o, k: np.array([2.5, 0.0, 0.0, -2.5]))
        expert = _rollout(env, seed, _expert)
        assert sum(r for r, _ in dive) < sum(r for r, _ in expert)


def test_dm_control_task_kwargs_select_the_reward_mode() -> None:
    gym_env = InsertionEnv(SOCKET, reward_mode="dense")
    env = dmc.load("circle2x2", "insert", task_kwargs={"random": 3, "reward_mode": "dense"})
    gym_env.reset(seed=3)
    env.reset()
    for action in _descending_actions(3):
        _, reward, *_, info = gym_env.step(action)
        timestep = env.step(action)
        assert timestep.reward == reward
        assert env.task.last_score.reward_info() == {
            k: v for k, v in info.items() if k.startswith("reward_")
        }
        if timestep.last():
            break
    assert reward != 0.0


@pytest.mark.parametrize("mode", ["Dense", "", None, 1])
def test_an_unknown_reward_mode_raises_everywhere(mode) -> None:
    with pytest.raises(ValueError, match=r"reward_mode=.*allowed: sparse, dense"):
        InsertionEnv(SOCKET, reward_mode=mode)
    with pytest.raises(ValueError, match=r"reward_mode=.*allowed: sparse, dense"):
        dmc.load("circle2x2", "insert", task_kwargs={"reward_mode": mode})


def _oracle_return(env: InsertionEnv, seed: int) -> tuple[float, float]:
    """The start height and the sparse return of a policy that sees the true pose and
    moves at full speed: the goal's horizontal pose, and down."""
    _, info = env.reset(seed=seed)
    z0, total, done = float(info["pose"][3]), 0.0, False
    while not done:
        pose = np.asarray(info["pose"])
        horizontal = np.clip(-pose[:3] / CONTROL_DT, -A_MAX[:3], A_MAX[:3])
        _, reward, terminated, truncated, info = env.step(np.append(horizontal, -A_MAX[3]))
        total, done = total + reward, terminated or truncated
    return z0, total


def test_the_sparse_return_ceiling_is_what_a_full_speed_oracle_earns():
    kinematic, mujoco = (
        InsertionEnv(SOCKET, backend=backend, physics_version=2) for backend in BACKENDS[::-1]
    )
    for seed in range(4):
        # On the paper's simulator the oracle earns the ceiling of its own start height...
        z0, earned = _oracle_return(kinematic, seed)
        start = InitialPoseDistribution(z_min=z0, z_max=z0)
        assert earned == pytest.approx(sparse_return_ceiling(start), abs=1e-9)
        # ...and on contact physics, whose servos lag the command, at most that.
        assert _oracle_return(mujoco, seed)[1] <= earned
    # The mean over the start heights: each height's ceiling, averaged.
    heights = np.random.default_rng(0).uniform(16.0, 18.0, 200_000)
    steps = np.ceil((heights + 1.0) / (A_MAX[3] * CONTROL_DT))
    sampled = np.mean(SUCCESS_REWARD * (1 - steps / HORIZON))
    assert sparse_return_ceiling() == pytest.approx(sampled, abs=0.05)
