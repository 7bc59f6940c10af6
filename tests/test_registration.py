"""Gymnasium registration from the task table, and vector environments."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import tolins
from tolins.envs import GENERIC_ID, TASKS, InsertionEnv
from tolins.envs.tasks import DEFECT_SIGMA, register_envs

PAPER_IDS = [
    "tolins/Circle2x1-v1",
    "tolins/Circle2x2-v1",
    "tolins/Circle2x4-v1",
    "tolins/Circle2x8-v1",
    "tolins/Circle2x1Defective-v1",
    "tolins/Square-v1",
    "tolins/Pentagon-v1",
    "tolins/Hexagon-v1",
]


def test_every_paper_workpiece_is_registered_from_the_task_table() -> None:
    assert [task.gym_id for task in TASKS] == PAPER_IDS
    for gym_id in [*PAPER_IDS, GENERIC_ID]:
        assert gym_id in gym.registry
    register_envs()  # a second call is harmless


@pytest.mark.parametrize("task", TASKS, ids=lambda t: t.name)
def test_registered_env_has_the_tasks_socket(task) -> None:
    env = gym.make(task.gym_id).unwrapped
    assert isinstance(env, InsertionEnv)
    assert env.nominal_socket == task.socket
    assert env.defect_sigma == task.defect_sigma
    assert set(task.tags) >= {"paper", task.socket.family}


def test_table_1_sizes() -> None:
    sockets = {task.name: task.socket for task in TASKS}
    assert sockets["Circle2x4"] == tolins.CircularSocket(2, 4, 0.3, 0.5, 7.62, 2.54)
    assert sockets["Square"] == tolins.PolygonSocket(4, 1.5, 1.65)
    assert sockets["Pentagon"] == tolins.PolygonSocket(5, 1.5, 1.65)
    assert sockets["Hexagon"] == tolins.PolygonSocket(6, 1.2, 1.26)
    assert DEFECT_SIGMA > 0


def test_generic_id_takes_socket_and_backend_kwargs() -> None:
    env = gym.make(GENERIC_ID, socket=tolins.CircularSocket(3, 2), backend="mujoco")
    observation, info = env.reset(seed=0)
    assert observation.shape == (8,) and info["pose"].shape == (4,)
    with pytest.raises(ValueError, match="backend"):
        gym.make(GENERIC_ID, socket=tolins.CircularSocket(3, 2), backend="bullet")


@pytest.mark.parametrize(
    ("mode", "vector_kwargs"),
    [("sync", {}), ("async", {}), ("async", {"context": "spawn"})],
    ids=["sync", "async-fork", "async-spawn"],
)
def test_make_vec(mode: str, vector_kwargs: dict) -> None:
    envs = gym.make_vec(
        "tolins/Square-v1", num_envs=2, vectorization_mode=mode, vector_kwargs=vector_kwargs
    )
    try:
        observations, infos = envs.reset(seed=[1, 2])
        assert observations.shape == (2, 8)
        assert not np.array_equal(observations[0], observations[1])
        actions = np.tile([0.5, -0.5, 0.0, -2.5], (2, 1))
        for _ in range(3):
            observations, rewards, _, _, infos = envs.step(actions)
        assert observations.shape == (2, 8) and rewards.shape == (2,)
        assert np.all(np.isfinite(observations))
        assert infos["pose"].shape == (2, 4)
    finally:
        envs.close()


def test_vector_env_matches_single_envs() -> None:
    envs = gym.make_vec("tolins/Circle2x2-v1", num_envs=2, vectorization_mode="sync")
    singles = [gym.make("tolins/Circle2x2-v1") for _ in range(2)]
    observations, _ = envs.reset(seed=[5, 6])
    for i, env in enumerate(singles):
        assert np.array_equal(env.reset(seed=5 + i)[0], observations[i])
    actions = np.array([[1.0, 0.0, 0.05, -2.5], [-1.0, 2.0, 0.0, -1.0]])
    observations, *_ = envs.step(actions)
    for i, env in enumerate(singles):
        assert np.array_equal(env.step(actions[i])[0], observations[i])
    envs.close()
