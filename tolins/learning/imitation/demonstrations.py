"""Expert demonstrations: the (observation, action) pairs of scripted experts' episodes."""

from __future__ import annotations

import numpy as np

from tolins.policies.experts import EXPERTS
from tolins.rollouts.collectors import Pairs
from tolins.rollouts.episodes import Episode, make_env, run_episode


def collect(env_id: str, expert: str, episodes: int, seed: int, backend: str) -> list[Episode]:
    """``episodes`` episodes of the scripted ``expert`` with seeds derived from ``seed``,
    their (observation, action) pairs kept."""
    env = make_env(env_id, backend)
    seeds = np.random.SeedSequence([seed, 0xDE70]).generate_state(episodes)
    try:
        return [run_episode(env, EXPERTS[expert](), int(s), (Pairs(),)) for s in seeds]
    finally:
        env.close()


def pairs(rollouts: list[Episode]) -> tuple[np.ndarray, np.ndarray]:
    """All ``(observations, actions)`` of ``rollouts``, stacked."""
    return (
        np.concatenate([r.observations for r in rollouts]),
        np.concatenate([r.actions for r in rollouts]),
    )
