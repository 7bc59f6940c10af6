"""RS-GAIL against the deep-RL baselines at equal env steps: the curves of a bench run.

Both kinds of stage write ``curves.csv`` with an ``env_steps`` column and the sparse
(paper's) reward of the current policy. RS-GAIL's rows are per iteration and count the
steps of that iteration (``popsize × candidate_episodes`` candidate episodes and the
``curve_episodes`` of the CMA-ES mean): the cumulative sum is the x axis. The SB3
baselines' rows already hold the steps trained so far (their curve episodes are not
counted: they do not train). RS-GAIL starts from BC on 50 expert demonstrations, whose
expert steps are not counted either.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from tolins.bench.table.rows import SB3_METHODS, TRAININGS

#: Curve of one stage: ``env_steps``, ``reward``, ``success`` as arrays.
Curve = dict[str, np.ndarray]


def read_curves(path: Path) -> list[dict[str, float]]:
    """The rows of the ``curves.csv`` at ``path``, every value a float."""
    with open(path) as file:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(file)]


def env_step_curves(stage_folders: dict[str, Path]) -> dict[str, Curve]:
    """The curve of every RS-GAIL π_n and SB3 stage in ``stage_folders`` (stage name →
    folder), labelled by stage name, x axis in env steps."""
    curves = {}
    for stage, folder in stage_folders.items():
        training = TRAININGS.get(stage.rsplit("-seed", 1)[0])
        path = Path(folder) / "curves.csv"
        if training is None or not path.is_file():
            continue
        if training.method not in (*SB3_METHODS, "rs-gail"):
            continue
        rows = read_curves(path)
        if not rows:
            continue
        steps = np.array([row["env_steps"] for row in rows])
        if training.method == "rs-gail":
            steps = np.cumsum(steps)
        curves[stage] = {
            "env_steps": steps,
            "reward": np.array([row["reward"] for row in rows]),
            "success": np.array([row["success"] for row in rows]),
        }
    return curves
