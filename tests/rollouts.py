"""Episodes (and tiny trainings) the tests run again and again, shared by several test
modules."""

from __future__ import annotations

from collections.abc import Callable

import gymnasium as gym
import numpy as np

from tolins.envs import InsertionEnv
from tolins.paper import A_MAX, HORIZON


def push_down(
    socket, pose, steps: int = HORIZON, speed: float = A_MAX[3], backend: str = "mujoco"
) -> list[dict]:
    """The infos of pushing straight down from ``pose`` with noise off, until the episode
    ends or ``steps`` steps."""
    env = InsertionEnv(socket, backend=backend, measurement_noise=0)
    env.reset(seed=0, options={"pose": pose})
    infos = []
    for _ in range(steps):
        *_, terminated, truncated, info = env.step([0.0, 0.0, 0.0, -speed])
        infos.append(info)
        if terminated or truncated:
            break
    return infos


def random_rollout(
    env: gym.Env, seed: int, steps: int = HORIZON, shape: Callable | None = None
) -> list[np.ndarray]:
    """The observations of uniformly random actions (seeded apart from ``seed``), each
    passed through ``shape`` if given, from ``reset(seed=seed)``."""
    rng = np.random.default_rng(123)
    observation, _ = env.reset(seed=seed)
    observations = [observation]
    for _ in range(steps):
        action = rng.uniform(-A_MAX, A_MAX)
        observation, *_, terminated, truncated, _ = env.step(shape(action) if shape else action)
        observations.append(observation)
        if terminated or truncated:
            break
    return observations


def train_rs_gail_on_kinematic(policy, demos, out, config, env_id: str, **kwargs):
    """RS-GAIL from ``policy`` on ``env_id``'s kinematic backend, seed 0, no progress bar
    (``kwargs``: more keywords of ``train_rs_gail``)."""
    from tolins.learning.imitation.rs_gail import Workpiece, train_rs_gail

    return train_rs_gail(
        policy,
        [Workpiece(env_id)],
        demos,
        config,
        seed=0,
        backend="kinematic",
        out=out,
        metadata={"test": 1},
        progress=False,
        **kwargs,
    )
