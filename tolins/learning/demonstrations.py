"""Expert demonstrations: the (observation, action) pairs of scripted experts' episodes."""

from __future__ import annotations

import numpy as np

from tolins.policies.experts import EXPERTS
from tolins.rollouts.episodes import Rollout, make_env, rollout


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
