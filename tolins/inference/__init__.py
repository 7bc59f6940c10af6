"""Probabilistic inference of bent pins from failed insertions, and the next insertion goal.

The paper's section "Probabilistic Inference": a particle posterior over the pin offsets
(:mod:`.posterior`), CMA-ES over the next goal (:mod:`.goal`) and the numerical study
(:mod:`.study`). Beside the bent-pin prior, :class:`DefectModel` adds pitch error, burrs,
a blocked hole and a grasp error (a common motion of every pin), and the goal search's
result says when a workpiece is not insertable.
Imports :mod:`tolins.geometry` only.
"""

from tolins.inference.goal import GoalResult, centre_goals, expected_success, find_goal, next_goal
from tolins.inference.history import History
from tolins.inference.posterior import (
    DefectModel,
    Posterior,
    log_likelihood,
    sample_defect_posterior,
    sample_posterior,
)

__all__ = [
    "DefectModel",
    "GoalResult",
    "History",
    "Posterior",
    "centre_goals",
    "expected_success",
    "find_goal",
    "log_likelihood",
    "next_goal",
    "sample_defect_posterior",
    "sample_posterior",
]
