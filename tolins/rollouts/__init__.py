"""Running episodes: one episode loop and its collectors, the vector-env runner and the
candidate pools.

Below ``tolins.learning``: policies come in as callables (or as objects with
``with_flat``/``bind``, :class:`~tolins.rollouts.pool.ParametricPolicy`), and nothing here
imports a learning type.
"""

from tolins.rollouts.collectors import Collector, Forces, Outcome, Pairs, Poses
from tolins.rollouts.episodes import (
    Episode,
    EpisodeRun,
    Policy,
    episode_from_dict,
    episode_poses,
    episode_to_dict,
    make_env,
    run_episode,
)
from tolins.rollouts.pool import CandidatePool, VectorPool, Workpiece
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs
from tolins.rollouts.summary import Summary, summarise

__all__ = [
    "CandidatePool",
    "Collector",
    "Episode",
    "EpisodeRun",
    "Forces",
    "Job",
    "Outcome",
    "Pairs",
    "Policy",
    "Poses",
    "Summary",
    "VectorEnvCache",
    "VectorPool",
    "Workpiece",
    "episode_from_dict",
    "episode_poses",
    "episode_to_dict",
    "make_env",
    "run_episode",
    "run_jobs",
    "summarise",
]
