"""The SB3 adapter over the vector env steps as SB3's DummyVecEnv of single envs does."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv

from tolins.envs.wrappers import agent_env
from tolins.rollouts.sb3_vec import Sb3VectorEnv


@pytest.mark.parametrize("backend", ["kinematic", "mujoco"])
def test_the_adapter_steps_as_a_dummy_vec_env_of_single_envs(backend) -> None:
    env_id, n = "tolins/Circle2x2-v1", 3
    ours = Sb3VectorEnv(env_id, n, backend=backend, reward_mode="dense")
    theirs = DummyVecEnv([lambda: agent_env(env_id, backend=backend, reward_mode="dense")] * n)
    ours.seed(11)
    theirs.seed(11)
    assert np.array_equal(ours.reset(), theirs.reset())
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(90 if backend == "kinematic" else 45):
        actions = rng.uniform(-1, 1, (n, 4)).astype(np.float32)
        actions[:, 3] = -1.0  # down, into contact and to the horizon
        a, b = ours.step(actions), theirs.step(actions)
        for x, y in zip(a[:3], b[:3], strict=True):
            assert x.dtype == y.dtype and np.array_equal(x, y)
        for mine, expected in zip(a[3], b[3], strict=True):
            assert set(mine) == set(expected)
            for key, value in expected.items():
                assert np.array_equal(np.asarray(mine[key]), np.asarray(value)), key
        ended += int(a[2].sum())
    assert ended >= n  # every env reached its horizon and was reset at least once


def test_ppo_learns_on_several_envs_of_one_batch() -> None:
    env = Sb3VectorEnv("tolins/Circle2x2-v1", 4, backend="kinematic", reward_mode="dense")
    model = PPO("MlpPolicy", env, n_steps=32, batch_size=64, seed=0, device="cpu")
    model.learn(256)
    assert model.num_timesteps == 256
    action, _ = model.predict(env.reset(), deterministic=True)
    assert action.shape == (4, 4) and np.all(np.abs(action) <= 1)


def test_get_attr_and_set_attr_answer_per_env_as_a_dummy_vec_env() -> None:
    env_id, n = "tolins/Circle2x1Defective-v1", 3
    ours = Sb3VectorEnv(env_id, n, backend="kinematic")
    theirs = DummyVecEnv([lambda: agent_env(env_id, backend="kinematic")] * n)
    ours.seed(5)
    theirs.seed(5)
    ours.reset()
    theirs.reset()
    # each env's own bent workpiece, as DummyVecEnv's envs hold theirs
    assert ours.get_attr("socket") == theirs.get_attr("socket")
    assert len(set(map(repr, ours.get_attr("socket")))) == n
    assert ours.get_attr("socket", indices=[2]) == theirs.get_attr("socket", indices=[2])
    goal = np.array([0.05, -0.05, 0.01])
    ours.set_attr("goal", goal, indices=[1])
    theirs.set_attr("goal", goal, indices=[1])
    for mine, expected in zip(ours.get_attr("goal"), theirs.get_attr("goal"), strict=True):
        assert np.array_equal(mine, expected)
    assert np.array_equal(ours.get_attr("goal")[1], goal)
    assert not np.array_equal(ours.get_attr("goal")[0], goal)
    assert ours.get_attr("spec") == [ours.vector.unwrapped.spec] * n  # the batch's own
