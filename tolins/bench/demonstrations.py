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
from typing import Any

from tolins.bench.stages import StageCache, stage_key

#: The Minari id, and folder, of the dataset inside a demonstration stage.
DATASET = "demonstrations-v0"


@dataclass(frozen=True)
class DemoStage:
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
        env = self.env_id.rpartition("/")[2].removesuffix("-v1")
        return f"demos-{env}-{self.expert}-seed{self.seed}-{self.stream}"

    def config(self) -> dict[str, Any]:
        """The stage config (with the tolins version)."""
        import tolins

        return {**asdict(self), "tolins_version": tolins.__version__}

    @property
    def key(self) -> str:
        """The stage's key (a training's config holds the keys of its demonstrations)."""
        return stage_key(self.config())

    def dataset(self, cache: StageCache) -> Path:
        """The dataset's folder in the stage's folder."""
        return cache.folder(self.name, self.config()) / DATASET


def demo_stages(
    env_ids: tuple[str, ...], expert: str, episodes: int, seed: int, backend: str
) -> list[DemoStage]:
    """The demonstration stages of a training on ``env_ids`` (one per env, in order)."""
    return [
        DemoStage(env_id, expert, episodes, seed, index, backend)
        for index, env_id in enumerate(env_ids)
    ]


def demos_stage(root: Path, stage: DemoStage) -> Path:
    """A job of :mod:`tolins.bench.executor`: ``stage``'s dataset in the cache under
    ``root`` (written unless the stage has finished); the stage's folder."""
    from tolins.datasets.sources import Source
    from tolins.datasets.writer import write_dataset
    from tolins.policies import EXPERTS

    def build(folder: Path) -> None:
        source = Source(stage.expert, lambda _: EXPERTS[stage.expert]())
        write_dataset(
            stage.env_id,
            [source],
            stage.episodes,
            folder,
            DATASET,
            backend=stage.backend,
            seed=stage.seed,
            stream=stage.stream,
            description=f"the bench's {stage.expert}-expert demonstrations",
        )

    return StageCache(root).run(stage.name, stage.config(), build)[0]
