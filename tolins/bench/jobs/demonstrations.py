"""The bench's demonstration stages: each expert's episodes, written as a Minari dataset.

A training that imitates an expert (BC, π_n, π_φ) reads its demonstrations from one
stage per env it trains on, ``demos-{env}-{expert}-seed{s}-{i}``: the expert's
``profile.demonstrations`` episodes on env number ``i`` of the training, seeded as
``tolins train --seed s`` seeds them (:func:`tolins.datasets.episode_seeds`), written by
:func:`tolins.datasets.write_dataset` into the stage's ``demonstrations-v0`` folder. The
trainings of one seed share them (π_bc, π_n and π_φ all read the 2*2's), and they are
ordinary Minari datasets: ``minari.MinariDataset(folder / "data")`` opens one, and
``tolins train --demos`` trains from one. Since the episodes are the very ones the expert
gives inline, every trained policy is the same as without the datasets (tested).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from tolins.bench.store.cache import Stage, StageCache
from tolins.envs.tasks import env_label

#: The Minari id, and folder, of the dataset inside a demonstration stage.
DATASET = "demonstrations-v0"


@dataclass(frozen=True)
class DemoSpec:
    """The demonstrations of one env of a training.

    Attributes:
        env_id: The env.
        expert: The scripted expert (``safe`` or ``efficient``).
        episodes: How many episodes.
        seed: The training seed.
        stream: The env's index in the training's envs (it picks the episode seeds).
        backend: ``mujoco`` or ``kinematic``.
    """

    env_id: str
    expert: str
    episodes: int
    seed: int
    stream: int
    backend: str

    @property
    def name(self) -> str:
        """The stage name, e.g. ``demos-Circle2x2-safe-seed0-0``."""
        return f"demos-{env_label(self.env_id)}-{self.expert}-seed{self.seed}-{self.stream}"


def demo_stage(spec: DemoSpec) -> Stage[DemoSpec]:
    """The stage of ``spec``: its config is ``spec``'s fields and the tolins version."""
    import tolins

    return Stage(spec.name, {**asdict(spec), "tolins_version": tolins.__version__}, spec)


def demo_stages(
    env_ids: tuple[str, ...], expert: str, episodes: int, seed: int, backend: str
) -> list[Stage[DemoSpec]]:
    """The demonstration stages of a training on ``env_ids`` (one per env, in order)."""
    return [
        demo_stage(DemoSpec(env_id, expert, episodes, seed, index, backend))
        for index, env_id in enumerate(env_ids)
    ]


def dataset_folder(cache: StageCache, stage: Stage[DemoSpec]) -> Path:
    """The dataset's folder in ``stage``'s folder."""
    return cache.folder(stage.name, stage.config) / DATASET


def demos_job(root: Path, stage: Stage[DemoSpec]) -> Path:
    """A job of :mod:`tolins.bench.pipeline.executor`: ``stage``'s dataset in the cache
    under ``root`` (written unless the stage has finished); the stage's folder."""
    from tolins.datasets.sources import Source
    from tolins.datasets.writer import write_dataset
    from tolins.policies import EXPERTS

    spec = stage.spec

    def build(folder: Path) -> None:
        source = Source(spec.expert, lambda _: EXPERTS[spec.expert]())
        write_dataset(
            spec.env_id,
            [source],
            spec.episodes,
            folder,
            DATASET,
            backend=spec.backend,
            seed=spec.seed,
            stream=spec.stream,
            description=f"the bench's {spec.expert}-expert demonstrations",
        )

    return StageCache(root).run_stage(stage, build)
