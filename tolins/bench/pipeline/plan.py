"""The stages of a bench run, planned once: each stage's config is built here, from the
profile and the stages it follows, and handed to its job with the stage
(:class:`~tolins.bench.store.cache.Stage`); a job never derives it again.

A stage that has finished (its folder's marker is there) is done; any other becomes a job
of the executor that runs after the stages it needs (:class:`Plan`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from tolins.bench.jobs import robustness, row_evaluation, study, training, trajectories
from tolins.bench.jobs.demonstrations import demos_job
from tolins.bench.pipeline import settings
from tolins.bench.pipeline.executor import Job
from tolins.bench.pipeline.profiles import Profile
from tolins.bench.store.cache import Stage, StageCache
from tolins.bench.table.robustness import ROBUSTNESS, ConditionTable
from tolins.bench.table.rows import TRAININGS, Row


class Plan:
    """The stages of a run: finished ones (``done``: name -> result) and jobs to run.

    Args:
        cache: Where the stages live.
        log: Where to say that a bad finished stage is run again.
        dry_run: Plan only: leave a bad finished stage where it is (and count it as a
            job) instead of moving it aside.
    """

    def __init__(
        self, cache: StageCache, log: Callable[[str], None], *, dry_run: bool = False
    ) -> None:
        self.cache, self.log, self.dry_run = cache, log, dry_run
        self.stages: dict[str, Stage[Any]] = {}
        self.done: dict[str, Path] = {}
        self.cached: set[str] = set()
        self.jobs: list[Job] = []
        self.trainings: dict[str, str] = {}  # stage -> its log line

    def __contains__(self, name: str) -> bool:
        return name in self.stages

    def folder_name(self, name: str) -> str:
        """The folder name (``NAME-KEY``) of the planned stage ``name``: what the stages
        that read its files put in their configs."""
        stage = self.stages[name]
        return self.cache.folder(stage.name, stage.config).name

    def folder(self, name: str, result: Path | None = None) -> Path:
        """The folder of the stage ``name`` whose result is ``result`` (default: its
        result in ``done``): a training's result is its policy file in the folder."""
        value = self.done[name] if result is None else result
        return value.parent if name in self.trainings else value

    def add(
        self,
        stage: Stage[Any],
        fn: Callable[..., Path],
        args: tuple = (),
        upstream: str | None = None,
        *,
        side_by_side: bool = False,
        result: str | None = None,
        takes_upstream: bool = True,
        needs: tuple[str, ...] = (),
        own_process: bool = False,
    ) -> None:
        """Plan ``stage``: finished (its ``result`` file, or folder) or a job of
        ``fn(root, stage, *args, upstream's result)`` (``upstream``: an earlier stage name,
        or ``None`` passed as such; nothing with ``takes_upstream=False``) that runs after
        the earlier stages ``needs`` (the results of those that run as jobs come last)."""
        self.stages[stage.name] = stage
        if self.dry_run:
            folder = self.cache.folder(stage.name, stage.config)
            finished = self.cache.finished(stage.name, stage.config)
            usable = finished and self.cache.problem(folder) is None
        else:
            bad = self.cache.discard_bad(stage.name, stage.config)
            if bad is not None:
                self.log(bad)
            usable = self.cache.finished(stage.name, stage.config)
        if usable:
            folder = self.cache.folder(stage.name, stage.config)
            self.done[stage.name] = folder if result is None else folder / result
            self.cached.add(stage.name)
            return
        args = (self.cache.root.parent, stage, *args)
        deps: tuple[str, ...] = ()
        if not takes_upstream:
            pass
        elif upstream is None or upstream in self.done:
            args = (*args, None if upstream is None else self.done[upstream])
        else:
            deps = (upstream,)
        deps += tuple(need for need in needs if need not in self.done)
        self.jobs.append(Job(stage.name, fn, args, deps, side_by_side, own_process))


def plan_trainings(
    plan: Plan,
    rows: list[Row],
    seeds: int,
    profile: Profile,
    backend: str,
    pool: Any,
    progress: bool,
    log: Callable[[str], None],
) -> None:
    """The trainings of ``rows`` for each training seed, each after its upstream and its
    demonstration stages (RS-GAIL's candidates on ``pool``; its bars if ``progress``)."""
    for seed in range(seeds):
        for row in rows:
            for trained in row.trainings:  # upstream first
                name = training.stage_name(trained.name, seed)
                if name in plan:
                    continue
                up = trained.upstream
                up = None if up is None else training.stage_name(up, seed)
                stage = training.training_stage(
                    settings.training_spec(trained.name, seed, profile, backend),
                    None if up is None else plan.stages[up],
                )
                for demo in stage.spec.demos:
                    if demo.name not in plan:
                        plan.add(demo, demos_job, takes_upstream=False)
                plan.trainings[name] = f"{trained.method} on {', '.join(trained.env_ids)}"
                plan.add(
                    stage,
                    training.train_job,
                    (pool, progress),
                    up,
                    result=training.policy_file(trained),
                    needs=tuple(demo.name for demo in stage.spec.demos),
                    own_process=stage.spec.sb3 is not None,  # SB3's loop holds the GIL
                )
                if name in plan.cached:
                    log(f"{name}: cached ({plan.cache.wall_s(plan.folder(name)):.0f} s)")


def _policy(plan: Plan, agent: str, seed: int) -> tuple[str | None, str | None]:
    """The training stage of ``agent`` with ``seed`` and its folder name; ``(None, None)``
    for an expert."""
    if agent not in TRAININGS:
        return None, None
    name = training.stage_name(agent, seed)
    return name, plan.folder_name(name)


def plan_evaluations(
    plan: Plan, rows: list[Row], seeds: int, profile: Profile, backend: str
) -> None:
    """One evaluation per row and training seed, each after its policy's training."""
    for row in rows:
        for seed in range(seeds):
            upstream, policy_stage = _policy(plan, row.agent, seed)
            plan.add(
                row_evaluation.evaluation_stage(
                    settings.evaluation_spec(row, seed, policy_stage, profile, backend)
                ),
                row_evaluation.evaluation_job,
                upstream=upstream,
                side_by_side=True,
            )


def plan_robustness(
    plan: Plan, seeds: int, profile: Profile, backend: str, table: ConditionTable = ROBUSTNESS
) -> None:
    """The stages of ``table`` (the robustness table's by default) of every policy whose
    training this run has, for each training seed."""
    for policy in table.policies:
        if policy.trained and training.stage_name(policy.agent, 0) not in plan:
            continue  # the selected rows do not train it
        for seed in range(seeds):
            upstream, policy_stage = _policy(plan, policy.agent, seed)
            spec = settings.robustness_spec(policy, seed, policy_stage, profile, backend, table)
            plan.add(
                robustness.robustness_stage(spec),
                robustness.robustness_job,
                upstream=upstream,
                side_by_side=True,
            )


def plan_study(plan: Plan, profile: Profile, backend: str, workers: int, progress: bool) -> None:
    """The inference study on ``workers`` processes (its bar if ``progress``)."""
    stage = study.study_stage(settings.study_settings(profile, backend, workers))
    plan.add(stage, study.study_job, (progress,), takes_upstream=False)


def plan_trajectories(plan: Plan, backend: str) -> None:
    """π_n's trajectories over its training, when this run trains it."""
    upstream = training.stage_name(trajectories.TRAINING, trajectories.SEED)
    if upstream in plan:
        stage = trajectories.trajectory_stage(plan.folder_name(upstream), backend)
        plan.add(stage, trajectories.trajectory_job, upstream=upstream)
