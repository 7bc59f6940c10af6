"""The files of a benchmark run: ``results.json``, ``results.md``, ``run.json``, plots,
recordings and the inference study, all rewritten from the finished stages."""

from __future__ import annotations

import datetime
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tolins.atomic import atomic_json, atomic_write
from tolins.bench.jobs import study
from tolins.bench.jobs.row_evaluation import RECORDING, stage_name
from tolins.bench.machine import machine
from tolins.bench.reports.figures import remove_figures, write_figures
from tolins.bench.reports.markdown import format_markdown, stage_minutes
from tolins.bench.reports.robustness import plot_robustness
from tolins.bench.store.integrity import read_stage_curves, stage_file
from tolins.bench.table.baselines import curves_json, env_step_curves
from tolins.bench.table.delicate import KEY as DELICATE_KEY
from tolins.bench.table.results import read_results, results_document
from tolins.bench.table.robot import KEY as ROBOT_KEY
from tolins.bench.table.robustness import KEY
from tolins.bench.table.rows import ALL_ROWS
from tolins.physics import BACKENDS

if TYPE_CHECKING:
    from tolins.bench.pipeline.config import BenchRun


def write_reports(run: BenchRun, seeds: int) -> list[Path]:
    """Write every output of ``run`` into ``run.config.out``; the paths written."""
    out = Path(run.config.out)
    backend = run.config.backend
    document = results_document(
        run.results, source="bench", backend=backend, profile=run.config.profile
    )
    document["claims"] = {check.claim.name: check.to_json() for check in run.claims}
    if run.robustness is not None:
        document[KEY] = run.robustness
    if run.robot is not None:
        document[ROBOT_KEY] = run.robot
    if run.delicate is not None:
        document[DELICATE_KEY] = run.delicate
    written = [
        atomic_json(out / "results.json", document),
        atomic_json(out / f"results.{backend}.json", document),
    ]
    figures = run.config.figures
    if not figures:
        remove_figures(out)
    if run.study is not None:
        written.append(atomic_json(out / "inference.json", run.study))
        if figures:
            written.append(_copy(run.stage_folders[study.NAME] / study.PLOT, out))
    else:  # an earlier run's study would read as this run's (its stage stays cached)
        (out / "inference.json").unlink(missing_ok=True)
        (out / "inference_study.png").unlink(missing_ok=True)
    written += _recordings(run, out)
    if run.robustness is not None and figures:
        written.append(plot_robustness(out / "robustness.png", run.robustness))
    else:  # an earlier run's table would read as this run's
        (out / "robustness.png").unlink(missing_ok=True)
    curves = env_step_curves(run.stage_folders, read_stage_curves)
    if figures:
        written += write_figures(run, out, curves)
    written.append(atomic_json(out / "curves.json", curves_json(curves)))
    facts = machine()
    written.append(atomic_json(out / "run.json", _run_record(run, seeds, facts)))
    text = format_markdown(run, _other_backend(out, backend), curves, facts)
    written.append(atomic_write(out / "results.md", lambda file: file.write(text), mode="w"))
    return written


def _copy(source: Path, folder: Path, name: str | None = None) -> Path:
    data = source.read_bytes()
    return atomic_write(folder / (name or source.name), lambda file: file.write(data))


def _recordings(run: BenchRun, out: Path) -> list[Path]:
    from tolins.record import check_rrd

    rows = {row.id: row for row in ALL_ROWS}
    written = []
    for row_id in run.results:
        source = run.stage_folders[stage_name(rows[row_id], 0)] / RECORDING
        if source.is_file():
            with stage_file(source):  # a truncated recording is not shipped as the row's
                check_rrd(source)
            written.append(_copy(source, out / "recordings", f"{row_id}.rrd"))
    return written


def _other_backend(out: Path, backend: str) -> tuple[str, dict[str, Any]] | None:
    other = next(b for b in BACKENDS if b != backend)
    path = out / f"results.{other}.json"
    return (other, read_results(path)["rows"]) if path.is_file() else None


def _run_record(run: BenchRun, seeds: int, facts: dict[str, Any]) -> dict[str, Any]:
    import mujoco
    import torch

    import tolins

    return {
        "date": datetime.date.today().isoformat(),
        "config": asdict(run.config),
        "profile": asdict(run.profile),
        "seeds": seeds,
        "wall_s": run.wall_s,
        "machine": facts,
        "stage_minutes": stage_minutes(run.stage_wall_s),
        "stage_wall_s": run.stage_wall_s,
        "cached_stages": run.cached,
        "claims": {check.claim.name: check.to_json() for check in run.claims},
        "versions": {
            "tolins": tolins.__version__,
            "mujoco": mujoco.__version__,
            "torch": torch.__version__,
        },
    }
