"""Table 1's figures of a set of episodes: the mean and std of each."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tolins.rollouts.episodes import Episode


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
