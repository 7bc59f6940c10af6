"""Run a policy's episodes in one env and summarise them: the single-env loop.

:func:`run_episode` keeps what Table 1 counts (:class:`Episode`), :func:`rollout` also the
episode's (observation, action) pairs (:class:`Rollout`, for imitation). Many episodes at
once go through the vector env (:mod:`tolins.rollouts.runner`), which gives the same
records bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import tolins.envs  # noqa: F401  (registers the env ids)
from tolins.envs.episode import check_action
from tolins.envs.tasks import check_env_id
from tolins.rollouts.forces import ForceScores, ForceTracker

Policy = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Episode:
    """What one episode came to; ``forces`` are its force-aware scores and ``profile``
    each step's ``(depth mm, peak normal force N)`` (:mod:`tolins.rollouts.forces`; both
    ``None`` in a record made before tolins 0.4)."""

    reward: float
    success: bool
    steps: int
    collisions: int
    error: str | None = None
    forces: ForceScores | None = None
    profile: tuple[tuple[float, float], ...] | None = None


def episode_from_dict(row: dict) -> Episode:
    """The :class:`Episode` of ``dataclasses.asdict(episode)`` (as JSON gives it back)."""
    forces, profile = row.get("forces"), row.get("profile")
    return Episode(
        **{
            **row,
            "forces": None if forces is None else ForceScores(**forces),
            "profile": None if profile is None else tuple(tuple(p) for p in profile),
        }
    )


def run_episode(env: gym.Env, policy: Policy, seed: int | None = None) -> Episode:
    """Run ``policy`` in ``env`` from ``reset(seed=seed)`` until the episode ends."""
    observation, info = env.reset(seed=seed)
    forces = ForceTracker.of(env.unwrapped.settings, info)
    total, done = 0.0, False
    while not done:
        observation, reward, terminated, truncated, info = env.step(policy(observation))
        forces.step(info["peak_force"], info["pose"][3])
        total += reward
        done = terminated or truncated
    return Episode(
        total,
        bool(info["success"]),
        int(info["step"]),
        int(info["n_collisions"]),
        info.get("error"),
        forces.scores(),
        forces.profile(),
    )


@dataclass(frozen=True)
class Summary:
    """Mean and std of each figure of the paper's Table 1 over episodes."""

    episodes: int
    reward_mean: float
    reward_std: float
    success_mean: float
    success_std: float
    steps_mean: float
    steps_std: float
    collisions_mean: float
    collisions_std: float
    faults: int


def summarise(episodes: list[Episode]) -> Summary:
    """Table 1's figures of ``episodes``."""
    if not episodes:
        raise ValueError("no episodes to summarise; allowed: at least one")
    columns = {
        "reward": [e.reward for e in episodes],
        "success": [float(e.success) for e in episodes],
        "steps": [e.steps for e in episodes],
        "collisions": [e.collisions for e in episodes],
    }
    stats = {}
    for name, values in columns.items():
        stats[f"{name}_mean"] = float(np.mean(values))
        stats[f"{name}_std"] = float(np.std(values))
    return Summary(len(episodes), **stats, faults=sum(e.error is not None for e in episodes))


def episode_poses(env: gym.Env, policy: Policy, seed: int | None = None) -> np.ndarray:
    """The workpiece poses ``(steps + 1, 4)`` = ``[x, y, theta, z]`` of one episode, from
    the initial pose to the last."""
    observation, info = env.reset(seed=seed)
    poses, done = [info["pose"]], False
    while not done:
        observation, _, terminated, truncated, info = env.step(policy(observation))
        poses.append(info["pose"])
        done = terminated or truncated
    return np.array(poses)


@dataclass(frozen=True)
class Rollout:
    """One episode: ``observations`` ``(T, 8)``, ``actions`` ``(T, 4)`` (clipped as the env
    applies them), return, success, collisions."""

    observations: np.ndarray
    actions: np.ndarray
    reward: float
    success: bool
    collisions: int


def rollout(env: gym.Env, policy: Policy, seed: int) -> Rollout:
    """One episode of ``policy`` in ``env`` from ``reset(seed=seed)``, keeping its pairs."""
    observation, info = env.reset(seed=seed)
    observations, actions, total, done = [], [], 0.0, False
    while not done:
        action = check_action(policy(observation))
        observations.append(observation)
        actions.append(action)
        observation, reward, terminated, truncated, info = env.step(action)
        total += reward
        done = terminated or truncated
    return Rollout(
        np.array(observations),
        np.array(actions),
        total,
        bool(info["success"]),
        int(info["n_collisions"]),
    )


def make_env(env_id: str, backend: str) -> gym.Env:
    """The unwrapped env ``env_id`` on ``backend`` (no wrappers: rollouts end on their own)."""
    return gym.make(check_env_id(env_id), backend=backend).unwrapped
