"""The inference-study stage of ``tolins bench`` (:mod:`tolins.inference.study`): MuJoCo
contact outcomes on the mujoco backend, the tolerance model's on the kinematic one."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING

from tqdm import tqdm

from tolins.bench.store.cache import Stage, StageCache

if TYPE_CHECKING:
    from tolins.inference.study import StudyConfig

#: The stage's name.
NAME = "inference-study"
#: The study's JSON in the stage's folder.
STUDY = "inference.json"
#: The study's figure in the stage's folder.
PLOT = "inference_study.png"


def study_stage(settings: StudyConfig) -> Stage[StudyConfig]:
    """The study's stage. Its config: the study's settings but its workers (the results
    do not depend on them; nor the pins' settings when they are rigid) and the tolins
    version."""
    import tolins

    config = {**asdict(settings), "tolins_version": tolins.__version__}
    config.pop("workers")
    if settings.pins == "rigid":  # the study's key from before pins could bend
        config.pop("pins")
        config.pop("pin_material")
    return Stage(NAME, config, settings)


def study_job(root: Path, stage: Stage[StudyConfig], progress: bool) -> Path:
    """A job of :mod:`tolins.bench.pipeline.executor`: the study ``stage`` in the cache
    under ``root`` (its progress bar if ``progress``); its folder, holding :data:`STUDY`
    and :data:`PLOT`."""
    from tolins.inference.report import save_plot, write_json
    from tolins.inference.study import run_study

    study = stage.spec

    def build(folder: Path) -> None:
        with tqdm(total=study.samples, desc="inference study", disable=not progress) as bar:
            result = run_study(study, on_workpiece=lambda _: bar.update())
        save_plot(result, folder / PLOT)
        write_json(result, folder / STUDY)

    return StageCache(root).run_stage(stage, build)
