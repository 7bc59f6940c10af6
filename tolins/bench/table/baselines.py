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
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tolins.bench.table.rows import SB3_METHODS, TRAININGS, seed_order, unseeded

#: Curve of one stage: ``env_steps``, ``reward``, ``success`` as arrays.
Curve = dict[str, np.ndarray]


#: The columns every ``curves.csv`` has (RS-GAIL's and the deep-RL baselines').
CURVE_COLUMNS = ("env_steps", "reward", "success")


def read_curves(path: Path) -> list[dict[str, float]]:
    """The rows of the ``curves.csv`` at ``path``, every value a float; ``ValueError``
    naming the file when it is not one (not UTF-8 text, a value that is not a number, no
    :data:`CURVE_COLUMNS`)."""
    allowed = f"allowed: a CSV of numbers with columns {', '.join(CURVE_COLUMNS)}"
    try:
        with open(path, encoding="utf-8", newline="") as file:
            reader = csv.DictReader(file)
            rows = [{k: float(v) for k, v in row.items()} for row in reader]
            missing = sorted(set(CURVE_COLUMNS) - set(reader.fieldnames or ()))
    except (ValueError, TypeError, csv.Error) as error:  # UnicodeDecodeError too
        raise ValueError(f"{path}: not a CSV of numbers ({error}); {allowed}") from None
    if missing:
        raise ValueError(f"{path}: no column {', '.join(missing)}; {allowed}")
    return rows


def env_step_curves(
    stage_folders: dict[str, Path],
    read: Callable[[Path], list[dict[str, float]]] = read_curves,
) -> dict[str, Curve]:
    """The curve of every RS-GAIL π_n and SB3 stage in ``stage_folders`` (stage name →
    folder), labelled by stage name, x axis in env steps; ``read`` reads a ``curves.csv``
    (the bench's: :func:`tolins.bench.store.integrity.read_stage_curves`)."""
    curves = {}
    for stage, folder in stage_folders.items():
        training = TRAININGS.get(unseeded(stage))
        path = Path(folder) / "curves.csv"
        if training is None or not path.is_file():
            continue
        if training.method not in (*SB3_METHODS, "rs-gail"):
            continue
        rows = read(path)
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


def curves_json(curves: Mapping[str, Curve]) -> dict[str, dict[str, list[float]]]:
    """``curves`` as JSON (``curves.json`` of a run): stage → column → values."""
    return {
        stage: {key: [float(v) for v in values] for key, values in curve.items()}
        for stage, curve in curves.items()
    }


def curves_from_json(document: Mapping[str, Any]) -> dict[str, Curve]:
    """The curves of a ``curves.json`` document (:func:`curves_json`)."""
    return {
        stage: {key: np.asarray(values, dtype=float) for key, values in curve.items()}
        for stage, curve in document.items()
    }


def first_success(curve: Curve) -> float | None:
    """The env steps of the curve's first point whose success rate is above 0 (``None``:
    it never leaves zero)."""
    above = np.flatnonzero(curve["success"] > 0)
    return float(curve["env_steps"][above[0]]) if len(above) else None


@dataclass(frozen=True)
class CurveSummary:
    """One training's curves over its seeds: the env steps each seed's curve left a success
    rate of 0 (``None``: never), and the last point's reward and success, mean over seeds."""

    training: str
    env_steps: float
    first_success: tuple[float | None, ...]
    last_reward: float
    last_success: float


def summarise_curves(curves: Mapping[str, Curve]) -> list[CurveSummary]:
    """:class:`CurveSummary` of each training in ``curves`` (stage name → curve), in
    :data:`~tolins.bench.table.rows.TRAININGS` order."""
    by_training: dict[str, list[Curve]] = {}
    for stage in sorted(curves, key=seed_order):
        curve = curves[stage]
        by_training.setdefault(unseeded(stage), []).append(curve)
    return [
        CurveSummary(
            name,
            float(np.mean([c["env_steps"][-1] for c in seeds])),
            tuple(first_success(c) for c in seeds),
            float(np.mean([c["reward"][-1] for c in seeds])),
            float(np.mean([c["success"][-1] for c in seeds])),
        )
        for name in TRAININGS
        if (seeds := by_training.get(name))
    ]
