"""``tolins bench``: train and evaluate Table 1's rows and run the inference study.

Stages (all cached by config hash under ``DIR/stages``, see :mod:`.cache`): the trainings
each selected row needs, once per training seed (:mod:`tolins.bench.jobs.training`); one
evaluation per row and seed (:mod:`tolins.bench.jobs.row_evaluation`); the robustness
stages; the inference study. The stages that have not finished run as jobs of an executor
(:mod:`.executor`: this process, or Ray tasks on a cluster), each after the stage it needs,
under one progress bar over all of them (:mod:`.progress`: the stage running, the time
left). Then the reports: every file in ``DIR`` is rewritten from the finished stages
(:mod:`tolins.bench.reports`), and ``timeline.png`` shows when and where each stage ran
(:mod:`.timeline`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from tolins.bench.jobs import row_evaluation, study
from tolins.bench.jobs.robustness import PREFIX, robustness_results
from tolins.bench.pipeline.config import BenchConfig, BenchRun
from tolins.bench.pipeline.executor import Job, make_executor
from tolins.bench.pipeline.lock import locked_folder
from tolins.bench.pipeline.plan import (
    Plan,
    plan_evaluations,
    plan_robustness,
    plan_study,
    plan_trainings,
    plan_trajectories,
)
from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.pipeline.progress import BenchProgress, expected_cost
from tolins.bench.pipeline.settings import demonstrations
from tolins.bench.pipeline.timeline import write_timeline
from tolins.bench.reports.writer import write_reports
from tolins.bench.store.cache import StageCache
from tolins.bench.store.integrity import StageFileError, read_json
from tolins.bench.table.claims import check_claims
from tolins.bench.table.delicate import DELICATE, with_verdicts
from tolins.bench.table.results import row_entry
from tolins.bench.table.robot import ROBOT, with_grasp_column
from tolins.bench.table.rows import select_rows
from tolins.datasets.reader import require_minari
from tolins.mjcf.panda import require_panda

#: The log of the progress bar's estimates in the bench's folder (:class:`BenchProgress`).
PROGRESS_LOG = "progress.jsonl"


@dataclass(frozen=True)
class PlannedStage:
    """A stage of a planned run (:func:`plan_bench`)."""

    name: str
    finished: bool
    """Finished before (cached): the run only reads it."""
    expected_s: float
    """Its expected wall time (s; :func:`~tolins.bench.pipeline.progress.expected_cost`)."""
    needs: tuple[str, ...] = ()
    """The stages to run that it runs after."""


def run_bench(
    config: BenchConfig, *, progress: bool = True, log: Callable[[str], None] = tqdm.write
) -> BenchRun:
    """Run (or resume) the benchmark and write every report into ``config.out``, holding
    its lock (:mod:`.lock`: ``ValueError`` naming the process when another bench has it)."""
    with locked_folder(config.out):
        return _run_bench(config, progress=progress, log=log)


def study_workers(local: bool) -> int:
    """The processes the study runs on: 2 under the ``local`` executor (beside the other
    stages' threads), 1 as a Ray task (one CPU)."""
    return 2 if local else 1


def plan_bench(config: BenchConfig) -> list[PlannedStage]:
    """Every stage of the run ``config`` describes, finished or not, with its expected cost
    (:func:`~tolins.bench.pipeline.progress.expected_cost`): what ``tolins bench --dry-run``
    prints. Runs nothing and writes nothing; a finished stage whose files are bad counts as
    one to run (a run would move it aside and run it again)."""
    profile = PROFILES[config.profile]
    plan = Plan(StageCache(Path(config.out)), log=lambda _: None, dry_run=True)
    _plan_stages(plan, config, None, local=config.executor == "local", inner_bars=False)
    workers = study_workers(config.executor == "local")
    cost = {name: expected_cost(name, profile, config.backend, workers) for name in plan.stages}
    return [PlannedStage(name, True, cost[name]) for name in plan.done] + [
        PlannedStage(job.name, False, cost[job.name], job.deps) for job in plan.jobs
    ]


def _plan_stages(
    plan: Plan, config: BenchConfig, pool: Any, *, local: bool, inner_bars: bool
) -> None:
    """Plan every stage of ``config``'s run into ``plan`` (RS-GAIL's candidates on ``pool``;
    the study on 2 processes when the stages run ``local``ly, else in one Ray task's CPU)."""
    profile, backend = PROFILES[config.profile], config.backend
    seeds = config.seeds or profile.seeds
    rows = select_rows(config.rows, baselines=profile.baselines)
    if any(demonstrations(t, profile, backend, 0) for row in rows for t in row.trainings):
        require_minari("tolins bench (its demonstrations are Minari datasets)")
    plan_trainings(plan, rows, seeds, profile, backend, pool, inner_bars, plan.log)
    plan_evaluations(plan, rows, seeds, profile, backend)
    if config.robustness:
        plan_robustness(plan, seeds, profile, backend)
    if config.robot and backend == "mujoco":
        require_panda("tolins bench (its Panda table; --no-robot leaves it out)")
        plan_robustness(plan, seeds, profile, backend, ROBOT)
    if config.delicate and backend == "mujoco":
        plan_robustness(plan, seeds, profile, backend, DELICATE)
    if config.study:
        plan_study(plan, profile, backend, study_workers(local), inner_bars)
    plan_trajectories(plan, backend)


def _run_bench(config: BenchConfig, *, progress: bool, log: Callable[[str], None]) -> BenchRun:
    began = time.perf_counter()
    profile, backend = PROFILES[config.profile], config.backend
    seeds = config.seeds or profile.seeds
    rows = select_rows(config.rows, baselines=profile.baselines)
    out = Path(config.out)
    cache = StageCache(out)
    run = BenchRun(config, profile, {}, [], None, 0.0)
    executor = make_executor(
        config.executor, workers=config.workers, address=config.address, shared=cache.root
    )
    cache.root.mkdir(parents=True, exist_ok=True)
    try:
        local = executor.name == "local"
        plan = Plan(cache, log)
        # Trainings run side by side: their own progress bars would interleave.
        inner_bars = progress and local and config.workers == 1
        _plan_stages(plan, config, executor.candidate_pool(), local=local, inner_bars=inner_bars)
        names = [*plan.done, *(job.name for job in plan.jobs)]
        workers = study_workers(local)
        costs = {name: expected_cost(name, profile, backend, workers) for name in names}
        walls = {
            name: cache.wall_s(plan.folder(name))
            for name in plan.done
            if cache.ran_here(plan.folder(name))
        }
        with BenchProgress(
            costs,
            plan.done,
            needs={job.name: job.deps for job in plan.jobs},
            walls=walls,
            workers=executor.workers,
            log=out / PROGRESS_LOG,
            show=progress,
        ) as stages:
            plan.done.update(
                executor.run(
                    plan.jobs,
                    on_start=lambda job: _log_start(job, plan, log, stages),
                    on_done=lambda job, result: _log_done(job, result, plan, log, stages),
                    costs=costs,
                )
            )
        _record_stages(run, plan, cache, executor.placement)
    finally:
        executor.close()
    run.cached += [name for name in plan.done if name in plan.cached]
    for row in rows:
        run.episodes[row.id] = [
            row_evaluation.read_episodes(
                run.stage_folders[row_evaluation.stage_name(row, s)], profile.eval_episodes
            )
            for s in range(seeds)
        ]
        run.results[row.id] = row_entry(row, run.episodes[row.id])
    budgets = (profile.deep_rl_env_steps, profile.rs_gail_env_steps)
    run.claims = check_claims(run.results, budgets=budgets)
    if config.study:
        path = run.stage_folders[study.NAME] / study.STUDY
        run.study = read_json(path)
        if not isinstance(run.study, dict):
            raise StageFileError(path, "not an inference study")
    if config.robustness:
        run.robustness = robustness_results(run.stage_folders, profile.robustness_episodes, seeds)
    if config.robot and backend == "mujoco":
        count = profile.robustness_episodes
        run.robot = robustness_results(run.stage_folders, count, seeds, ROBOT)
        run.robustness = with_grasp_column(run.robustness, run.robot)
    if config.delicate and backend == "mujoco":
        count = profile.robustness_episodes
        table = robustness_results(run.stage_folders, count, seeds, DELICATE)
        run.delicate = with_verdicts(table)
    run.wall_s = time.perf_counter() - began
    write_reports(run, seeds)
    write_timeline(out, run)
    return run


def _log_start(job: Job, plan: Plan, log: Callable[[str], None], stages: BenchProgress) -> None:
    stages.start(job.name)
    if job.name in plan.trainings:
        log(f"training {job.name} ({plan.trainings[job.name]})")
    elif job.name == study.NAME:
        settings = plan.stages[job.name].spec
        source = "MuJoCo contacts" if settings.physics else "the tolerance model"
        log(f"inference study: {settings.samples} workpieces, outcomes from {source}")


def _log_done(
    job: Job, result: Path, plan: Plan, log: Callable[[str], None], stages: BenchProgress
) -> None:
    wall_s = plan.cache.wall_s(plan.folder(job.name, result))
    stages.finish(job.name, wall_s)
    if job.name.startswith("demos-"):
        log(f"{job.name}: {plan.stages[job.name].spec.episodes} episodes written ({wall_s:.0f} s)")
    elif job.name.startswith((PREFIX, ROBOT.prefix, DELICATE.prefix)):
        log(f"{job.name}: evaluated ({wall_s:.0f} s)")
    elif job.name in plan.trainings:
        log(f"{job.name}: trained ({wall_s:.0f} s)")


def _record_stages(
    run: BenchRun, plan: Plan, cache: StageCache, placement: dict[str, dict[str, Any]]
) -> None:
    """Each finished stage's folder and wall time, and when and where it ran (from its
    marker and the executor), and if cached, into ``run``."""
    for name in plan.done:
        folder = plan.folder(name)
        marker = cache.record(folder)
        run.stage_folders[name] = folder
        run.stage_wall_s[name] = float(marker["wall_s"])
        run.stage_times[name] = {
            "started": marker.get("started"),
            "finished": marker.get("finished"),
            "wall_s": marker["wall_s"],
            "cached": name in plan.cached,
            **{"host": marker.get("host"), "pid": marker.get("pid")},
            **placement.get(name, {}),
        }
