"""Each stage's settings from the profile's budgets: what the planner
(:mod:`tolins.bench.pipeline.plan`) builds once per stage and hands its job, which runs
them as given."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from tolins.bench.jobs.demonstrations import DemoSpec, demo_stages
from tolins.bench.jobs.robustness import RobustnessSpec
from tolins.bench.jobs.row_evaluation import EvaluationSpec
from tolins.bench.jobs.training import TrainingSpec
from tolins.bench.pipeline.profiles import Profile
from tolins.bench.store.cache import Stage
from tolins.bench.table.robustness import ROBUSTNESS, ConditionTable, RobustPolicy
from tolins.bench.table.rows import SB3_METHODS, TRAININGS, Row, Training
from tolins.bench.table.seeds import eval_seeds

if TYPE_CHECKING:
    from tolins.inference.study import StudyConfig


def demonstrations(
    training: Training, profile: Profile, backend: str, seed: int
) -> list[Stage[DemoSpec]]:
    """The demonstration stages ``training`` reads with ``seed`` (none for deep RL): the
    profile's demonstrations of its expert on each of its envs."""
    if training.method in SB3_METHODS:
        return []
    task = profile.task(backend, training.expert, seed)
    return demo_stages(training.env_ids, task.expert, task.demonstrations, seed, backend)


def training_spec(name: str, seed: int, profile: Profile, backend: str) -> TrainingSpec:
    """Training ``name`` with ``seed``: a baseline's env steps, or the expert imitated, its
    demonstrations and the BC, RS-GAIL and residual settings of ``profile``."""
    training = TRAININGS[name]
    if training.method in SB3_METHODS:
        sb3 = profile.sb3(training.method, training.env_ids[0], backend, seed, training.reward_mode)
        return TrainingSpec(training, seed, sb3=sb3)
    return TrainingSpec(
        training,
        seed,
        task=profile.task(backend, training.expert, seed),
        bc=profile.bc(),
        rs_gail=None if training.method == "bc" else profile.rs_gail(training.method),
        residual=profile.residual() if training.method == "tolerance-guided" else None,
        demos=tuple(demonstrations(training, profile, backend, seed)),
    )


def evaluation_spec(
    row: Row, seed: int, policy_stage: str | None, profile: Profile, backend: str
) -> EvaluationSpec:
    """``row``'s evaluation for training seed ``seed`` (``policy_stage``: its trained
    policy's stage folder, ``None`` for an expert row): the profile's evaluation episodes,
    the first training seed's first ones recorded."""
    return EvaluationSpec(
        row,
        seed,
        backend,
        tuple(eval_seeds(seed, profile.eval_episodes)),
        profile.recorded_episodes if seed == 0 else 0,
        policy_stage,
    )


def robustness_spec(
    policy: RobustPolicy,
    seed: int,
    policy_stage: str | None,
    profile: Profile,
    backend: str,
    table: ConditionTable = ROBUSTNESS,
) -> RobustnessSpec:
    """``policy``'s line of ``table`` (the robustness table's by default) for training seed
    ``seed`` (``policy_stage``: its training's stage folder, ``None`` for an expert): the
    profile's robustness episodes per condition."""
    seeds = tuple(eval_seeds(seed, profile.robustness_episodes))
    return RobustnessSpec(policy, seed, backend, seeds, policy_stage, table)


#: Workpieces of the inference study per process it runs on: a smaller study runs on
#: fewer processes (starting one, which imports tolins, costs as much as a few dozen
#: workpieces of the tolerance model; the results do not depend on them).
STUDY_WORKPIECES_PER_PROCESS = 100


def study_settings(profile: Profile, backend: str, workers: int = 2) -> StudyConfig:
    """The inference study of ``profile`` on ``backend`` (MuJoCo contact outcomes on
    mujoco, the tolerance model's on kinematic), on at most ``workers`` processes (one per
    :data:`STUDY_WORKPIECES_PER_PROCESS`): its workpieces, and besides the bent ones pitch,
    burr and blocked workpieces (12 each, at most the profile's workpieces), with the
    profile's posterior samples per goal query."""
    from tolins.inference.study import StudyConfig

    study = StudyConfig(
        samples=profile.study_samples,
        seed=0,
        particles=profile.study_particles or StudyConfig.particles,
        physics=backend == "mujoco",
        kind_samples=min(StudyConfig.kind_samples, profile.study_samples),
    )
    processes = study.workpieces // STUDY_WORKPIECES_PER_PROCESS
    return dataclasses.replace(study, workers=max(1, min(workers, processes)))
