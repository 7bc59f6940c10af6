"""Expert demonstrations: (observation, action) pairs of scripted experts, and rollouts
of any policy that keep their pairs (for the discriminator)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the env ids)
from tolins.envs.episode import check_action
from tolins.policies.experts import EXPERTS

Policy = Callable[[np.ndarray], np.ndarray]


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
    if env_id not in gym.registry:
        ids = sorted(i for i in gym.registry if i.startswith("tolins/"))
        raise ValueError(f"unknown env {env_id!r}; allowed: {', '.join(ids)}")
    return gym.make(env_id, backend=backend).unwrapped


def collect(env_id: str, expert: str, episodes: int, seed: int, backend: str) -> list[Rollout]:
    """``episodes`` episodes of the scripted ``expert`` with seeds derived from ``seed``."""
    env = make_env(env_id, backend)
    seeds = np.random.SeedSequence([seed, 0xDE70]).generate_state(episodes)
    try:
        return [rollout(env, EXPERTS[expert](), int(s)) for s in seeds]
    finally:
        env.close()


def pairs(rollouts: list[Rollout]) -> tuple[np.ndarray, np.ndarray]:
    """All ``(observations, actions)`` of ``rollouts``, stacked."""
    return (
        np.concatenate([r.observations for r in rollouts]),
        np.concatenate([r.actions for r in rollouts]),
    )
