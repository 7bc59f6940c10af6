"""The insertion env's interface: spaces, determinism, reward, errors and faults."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from rollouts import random_rollout

import tolins
from tolins.envs import GENERIC_ID, TASKS, InsertionEnv
from tolins.paper import A_MAX, HORIZON, SUCCESS_REWARD

ABOVE = [3.0, -2.0, 0.05, 10.0]


@pytest.fixture
def env() -> InsertionEnv:
    return InsertionEnv(tolins.CircularSocket(2, 2))


@pytest.mark.parametrize("gym_id", [task.gym_id_of(v) for v in (1, 2) for task in TASKS])
def test_check_env_on_every_registered_id(gym_id: str) -> None:
    check_env(gym.make(gym_id).unwrapped, skip_render_check=True)


def test_check_env_on_the_generic_id() -> None:
    socket = tolins.PolygonSocket(3, 1.5, 1.65)
    env = gym.make(GENERIC_ID, socket=socket)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.unwrapped.socket == socket


@pytest.mark.parametrize("gym_id", ["tolins/Circle2x2-v1", "tolins/Circle2x1Defective-v1"])
def test_same_seed_and_actions_give_bit_identical_observations(gym_id: str) -> None:
    first = random_rollout(gym.make(gym_id), seed=7)
    second = random_rollout(gym.make(gym_id), seed=7)
    assert len(first) == len(second)
    for a, b in zip(first, second, strict=True):
        assert np.array_equal(a, b)
    other = random_rollout(gym.make(gym_id), seed=8)
    assert not np.array_equal(first[0], other[0])


def test_defective_env_draws_a_new_workpiece_at_every_reset() -> None:
    env = gym.make("tolins/Circle2x1Defective-v1").unwrapped
    env.reset(seed=0)
    first = env.socket
    env.reset()
    assert first.is_defective and env.socket.is_defective
    assert first != env.socket
    assert env.nominal_socket == tolins.CircularSocket(2, 1)


def test_reset_pose_and_goal_options(env: InsertionEnv) -> None:
    quiet = InsertionEnv(tolins.CircularSocket(2, 2), measurement_noise=0)
    goal = [0.1, -0.2, 0.01]
    observation, info = quiet.reset(seed=0, options={"pose": ABOVE, "goal": goal})
    assert np.array_equal(info["pose"], ABOVE)
    assert np.allclose(observation[:3], np.subtract(ABOVE[:3], goal), atol=1e-12)
    assert observation[3] == pytest.approx(ABOVE[3], abs=1e-12)
    assert np.allclose(observation[4:], 0.0)
    quiet.goal = [0, 0, 0]
    assert np.array_equal(quiet.goal, [0, 0, 0])


def test_random_initial_pose_follows_the_documented_distribution(env: InsertionEnv) -> None:
    dist = env.initial_pose
    poses = np.array([env.reset(seed=s)[1]["pose"] for s in range(200)])
    radius = np.hypot(poses[:, 0], poses[:, 1])
    assert np.all((dist.radius_min <= radius) & (radius <= dist.radius_max))
    assert np.all(np.abs(poses[:, 2]) <= dist.theta_max)
    assert np.all((dist.z_min <= poses[:, 3]) & (poses[:, 3] <= dist.z_max))
    assert np.std(poses[:, 2]) > dist.theta_max / 3


def test_measurement_noise_has_the_papers_std() -> None:
    env = InsertionEnv(tolins.PolygonSocket(4, 1.5, 1.65))
    errors = []
    for seed in range(400):
        observation, info = env.reset(seed=seed, options={"pose": ABOVE})
        errors.append(observation[:4] - np.append(info["pose"][:3], info["pose"][3]))
    std = np.std(errors, axis=0)
    assert np.allclose(std, [0.1, 0.1, 0.0, 0.1], atol=0.015)
    assert std[2] == 0.0


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_action_raises_and_leaves_the_state_untouched(bad: float) -> None:
    env, twin = (InsertionEnv(tolins.CircularSocket(2, 2)) for _ in range(2))
    for e in (env, twin):
        e.reset(seed=3)
    with pytest.raises(ValueError, match="NaN or inf"):
        env.step([0.0, bad, 0.0, -1.0])
    action = [1.0, -1.0, 0.02, -2.0]
    assert np.array_equal(env.step(action)[0], twin.step(action)[0])


@pytest.mark.parametrize("action", [[1.0, 2.0, 3.0], [[0, 0, 0, 0]], "fast"])
def test_malformed_action_raises(env: InsertionEnv, action: object) -> None:
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(action)


def test_out_of_range_actions_are_clipped() -> None:
    env, twin = (InsertionEnv(tolins.CircularSocket(2, 2)) for _ in range(2))
    env.reset(seed=1)
    twin.reset(seed=1)
    sign = np.array([1, -1, 1, -1])
    big = env.step(10 * A_MAX * sign)
    limit = twin.step(A_MAX * sign)
    assert np.array_equal(big[0], limit[0])
    assert np.array_equal(big[4]["pose"], limit[4]["pose"])


def test_step_before_reset_raises(env: InsertionEnv) -> None:
    with pytest.raises(gym.error.ResetNeeded, match="reset"):
        env.step(np.zeros(4))


def test_horizon_truncates_without_reward(env: InsertionEnv) -> None:
    env.reset(seed=0, options={"pose": ABOVE})
    for k in range(1, HORIZON + 1):
        _, reward, terminated, truncated, info = env.step(np.zeros(4))
        assert reward == 0.0 and not terminated
        assert truncated == (k == HORIZON)
        assert info["step"] == k


def test_success_reward_and_reward_terms() -> None:
    env = InsertionEnv(tolins.CircularSocket(2, 2), measurement_noise=0)
    env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, 1.0]})
    total, terminated, k = 0.0, False, 0
    while not terminated:
        _, reward, terminated, truncated, info = env.step([0, 0, 0, -2.5])
        k += 1
        assert reward == info["reward_success"] + info["reward_collision"]
        assert not truncated
        total += reward
    assert info["success"] and info["is_success"]
    assert info["pose"][3] <= -env.success_depth
    assert k == 4  # 1 mm above + 1 mm deep at 0.625 mm per step
    assert info["reward_success"] == pytest.approx(SUCCESS_REWARD * (1 - k / HORIZON))
    assert info["n_collisions"] == 0 and total == info["reward_success"]


def test_simulator_fault_truncates_with_an_error_and_finite_observation(
    env: InsertionEnv, tmp_path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo logs the warning to ./MUJOCO_LOG.TXT
    observation, _ = env.reset(seed=0)
    env.backend.data.qvel[0] = np.nan
    next_observation, reward, terminated, truncated, info = env.step(np.zeros(4))
    assert truncated and not terminated and reward == 0.0
    assert "BADQVEL" in info["error"]
    assert np.all(np.isfinite(next_observation))
    assert np.array_equal(next_observation, observation)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"backend": "bullet"}, "backend"),
        ({"measurement_noise": [0.1, 0.1]}, "measurement_noise"),
        ({"measurement_noise": -0.1}, "measurement_noise"),
        ({"force_noise": np.nan}, "force_noise"),
        ({"goal": [0.0, np.inf, 0.0]}, "goal"),
        ({"horizon": 0}, "horizon"),
        ({"horizon": 2.5}, "horizon"),
        ({"defect_sigma": -0.1}, "defect_sigma"),
        ({"success_depth": "deep"}, "success_depth"),
        ({"success_depth": -1.0}, "success_depth"),
        ({"collision_force": np.nan}, "collision_force"),
        ({"defect_sigma": 0.1, "socket": tolins.PolygonSocket(4, 1.5, 1.65)}, "defect_sigma"),
        ({"socket": "2x2"}, "socket"),
        ({"render_mode": "human"}, "render_mode"),
    ],
)
def test_invalid_env_arguments_raise(kwargs: dict, field: str) -> None:
    kwargs = {"socket": tolins.CircularSocket(2, 2), **kwargs}
    with pytest.raises(ValueError, match=field):
        InsertionEnv(kwargs.pop("socket"), **kwargs)


def test_invalid_reset_options_raise(env: InsertionEnv) -> None:
    with pytest.raises(ValueError, match="unknown"):
        env.reset(options={"start": ABOVE})
    with pytest.raises(ValueError, match="pose"):
        env.reset(options={"pose": [0.0, 0.0, np.nan, 1.0]})


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_rgb_array_render_shows_the_parts(backend: str) -> None:
    env = InsertionEnv(tolins.CircularSocket(2, 4), backend=backend, render_mode="rgb_array")
    env.reset(seed=0, options={"pose": [0.8, 0.5, 0.05, 1.0]})
    try:
        image = env.render()
    except Exception as error:  # no OpenGL (EGL) on this machine
        env.close()
        pytest.skip(f"headless OpenGL unavailable: {error}")
    drawn_x = env.backend.data.qpos[env.backend.model.joint("x").qposadr[0]]
    env.close()  # releases the backend: read the drawn pose before
    assert image.shape == (480, 640, 3) and image.dtype == np.uint8
    board_green = (image[..., 1] > image[..., 0] + 30) & (image[..., 1] > image[..., 2] + 30)
    pin_gold = (image[..., 0] > 150) & (image[..., 2] < 100)
    assert board_green.mean() > 0.1 and pin_gold.sum() > 200
    assert drawn_x == 0.8  # the drawing model shows the backend's pose
