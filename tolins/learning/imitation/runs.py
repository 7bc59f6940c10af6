"""``tolins train bc|rs-gail|tolerance-guided``: whole runs that write their artefacts.

Every artefact (``policy.pt``, ``checkpoint.pt``, ``run.json``; RS-GAIL runs also
``means.npy``, the policy's parameters over training) records the configs, the
seed and ``tolins.__version__`` (:func:`tolins.learning.artefacts.run_metadata`).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tolins.atomic import atomic_json, atomic_write
from tolins.learning.artefacts import run_metadata
from tolins.learning.curves import plot_curves, write_curves_csv
from tolins.learning.imitation.bc import BCResult, behaviour_clone
from tolins.learning.imitation.config import BCConfig, ResidualConfig, RSGailConfig, TaskConfig
from tolins.learning.imitation.demonstrations import collect
from tolins.learning.imitation.policy import load_policy, save_policy
from tolins.learning.imitation.rs_gail import (
    RSGailResult,
    Workpiece,
    check_resumable,
    train_rs_gail,
)
from tolins.learning.imitation.tolerance_guided import train_tolerance_guided, workpieces
from tolins.rollouts.episodes import Episode
from tolins.rollouts.pool import CandidatePool

#: The CMA-ES mean of every iteration, then the final policy's parameters (``.npy``).
MEANS = "means.npy"


@dataclass(frozen=True)
class Demos:
    """Demonstrations from elsewhere (a Minari dataset, ``tolins train --demos``): where
    they came from (recorded in ``run.json``) and their episodes."""

    source: str
    rollouts: list[Episode]


def demonstrations(env_ids: list[str], task: TaskConfig) -> list[Episode]:
    """The expert's episodes on each env (seeded from ``task.seed`` and the env's index)."""
    episodes = []
    for index, env_id in enumerate(env_ids):
        seed = task.seed * 1000 + index
        episodes += collect(env_id, task.expert, task.demonstrations, seed, task.backend)
    return episodes


def trained_bc(env_id: str, backend: str, seed: int) -> Callable[[np.ndarray], np.ndarray]:
    """π_bc of ``tolins train bc --env ENV_ID --seed SEED --backend BACKEND`` with the
    default configs, ready to act and not written anywhere (a few seconds of training)."""
    task = TaskConfig(backend=backend, seed=seed)
    return behaviour_clone(demonstrations([env_id], task), BCConfig(), seed=seed).policy.bind()


def _demos_metadata(demos: Demos | None) -> dict[str, Any]:
    """What a run records of demonstrations read from a dataset (nothing for the expert's)."""
    if demos is None:
        return {}
    return {"demos": {"dataset": demos.source, "episodes": len(demos.rollouts)}}


def run_bc(
    env_id: str, task: TaskConfig, bc: BCConfig, out: str | Path, *, demos: Demos | None = None
) -> BCResult:
    """Clone the expert (or the episodes of ``demos``, read from a dataset); write
    ``policy.pt``, ``bc_loss.csv`` and ``run.json``."""
    out = Path(out)
    metadata = run_metadata(task.seed, env=env_id, task=task, bc=bc, **_demos_metadata(demos))
    expert = demonstrations([env_id], task) if demos is None else demos.rollouts
    result = behaviour_clone(expert, bc, seed=task.seed)
    save_policy(out / "policy.pt", result.policy, metadata)
    rows = [{"epoch": i, "loss": loss} for i, loss in enumerate(result.losses)]
    write_curves_csv(out / "bc_loss.csv", rows)
    fit = {
        "train_loss": result.train_loss,
        "held_out_loss": result.held_out_loss,
        "held_out_episodes": result.held_out_episodes,
        "first_epoch_loss": result.losses[0],
    }
    atomic_json(out / "run.json", {**metadata, "fit": fit})
    return result


def run_rs_gail(
    env_id: str,
    task: TaskConfig,
    bc: BCConfig,
    rs_gail: RSGailConfig,
    out: str | Path,
    *,
    init: str | None = None,
    resume: bool = False,
    progress: bool = True,
    pool: CandidatePool | None = None,
    demos: Demos | None = None,
) -> RSGailResult:
    """π_n: RS-GAIL from the BC policy ``init`` (or one cloned here with ``bc``), imitating
    the expert (or the episodes of ``demos``, read from a dataset)."""
    out = Path(out)
    start = None if init is None else _relative(init, out)
    metadata = run_metadata(
        task.seed,
        env=env_id,
        init=start,
        task=task,
        bc=bc,
        rs_gail=rs_gail,
        **_demos_metadata(demos),
    )
    if resume:
        check_resumable(out, metadata)
    if init is not None:
        policy, _ = load_policy(init, kind="nominal")
    expert = demonstrations([env_id], task) if demos is None else demos.rollouts
    if init is None:
        policy = behaviour_clone(expert, bc, seed=task.seed).policy
    result = train_rs_gail(
        policy,
        [Workpiece(env_id)],
        expert,
        rs_gail,
        seed=task.seed,
        backend=task.backend,
        out=out,
        metadata=metadata,
        resume=resume,
        progress=progress,
        pool=pool,
    )
    _finish(out, result, metadata, f"RS-GAIL on {env_id}")
    return result


def run_tolerance_guided(
    env_ids: list[str],
    task: TaskConfig,
    rs_gail: RSGailConfig,
    residual: ResidualConfig,
    out: str | Path,
    *,
    nominal: str,
    resume: bool = False,
    progress: bool = True,
    pool: CandidatePool | None = None,
    demos: Demos | None = None,
) -> RSGailResult:
    """π_φ: φ2 by RS-GAIL over ``env_ids`` with φ1 from the nominal policy file ``nominal``,
    imitating the expert on every env (or the episodes of ``demos``, in env order)."""
    out = Path(out)
    metadata = run_metadata(
        task.seed,
        env=",".join(env_ids),
        nominal=_relative(nominal, out),
        task=task,
        rs_gail=rs_gail,
        residual=residual,
        **_demos_metadata(demos),
    )
    if resume:
        check_resumable(out, metadata)
    policy, _ = load_policy(nominal, kind="nominal")
    pieces = workpieces(env_ids)
    expert = demonstrations(env_ids, task) if demos is None else demos.rollouts
    result = train_tolerance_guided(
        policy,
        pieces,
        expert,
        rs_gail,
        residual,
        seed=task.seed,
        backend=task.backend,
        out=out,
        metadata=metadata,
        resume=resume,
        progress=progress,
        pool=pool,
    )
    _finish(out, result, metadata, f"tolerance-guided on {', '.join(env_ids)}")
    return result


def _relative(path: str | Path, out: Path) -> str:
    """``path`` relative to the run folder ``out``: what the metadata records, so that a
    run folder moved together with its inputs (a bench's stages) still resumes."""
    return os.path.relpath(Path(path).resolve(), out.resolve())


def _finish(out: Path, result: RSGailResult, metadata: dict[str, Any], title: str) -> None:
    save_policy(out / "policy.pt", result.policy, metadata)
    atomic_write(out / MEANS, lambda file: np.save(file, result.means))
    if result.history:
        plot_curves(out / "curves.png", result.history, title)
    summary = {
        "stopped": result.stopped,
        "iterations": len(result.history),
        "selected": result.selected,
        "final": result.final,
    }
    atomic_json(out / "run.json", {**metadata, "result": summary})
