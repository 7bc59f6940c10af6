"""The training stages of the benchmark: BC, π_n by RS-GAIL, π_φ by tolerance-guided
RS-GAIL, and the deep-RL baselines (PPO, SAC).

The run plans each training once (its settings from the profile,
:func:`tolins.bench.pipeline.settings.training_spec`; its stage, :func:`training_stage`:
the config whose hash names its folder) and hands that stage to :func:`train_job`, which
trains from the settings it is given.
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tolins.bench.jobs.demonstrations import DemoSpec, dataset_folder
from tolins.bench.store.cache import Stage, StageCache, stage_key
from tolins.bench.store.integrity import stage_file
from tolins.bench.table.rows import SB3_METHODS, Training, seeded
from tolins.learning.agents.sb3_config import CHECKPOINT as SB3_CHECKPOINT

if TYPE_CHECKING:
    from tolins.learning.agents.sb3_config import Sb3Config
    from tolins.learning.imitation.config import (
        BCConfig,
        ResidualConfig,
        RSGailConfig,
        TaskConfig,
    )
    from tolins.learning.imitation.runs import Demos
    from tolins.rollouts.pool import CandidatePool


@dataclass(frozen=True)
class TrainingSpec:
    """What one training stage trains, with which settings.

    Attributes:
        training: The policy trained (:data:`~tolins.bench.table.rows.TRAININGS`).
        seed: The training seed.
        task: The expert, its demonstrations and the seed (imitation only).
        bc: Behaviour cloning (BC, and RS-GAIL's start).
        rs_gail: RS-GAIL (π_n and π_φ).
        residual: The tolerance-guided residual (π_φ).
        sb3: The deep-RL baseline (PPO, SAC).
        demos: The demonstration stages it reads, in env order (imitation only).
    """

    training: Training
    seed: int
    task: TaskConfig | None = None
    bc: BCConfig | None = None
    rs_gail: RSGailConfig | None = None
    residual: ResidualConfig | None = None
    sb3: Sb3Config | None = None
    demos: tuple[Stage[DemoSpec], ...] = ()


def stage_name(name: str, seed: int) -> str:
    """The stage name of training ``name`` with ``seed``, e.g. ``pi_n_safe-seed0``."""
    return seeded(name, seed)


def policy_file(training: Training) -> str:
    """The file of a finished stage of ``training`` that holds its policy."""
    from tolins.learning.agents.sb3_config import MODEL

    return MODEL if training.method in SB3_METHODS else "policy.pt"


def training_stage(spec: TrainingSpec, upstream: Stage[TrainingSpec] | None) -> Stage[TrainingSpec]:
    """The stage of ``spec`` (``upstream``: the planned stage of the training it starts
    from, whose key its config holds)."""
    if (upstream is None) != (spec.training.upstream is None):
        given = None if upstream is None else upstream.name
        raise ValueError(
            f"training {spec.training.name} starts from {spec.training.upstream!r}; "
            f"given the stage {given!r}"
        )
    return Stage(stage_name(spec.training.name, spec.seed), _config(spec, upstream), spec)


def _config(spec: TrainingSpec, upstream: Stage[TrainingSpec] | None) -> dict[str, Any]:
    """The stage config: the training, its settings (without RS-GAIL's workers and SB3's
    checkpoint interval: the results do not depend on them), its upstream's key, its
    demonstrations' keys and the tolins version."""
    import tolins

    config: dict[str, Any] = {
        "training": asdict(spec.training),
        "tolins_version": tolins.__version__,
    }
    if upstream is not None:
        config["upstream"] = stage_key(upstream.config)
    if spec.sb3 is not None:
        sb3 = asdict(spec.sb3)
        sb3.pop("checkpoint_every")
        config["sb3"] = sb3
        return config
    config["task"] = asdict(spec.task)
    config["demos"] = [stage_key(demo.config) for demo in spec.demos]
    if spec.rs_gail is None:
        config["bc"] = asdict(spec.bc)
    else:
        rs_gail = asdict(spec.rs_gail)
        rs_gail.pop("workers")
        config["rs_gail"] = rs_gail
    if spec.residual is not None:
        config["residual"] = asdict(spec.residual)
    return config


def train_job(
    root: Path,
    stage: Stage[TrainingSpec],
    pool: CandidatePool | None,
    progress: bool,
    upstream: Path | None,
    *_demos: Path,
) -> Path:
    """A job of :mod:`tolins.bench.pipeline.executor`: ``stage`` trained in the cache under
    ``root`` from the ``upstream`` policy file unless it has finished (RS-GAIL's
    candidates on ``pool``, default threads; its progress bars if ``progress``); the
    policy file. The folders of its demonstration stages, when they ran as jobs before
    it, come last (unused: the stage names them)."""
    cache = StageCache(root)
    # a deep-RL training's checkpoint stays until the stage is recorded: a run killed in
    # between resumes from the finished training instead of training again
    transient = (SB3_CHECKPOINT,) if stage.spec.sb3 is not None else ()
    folder = cache.run_stage(
        stage, lambda out: _train(cache, stage.spec, out, upstream, pool, progress), transient
    )
    return folder / policy_file(stage.spec.training)


def _train(
    cache: StageCache,
    spec: TrainingSpec,
    out: Path,
    upstream: Path | None,
    pool: CandidatePool | None,
    progress: bool,
) -> None:
    from tolins.learning.imitation import runs

    training = spec.training
    if spec.sb3 is not None:
        from tolins.learning.agents.sb3 import train_sb3

        # from its checkpoint, if it was interrupted; the stage cache removes it
        train_sb3(spec.sb3, out, resume=True, keep_checkpoint=True)
        return
    env_ids = list(training.env_ids)
    demos = _demos(cache, spec.demos, out)
    if upstream is not None:
        _check_upstream(upstream)
    if training.method == "bc":
        runs.run_bc(env_ids[0], spec.task, spec.bc, out, demos=demos)
    elif training.method == "rs-gail":
        runs.run_rs_gail(
            env_ids[0],
            spec.task,
            spec.bc,
            spec.rs_gail,
            out,
            init=str(upstream),
            resume=True,
            progress=progress,
            pool=pool,
            demos=demos,
        )
    else:
        runs.run_tolerance_guided(
            env_ids,
            spec.task,
            spec.rs_gail,
            spec.residual,
            out,
            nominal=str(upstream),
            resume=True,
            progress=progress,
            pool=pool,
            demos=demos,
        )


def _demos(cache: StageCache, stages: tuple[Stage[DemoSpec], ...], out: Path) -> Demos:
    """The episodes of the demonstration datasets of ``stages``, in env order (their
    folders recorded relative to the training's folder ``out``)."""
    from tolins.datasets.reader import load_demonstrations
    from tolins.learning.imitation.runs import Demos

    folders = [dataset_folder(cache, stage) for stage in stages]
    for stage, folder in zip(stages, folders, strict=True):
        if not cache.finished(stage.name, stage.config):
            raise FileNotFoundError(f"{folder}: demonstration stage {stage.name} not run")
    rollouts = []
    for stage, folder in zip(stages, folders, strict=True):
        with stage_file(folder):
            rollouts += load_demonstrations(folder, stage.spec.env_id)
    source = ",".join(os.path.relpath(f.resolve(), out.resolve()) for f in folders)
    return Demos(source, rollouts)


def _check_upstream(policy: Path) -> None:
    """Load the upstream stage's policy file before the training reads it: one it cannot
    load is a :class:`~tolins.bench.store.integrity.StageFileError`, not a failed stage."""
    from tolins.learning.imitation.policy import load_policy

    with stage_file(policy):
        load_policy(policy, kind="nominal")
