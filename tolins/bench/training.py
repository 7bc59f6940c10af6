"""The training stages of the benchmark: BC, π_n by RS-GAIL, π_φ by tolerance-guided RS-GAIL."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tolins.bench.demonstrations import DemoStage, demo_stages
from tolins.bench.profiles import Profile
from tolins.bench.stages import StageCache, stage_key
from tolins.bench.table import SB3_METHODS, TRAININGS, Training

if TYPE_CHECKING:
    from tolins.rollouts.pool import CandidatePool


def train_stage(
    root: Path,
    profile: Profile,
    backend: str,
    name: str,
    seed: int,
    pool: CandidatePool | None,
    progress: bool,
    upstream: Path | None,
    *_demos: Path,
) -> Path:
    """A job of :mod:`tolins.bench.executor`: :meth:`Trainer.train` in the cache under
    ``root`` (RS-GAIL's progress bars if ``progress``); ``policy.pt``. The folders of its
    demonstration stages, when they ran as jobs before it, come last (unused: they are
    found by their configs)."""
    trainer = Trainer(StageCache(root), profile, backend, progress=progress)
    return trainer.train(name, seed, upstream, pool)[0]


class Trainer:
    """Trains (or finds cached) the policies of :data:`~tolins.bench.table.TRAININGS`.

    Args:
        cache: Where the stages live.
        profile: The budgets.
        backend: ``mujoco`` or ``kinematic``.
        progress: Show RS-GAIL's progress bars.
    """

    def __init__(
        self,
        cache: StageCache,
        profile: Profile,
        backend: str,
        *,
        progress: bool = True,
    ) -> None:
        self.cache, self.profile, self.backend = cache, profile, backend
        self.progress = progress

    def config(self, name: str, seed: int) -> dict[str, Any]:
        """The stage config of training ``name`` with ``seed`` (its upstream's key inside)."""
        import tolins

        training = TRAININGS[name]
        config: dict[str, Any] = {
            "training": asdict(training),
            "task": asdict(self.profile.task(self.backend, training.expert, seed)),
            "tolins_version": tolins.__version__,
        }
        if training.upstream is not None:
            config["upstream"] = stage_key(self.config(training.upstream, seed))
        if training.method in SB3_METHODS:
            config.pop("task")  # no expert, no demonstrations
            config["sb3"] = asdict(self._sb3(training, seed))
            return config
        config["demos"] = [stage.key for stage in self.demo_stages(name, seed)]
        if training.method == "bc":
            config["bc"] = asdict(self.profile.bc())
        else:
            rs_gail = asdict(self.profile.rs_gail(training.method))
            rs_gail.pop("workers")  # results do not depend on it
            config["rs_gail"] = rs_gail
        if training.method == "tolerance-guided":
            config["residual"] = asdict(self.profile.residual())
        return config

    def demo_stages(self, name: str, seed: int) -> list[DemoStage]:
        """The demonstration stages training ``name`` reads (none for deep RL)."""
        training = TRAININGS[name]
        if training.method in SB3_METHODS:
            return []
        task = self.profile.task(self.backend, training.expert, seed)
        return demo_stages(training.env_ids, task.expert, task.demonstrations, seed, self.backend)

    def stage_name(self, name: str, seed: int) -> str:
        """The stage name of training ``name`` with ``seed``, e.g. ``pi_n_safe-seed0``."""
        return f"{name}-seed{seed}"

    def stage_folder_name(self, name: str, seed: int) -> str:
        """The folder name (``NAME-KEY``) of training ``name``'s stage with ``seed``: what
        the stages evaluating its policy put in their configs."""
        return self.cache.folder(self.stage_name(name, seed), self.config(name, seed)).name

    def train(
        self, name: str, seed: int, upstream: Path | None, pool: CandidatePool | None = None
    ) -> tuple[Path, bool]:
        """Train ``name`` with ``seed`` from the ``upstream`` policy file unless its stage
        has finished; its ``policy.pt`` and whether it was cached. RS-GAIL's candidates run
        on ``pool`` (default: threads)."""
        training = TRAININGS[name]
        folder, cached = self.cache.run(
            self.stage_name(name, seed),
            self.config(name, seed),
            lambda out: self._train(training, seed, out, upstream, pool),
        )
        return folder / self.policy_file(name), cached

    def policy_file(self, name: str) -> str:
        """The file of a finished stage of training ``name`` that holds its policy."""
        from tolins.learning.sb3_config import MODEL

        return MODEL if TRAININGS[name].method in SB3_METHODS else "policy.pt"

    def _sb3(self, training: Training, seed: int):
        return self.profile.sb3(training.method, training.env_ids[0], self.backend, seed)

    def _train(
        self,
        training: Training,
        seed: int,
        out: Path,
        upstream: Path | None,
        pool: CandidatePool | None,
    ) -> None:
        from tolins.learning import runs

        if training.method in SB3_METHODS:
            from tolins.learning.sb3 import train_sb3

            train_sb3(self._sb3(training, seed), out)
            return
        task = self.profile.task(self.backend, training.expert, seed)
        env_ids = list(training.env_ids)
        demos = self._demos(training.name, seed, out)
        if training.method == "bc":
            runs.run_bc(env_ids[0], task, self.profile.bc(), out, demos=demos)
        elif training.method == "rs-gail":
            runs.run_rs_gail(
                env_ids[0],
                task,
                self.profile.bc(),
                self.profile.rs_gail(training.method),
                out,
                init=str(upstream),
                resume=True,
                progress=self.progress,
                pool=pool,
                demos=demos,
            )
        else:
            runs.run_tolerance_guided(
                env_ids,
                task,
                self.profile.rs_gail(training.method),
                self.profile.residual(),
                out,
                nominal=str(upstream),
                resume=True,
                progress=self.progress,
                pool=pool,
                demos=demos,
            )

    def _demos(self, name: str, seed: int, out: Path):
        """The episodes of training ``name``'s demonstration datasets, in env order (their
        folders recorded relative to the training's folder ``out``)."""
        import os

        from tolins.datasets.reader import load_demonstrations
        from tolins.learning.runs import Demos

        stages = self.demo_stages(name, seed)
        folders = [stage.dataset(self.cache) for stage in stages]
        for stage, folder in zip(stages, folders, strict=True):
            if not self.cache.finished(stage.name, stage.config()):
                raise FileNotFoundError(f"{folder}: demonstration stage {stage.name} not run")
        rollouts = [
            r
            for s, f in zip(stages, folders, strict=True)
            for r in load_demonstrations(f, s.env_id)
        ]
        source = ",".join(os.path.relpath(f.resolve(), out.resolve()) for f in folders)
        return Demos(source, rollouts)
