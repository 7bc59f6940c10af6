"""The training stages of the benchmark: BC, π_n by RS-GAIL, π_φ by tolerance-guided RS-GAIL."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from tolins.bench.profiles import Profile
from tolins.bench.stages import StageCache, stage_key
from tolins.bench.table import TRAININGS, Training


class Trainer:
    """Trains (or finds cached) the policies of :data:`~tolins.bench.table.TRAININGS`.

    Args:
        cache: Where the stages live.
        profile: The budgets.
        backend: ``mujoco`` or ``kinematic``.
        progress: Show RS-GAIL's progress bars.
        log: Called with one line per stage (started, cached, finished).
    """

    def __init__(
        self,
        cache: StageCache,
        profile: Profile,
        backend: str,
        *,
        progress: bool = True,
        log: Callable[[str], None] = print,
    ) -> None:
        self.cache, self.profile, self.backend = cache, profile, backend
        self.progress, self.log = progress, log
        self.wall_s: dict[str, float] = {}
        self.cached: list[str] = []
        self._done: dict[tuple[str, int], Path] = {}

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
        if training.method == "bc":
            config["bc"] = asdict(self.profile.bc())
        else:
            rs_gail = asdict(self.profile.rs_gail(training.method))
            rs_gail.pop("workers")  # results do not depend on it
            config["rs_gail"] = rs_gail
        if training.method == "tolerance-guided":
            config["residual"] = asdict(self.profile.residual())
        return config

    def stage_name(self, name: str, seed: int) -> str:
        """The stage name of training ``name`` with ``seed``, e.g. ``pi_n_safe-seed0``."""
        return f"{name}-seed{seed}"

    def policy(self, name: str, seed: int) -> Path:
        """``policy.pt`` of training ``name`` with ``seed``, training its upstream first."""
        if (name, seed) in self._done:
            return self._done[name, seed]
        training = TRAININGS[name]
        upstream = None if training.upstream is None else self.policy(training.upstream, seed)
        stage = self.stage_name(name, seed)
        config = self.config(name, seed)
        if not self.cache.finished(stage, config):
            self.log(f"training {stage} ({training.method} on {', '.join(training.env_ids)})")
        folder, cached = self.cache.run(
            stage, config, lambda out: self._train(training, seed, out, upstream)
        )
        self.wall_s[stage] = self.cache.wall_s(folder)
        if cached:
            self.cached.append(stage)
        self.log(f"{stage}: {'cached' if cached else 'trained'} ({self.wall_s[stage]:.0f} s)")
        self._done[name, seed] = folder / "policy.pt"
        return self._done[name, seed]

    def _train(self, training: Training, seed: int, out: Path, upstream: Path | None) -> None:
        from tolins.learning import runs

        task = self.profile.task(self.backend, training.expert, seed)
        env_ids = list(training.env_ids)
        if training.method == "bc":
            runs.run_bc(env_ids[0], task, self.profile.bc(), out)
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
            )
