"""``tolins bench``: train and evaluate Table 1's rows and run the inference study.

Stages (all cached by config hash under ``DIR/stages``, see :mod:`.stages`): the trainings
each selected row needs, once per training seed (:mod:`.training`); one evaluation per
row and seed (:mod:`.evaluation`); the inference study. Then the reports: every file in
``DIR`` is rewritten from the finished stages (:mod:`.report`).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict
from pathlib import Path
from typing import Any

from tqdm import tqdm

from tolins.atomic import atomic_json
from tolins.bench.claims import check_claims
from tolins.bench.config import EPISODES, RECORDING, BenchConfig, BenchRun
from tolins.bench.evaluation import (
    episodes_from_json,
    episodes_to_json,
    eval_seeds,
    evaluate_row,
)
from tolins.bench.profiles import PROFILES, Profile
from tolins.bench.report import write_reports
from tolins.bench.results import row_entry
from tolins.bench.stages import StageCache
from tolins.bench.table import Row, select_rows
from tolins.bench.training import Trainer
from tolins.rollout import Episode


def run_bench(
    config: BenchConfig, *, progress: bool = True, log: Callable[[str], None] = tqdm.write
) -> BenchRun:
    """Run (or resume) the benchmark and write every report into ``config.out``."""
    from tolins.learning.artefacts import single_threaded_torch

    began = time.perf_counter()
    profile = PROFILES[config.profile]
    seeds = config.seeds or profile.seeds
    rows = select_rows(config.rows)
    out = Path(config.out)
    cache = StageCache(out)
    trainer = Trainer(cache, profile, config.backend, progress=progress, log=log)
    run = BenchRun(config, profile, {}, [], None, 0.0)
    policies: dict[tuple[str, int], Path] = {}
    for seed in range(seeds):
        for row in rows:
            for training in row.trainings:
                if (training.name, seed) not in policies:
                    policies[training.name, seed] = trainer.policy(training.name, seed)
    run.stage_wall_s.update(trainer.wall_s)
    run.cached += trainer.cached
    for name, seed in policies:
        run.stage_folders[trainer.stage_name(name, seed)] = policies[name, seed].parent

    jobs = [(row, seed) for row in rows for seed in range(seeds)]
    bar = tqdm(total=len(jobs), desc="evaluate", unit="row×seed", disable=not progress)

    def evaluate(job: tuple[Row, int]) -> list[Episode]:
        row, seed = job
        policy = policies.get((row.agent, seed))
        episodes = _evaluation_stage(cache, run, row, seed, policy, profile, config.backend)
        bar.update()
        return episodes

    with single_threaded_torch(), ThreadPoolExecutor(config.workers) as pool:
        per_job = dict(zip(jobs, pool.map(evaluate, jobs), strict=True))
    bar.close()
    for row in rows:
        run.results[row.id] = row_entry(row, [per_job[row, seed] for seed in range(seeds)])
    run.claims = check_claims(run.results)
    if config.study:
        run.study = _study_stage(cache, run, profile, config.backend, log, progress)
    run.wall_s = time.perf_counter() - began
    write_reports(run, trainer, seeds)
    return run


def _evaluation_stage(
    cache: StageCache,
    run: BenchRun,
    row: Row,
    seed: int,
    policy: Path | None,
    profile: Profile,
    backend: str,
) -> list[Episode]:
    import tolins

    recorded = profile.recorded_episodes if seed == 0 else 0
    config = {
        "row": asdict(row),
        "backend": backend,
        "seeds": eval_seeds(seed, profile.eval_episodes),
        "recorded": recorded,
        "policy_stage": None if policy is None else policy.parent.name,
        "tolins_version": tolins.__version__,
    }

    def build(folder: Path) -> None:
        record = folder / RECORDING if recorded else None
        episodes = evaluate_row(
            row, policy, backend, config["seeds"], record=record, recorded=recorded
        )
        atomic_json(folder / EPISODES, episodes_to_json(episodes))

    name = f"eval-{row.id}-seed{seed}"
    folder, cached = cache.run(name, config, build)
    run.stage_wall_s[name] = cache.wall_s(folder)
    run.stage_folders[name] = folder
    if cached:
        run.cached.append(name)
    return episodes_from_json(json.loads((folder / EPISODES).read_text()))


def _study_stage(
    cache: StageCache,
    run: BenchRun,
    profile: Profile,
    backend: str,
    log: Callable[[str], None],
    progress: bool,
) -> dict[str, Any]:
    """The inference study (MuJoCo outcomes on the mujoco backend, the tolerance model on
    the kinematic one); its JSON in the issue's schema."""
    import tolins
    from tolins.inference.report import save_plot, write_json
    from tolins.inference.study import StudyConfig, run_study

    study = StudyConfig(
        samples=profile.study_samples, seed=0, workers=2, physics=backend == "mujoco"
    )
    config = {**asdict(study), "tolins_version": tolins.__version__}
    config.pop("workers")

    def build(folder: Path) -> None:
        source = "MuJoCo contacts" if study.physics else "the tolerance model"
        log(f"inference study: {study.samples} workpieces, outcomes from {source}")
        with tqdm(total=study.samples, desc="inference study", disable=not progress) as bar:
            result = run_study(study, on_workpiece=lambda _: bar.update())
        save_plot(result, folder / "inference_study.png")
        write_json(result, folder / "inference.json")

    folder, cached = cache.run("inference-study", config, build)
    run.stage_wall_s["inference-study"] = cache.wall_s(folder)
    run.stage_folders["inference-study"] = folder
    if cached:
        run.cached.append("inference-study")
    return json.loads((folder / "inference.json").read_text())
