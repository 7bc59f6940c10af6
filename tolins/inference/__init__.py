"""Probabilistic inference of bent pins from failed insertions, and the next insertion goal.

The paper's section "Probabilistic Inference": a particle posterior over the pin offsets
(:mod:`.posterior`), CMA-ES over the next goal (:mod:`.goal`) and the numerical study
(:mod:`.study`). Imports :mod:`tolins.geometry` only.
"""

from tolins.inference.goal import GoalResult, centre_goals, expected_success, find_goal, next_goal
from tolins.inference.history import History
from tolins.inference.posterior import Posterior, log_likelihood, sample_posterior

__all__ = [
    "GoalResult",
    "History",
    "Posterior",
    "centre_goals",
    "expected_success",
    "find_goal",
    "log_likelihood",
    "next_goal",
    "sample_posterior",
]
