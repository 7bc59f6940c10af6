"""The figures of a benchmark run (``table.png``, the learning and env-step curves, π_n's
trajectories, the force profiles, the tolerance images, one plot per claim), drawn from
its results and its finished stages."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from tolins.bench.jobs import trajectories
from tolins.bench.reports import plots
from tolins.bench.reports.force_plot import plot_row_profiles
from tolins.bench.store.integrity import read_stage_curves
from tolins.bench.table.baselines import Curve
from tolins.bench.table.rows import ALL_ROWS, PAPER, TRAININGS
from tolins.envs.tasks import TASKS, task_of

if TYPE_CHECKING:
    from tolins.bench.pipeline.config import BenchRun


#: The figures a run draws into its folder (besides ``claims/`` and ``force_profiles/``).
FIGURES = (
    "table.png",
    "learning_curves.png",
    "env_step_curves.png",
    "trajectories.png",
    "tolerance_images.png",
    "robustness.png",
    "inference_study.png",
    "timeline.png",
)


def remove_figures(out: Path) -> None:
    """Remove the figures of an earlier run from ``out`` (a run without figures: they would
    read as this run's)."""
    for name in FIGURES:
        (out / name).unlink(missing_ok=True)
    for folder in ("claims", "force_profiles"):
        for path in (out / folder).glob("*.png"):
            path.unlink()


def write_figures(run: BenchRun, out: Path, step_curves: dict[str, Curve]) -> list[Path]:
    """Draw every figure of ``run`` into ``out`` (``step_curves``: its stages'
    :func:`~tolins.bench.table.baselines.env_step_curves`); the paths written."""
    results = run.results
    written = [plots.plot_table(out / "table.png", results, PAPER)]
    curves = _learning_curves(run)
    if curves:
        written.append(plots.plot_learning_curves(out / "learning_curves.png", curves))
    if step_curves:
        written.append(plots.plot_env_step_curves(out / "env_step_curves.png", step_curves))
    fig_4a = _training_trajectories(run)
    if fig_4a is not None:
        written.append(fig_4a)
    env_ids = []
    for row in ALL_ROWS:
        if row.id in results:
            env_ids += [*(t for tr in row.trainings for t in tr.env_ids), row.eval_env]
    written += plot_row_profiles({row: seeds[0] for row, seeds in run.episodes.items()}, out)
    used = {task_of(env_id).name for env_id in env_ids}
    sockets = {t.name: t.socket for t in TASKS if t.name in used}
    written.append(plots.plot_tolerance_images(out / "tolerance_images.png", sockets))
    for check in run.claims:
        path = out / "claims" / f"{check.claim.name}.png"
        if check.comparisons:
            written.append(plots.plot_claim(path, check, results))
        else:  # an earlier run's plot would read as this run's
            path.unlink(missing_ok=True)
    return written


def _learning_curves(run: BenchRun) -> dict[str, list[dict[str, float]]]:
    """RS-GAIL's curves of every trained policy (stage name -> rows of its ``curves.csv``)."""
    return {
        stage: read_stage_curves(folder / "curves.csv")
        for stage, folder in run.stage_folders.items()
        if stage.startswith("pi_") and (folder / "curves.csv").is_file()
    }


def _training_trajectories(run: BenchRun) -> Path | None:
    """The paper's Fig. 4a from the trajectories stage (:mod:`tolins.bench.jobs.trajectories`):
    π_n at iterations across its training, beside the expert's (``None`` when the run has
    no such stage, or it drew no episode)."""
    folder = run.stage_folders.get(trajectories.NAME)
    episodes = None if folder is None else trajectories.read_trajectories(folder)
    if not episodes:
        return None
    env_id = TRAININGS[trajectories.TRAINING].env_ids[0]
    title = f"π_n over RS-GAIL training on {env_id} ({run.config.backend})"
    path = Path(run.config.out) / "trajectories.png"
    return plots.plot_training_trajectories(path, episodes, title)
