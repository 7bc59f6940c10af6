"""``tolins bench``: train and evaluate Table 1's rows and run the inference study.

Stages (all cached by config hash under ``DIR/stages``, see :mod:`.stages`): the trainings
each selected row needs, once per training seed (:mod:`.training`); one evaluation per
row and seed (:mod:`.evaluation`); the inference study. The stages that have not finished
run as jobs of an executor (:mod:`.executor`: this process, or Ray tasks on a cluster),
each after the stage it needs, under one progress bar over all of them (:mod:`.progress`:
the stage running, the time left). Then the reports: every file in ``DIR`` is rewritten from
the finished stages (:mod:`.report`), and ``timeline.png`` shows when and where each
stage ran (:mod:`.timeline`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from tqdm import tqdm

from tolins.atomic import atomic_json
from tolins.bench.claims import check_claims
from tolins.bench.config import EPISODES, RECORDING, BenchConfig, BenchRun
from tolins.bench.demonstrations import demos_stage
from tolins.bench.evaluation import episodes_to_json, eval_seeds, evaluate_row
from tolins.bench.executor import Job, make_executor
from tolins.bench.integrity import StageFileError, checked_episodes, read_json
from tolins.bench.lock import locked_folder
from tolins.bench.profiles import PROFILES, Profile
from tolins.bench.progress import BenchProgress, expected_cost
from tolins.bench.report import write_reports
from tolins.bench.results import row_entry
from tolins.bench.robustness import PREFIX, plan_robustness, robustness_results
from tolins.bench.stages import StageCache
from tolins.bench.table import TRAININGS, Row, select_rows
from tolins.bench.timeline import write_timeline
from tolins.bench.training import Trainer, train_stage
from tolins.datasets.reader import require_minari
from tolins.rollouts.episodes import Episode

STUDY = "inference.json"


def run_bench(
    config: BenchConfig, *, progress: bool = True, log: Callable[[str], None] = tqdm.write
) -> BenchRun:
    """Run (or resume) the benchmark and write every report into ``config.out``, holding
    its lock (:mod:`.lock`: ``ValueError`` naming the process when another bench has it)."""
    with locked_folder(config.out):
        return _run_bench(config, progress=progress, log=log)


def _run_bench(config: BenchConfig, *, progress: bool, log: Callable[[str], None]) -> BenchRun:
    began = time.perf_counter()
    profile = PROFILES[config.profile]
    seeds = config.seeds or profile.seeds
    rows = select_rows(config.rows)
    out = Path(config.out)
    cache = StageCache(out)
    trainer = Trainer(cache, profile, config.backend, progress=progress)
    run = BenchRun(config, profile, {}, [], None, 0.0)
    executor = make_executor(
        config.executor, workers=config.workers, address=config.address, shared=cache.root
    )
    cache.root.mkdir(parents=True, exist_ok=True)
    try:
        local = executor.name == "local"
        plan = _Plan(cache, log)
        if any(trainer.demo_stages(t.name, 0) for row in rows for t in row.trainings):
            require_minari("tolins bench (its demonstrations are Minari datasets)")
        pool = executor.candidate_pool()
        _plan_trainings(plan, trainer, rows, seeds, pool, progress and local, log)
        _plan_evaluations(plan, trainer, rows, seeds)
        if config.robustness:
            plan_robustness(plan, trainer, seeds)
        if config.study:
            workers = 2 if local else 1  # a Ray task holds one CPU
            args = (out, profile, config.backend, workers, progress and local)
            plan.add(
                "inference-study",
                _study_config(profile, config.backend),
                study_stage,
                args,
                takes_upstream=False,
            )
        names = [*plan.done, *(job.name for job in plan.jobs)]
        costs = {name: expected_cost(name, profile, config.backend) for name in names}
        with BenchProgress(costs, plan.done, show=progress) as stages:
            plan.done.update(
                executor.run(
                    plan.jobs,
                    on_start=lambda job: _log_start(job, plan, log, stages),
                    on_done=lambda job, result: _log_done(job, result, plan, log, stages),
                )
            )
        run.stage_times = _stage_times(plan, cache, executor.placement)
    finally:
        executor.close()
    for name, value in plan.done.items():
        folder = value.parent if name in plan.trainings else value
        run.stage_folders[name] = folder
        run.stage_wall_s[name] = cache.wall_s(folder)
    run.cached += [name for name in plan.done if name in plan.cached]
    for row in rows:
        per_seed = [
            _episodes(run.stage_folders[f"eval-{row.id}-seed{s}"], profile.eval_episodes)
            for s in range(seeds)
        ]
        run.results[row.id] = row_entry(row, per_seed)
    budgets = (profile.deep_rl_env_steps, profile.rs_gail_env_steps)
    run.claims = check_claims(run.results, budgets=budgets)
    if config.study:
        run.study = read_json(run.stage_folders["inference-study"] / STUDY)
        if not isinstance(run.study, dict):
            path = run.stage_folders["inference-study"] / STUDY
            raise StageFileError(f"{path}: not an inference study; delete its folder to rerun")
    if config.robustness:
        run.robustness = robustness_results(run.stage_folders, profile, seeds)
    run.wall_s = time.perf_counter() - began
    write_reports(run, trainer, seeds)
    write_timeline(out, run)
    return run


class _Plan:
    """The stages of a run: finished ones (``done``: name -> result) and jobs to run."""

    def __init__(self, cache: StageCache, log: Callable[[str], None]) -> None:
        self.cache, self.log = cache, log
        self.done: dict[str, Path] = {}
        self.cached: set[str] = set()
        self.jobs: list[Job] = []
        self.trainings: dict[str, str] = {}  # stage -> its log line
        self._names: set[str] = set()

    def __contains__(self, name: str) -> bool:
        return name in self._names

    def add(
        self,
        name: str,
        config: dict[str, Any],
        fn: Callable[..., Path],
        args: tuple,
        upstream: str | None = None,
        *,
        side_by_side: bool = False,
        result: str | None = None,
        takes_upstream: bool = True,
        needs: tuple[str, ...] = (),
    ) -> None:
        """Stage ``name``: finished (its ``result`` file, or folder) or a job of ``fn(*args,
        upstream's result)`` (``upstream``: an earlier stage name, or ``None`` passed as
        such; nothing with ``takes_upstream=False``) that runs after the earlier stages
        ``needs`` (the results of those that run as jobs come last)."""
        self._names.add(name)
        bad = self.cache.discard_bad(name, config)
        if bad is not None:
            self.log(bad)
        if self.cache.finished(name, config):
            folder = self.cache.folder(name, config)
            self.done[name] = folder if result is None else folder / result
            self.cached.add(name)
            return
        deps: tuple[str, ...] = ()
        if not takes_upstream:
            pass
        elif upstream is None or upstream in self.done:
            args = (*args, None if upstream is None else self.done[upstream])
        else:
            deps = (upstream,)
        deps += tuple(need for need in needs if need not in self.done)
        self.jobs.append(Job(name, fn, args, deps, side_by_side))


def _plan_trainings(
    plan: _Plan,
    trainer: Trainer,
    rows: list[Row],
    seeds: int,
    pool: Any,
    progress: bool,
    log: Callable[[str], None],
) -> None:
    cache, profile, backend = trainer.cache, trainer.profile, trainer.backend
    for seed in range(seeds):
        for row in rows:
            for training in row.trainings:  # upstream first
                stage = trainer.stage_name(training.name, seed)
                if stage in plan:
                    continue
                up = training.upstream
                demos = trainer.demo_stages(training.name, seed)
                for demo in demos:
                    if demo.name not in plan:
                        plan.add(
                            demo.name,
                            demo.config(),
                            demos_stage,
                            (cache.root.parent, demo),
                            takes_upstream=False,
                        )
                plan.trainings[stage] = f"{training.method} on {', '.join(training.env_ids)}"
                plan.add(
                    stage,
                    trainer.config(training.name, seed),
                    train_stage,
                    (cache.root.parent, profile, backend, training.name, seed, pool, progress),
                    None if up is None else trainer.stage_name(up, seed),
                    result=trainer.policy_file(training.name),
                    needs=tuple(demo.name for demo in demos),
                )
                if stage in plan.cached:
                    log(f"{stage}: cached ({trainer.cache.wall_s(plan.done[stage].parent):.0f} s)")


def _plan_evaluations(plan: _Plan, trainer: Trainer, rows: list[Row], seeds: int) -> None:
    cache, profile, backend = trainer.cache, trainer.profile, trainer.backend
    for row in rows:
        for seed in range(seeds):
            training = row.agent if row.agent in TRAININGS else None
            upstream = None if training is None else trainer.stage_name(training, seed)
            policy_stage = None
            if training is not None:
                policy_stage = trainer.stage_folder_name(training, seed)
            plan.add(
                f"eval-{row.id}-seed{seed}",
                _evaluation_config(row, seed, policy_stage, profile, backend),
                evaluation_stage,
                (cache.root.parent, row, seed, profile, backend),
                upstream,
                side_by_side=True,
            )


def _log_start(job: Job, plan: _Plan, log: Callable[[str], None], stages: BenchProgress) -> None:
    stages.start(job.name)
    if job.name in plan.trainings:
        log(f"training {job.name} ({plan.trainings[job.name]})")
    elif job.name == "inference-study":
        profile, backend = job.args[1], job.args[2]
        source = "MuJoCo contacts" if backend == "mujoco" else "the tolerance model"
        log(f"inference study: {profile.study_samples} workpieces, outcomes from {source}")


def _log_done(
    job: Job, result: Path, plan: _Plan, log: Callable[[str], None], stages: BenchProgress
) -> None:
    wall_s = plan.cache.wall_s(result.parent if job.name in plan.trainings else result)
    stages.finish(job.name, wall_s)
    if job.name.startswith("demos-"):
        log(f"{job.name}: {job.args[1].episodes} episodes written ({wall_s:.0f} s)")
    elif job.name.startswith(PREFIX):
        log(f"{job.name}: evaluated ({wall_s:.0f} s)")
    elif job.name in plan.trainings:
        log(f"{job.name}: trained ({wall_s:.0f} s)")


def _evaluation_config(
    row: Row, seed: int, policy_stage: str | None, profile: Profile, backend: str
) -> dict[str, Any]:
    import tolins

    return {
        "row": asdict(row),
        "backend": backend,
        "seeds": eval_seeds(seed, profile.eval_episodes),
        "recorded": profile.recorded_episodes if seed == 0 else 0,
        "policy_stage": policy_stage,
        "tolins_version": tolins.__version__,
    }


def evaluation_stage(
    root: Path, row: Row, seed: int, profile: Profile, backend: str, policy: Path | None
) -> Path:
    """A job of :mod:`tolins.bench.executor`: ``row``'s evaluation for training seed
    ``seed`` (``policy``: its trained ``policy.pt``, ``None`` for an expert); its folder."""
    policy_stage = None if policy is None else policy.parent.name
    config = _evaluation_config(row, seed, policy_stage, profile, backend)
    recorded = config["recorded"]

    def build(folder: Path) -> None:
        record = folder / RECORDING if recorded else None
        episodes = evaluate_row(
            row, policy, backend, config["seeds"], record=record, recorded=recorded
        )
        atomic_json(folder / EPISODES, episodes_to_json(episodes))

    return StageCache(root).run(f"eval-{row.id}-seed{seed}", config, build)[0]


def _episodes(folder: Path, count: int) -> list[Episode]:
    """The ``count`` episodes of the evaluation stage in ``folder``, checked."""
    return checked_episodes(folder / EPISODES, read_json(folder / EPISODES), count)


def _study(profile: Profile, backend: str, workers: int = 2):
    from tolins.inference.study import StudyConfig

    return StudyConfig(
        samples=profile.study_samples,
        seed=0,
        workers=workers,
        physics=backend == "mujoco",
        # Pitch, burr and blocked workpieces besides the bent ones (issue 22), 12 each.
        kind_samples=min(StudyConfig.kind_samples, profile.study_samples),
    )


def _study_config(profile: Profile, backend: str) -> dict[str, Any]:
    import tolins

    config = {**asdict(_study(profile, backend)), "tolins_version": tolins.__version__}
    config.pop("workers")  # results do not depend on it
    return config


def study_stage(root: Path, profile: Profile, backend: str, workers: int, progress: bool) -> Path:
    """A job of :mod:`tolins.bench.executor`: the inference study (MuJoCo outcomes on the
    mujoco backend, the tolerance model on the kinematic one) on ``workers`` processes;
    its folder, with its JSON in the issue's schema."""
    from tolins.inference.report import save_plot, write_json
    from tolins.inference.study import run_study

    study = _study(profile, backend, workers)

    def build(folder: Path) -> None:
        with tqdm(total=study.samples, desc="inference study", disable=not progress) as bar:
            result = run_study(study, on_workpiece=lambda _: bar.update())
        save_plot(result, folder / "inference_study.png")
        write_json(result, folder / STUDY)

    return StageCache(root).run("inference-study", _study_config(profile, backend), build)[0]


def _stage_times(
    plan: _Plan, cache: StageCache, placement: dict[str, dict[str, Any]]
) -> dict[str, dict[str, Any]]:
    """When and where each stage ran (from its marker and the executor), and if cached."""
    times = {}
    for name, value in plan.done.items():
        marker = cache.record(value.parent if name in plan.trainings else value)
        times[name] = {
            "started": marker.get("started"),
            "finished": marker.get("finished"),
            "wall_s": marker["wall_s"],
            "cached": name in plan.cached,
            **{"host": marker.get("host"), "pid": marker.get("pid")},
            **placement.get(name, {}),
        }
    return times
