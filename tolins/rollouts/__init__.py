"""Running episodes: the single-env loop, the vector-env runner and the candidate pools.

Below ``tolins.learning``: policies come in as callables (or as objects with
``with_flat``/``bind``, :class:`~tolins.rollouts.pool.ParametricPolicy`), and nothing here
imports a learning type.
"""

from tolins.rollouts.episodes import (
    Episode,
    Policy,
    Rollout,
    Summary,
    episode_poses,
    make_env,
    rollout,
    run_episode,
    summarise,
)
from tolins.rollouts.pool import CandidatePool, VectorPool, Workpiece
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs

__all__ = [
    "CandidatePool",
    "Episode",
    "Job",
    "Policy",
    "Rollout",
    "Summary",
    "VectorEnvCache",
    "VectorPool",
    "Workpiece",
    "episode_poses",
    "make_env",
    "rollout",
    "run_episode",
    "run_jobs",
    "summarise",
]
