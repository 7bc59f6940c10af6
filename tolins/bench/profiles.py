"""Budgets of the benchmark suite: ``quick`` (the default), ``paper`` and ``tiny`` (CI)."""

from __future__ import annotations

from dataclasses import dataclass

from tolins.learning.policy_config import BCConfig, ResidualConfig, RSGailConfig, TaskConfig


@dataclass(frozen=True)
class Profile:
    """How much each stage of ``tolins bench`` trains and evaluates.

    Attributes:
        name: Profile name.
        demonstrations: Expert episodes per training environment.
        bc_epochs: Behaviour-cloning epochs.
        nominal_iterations: RS-GAIL iterations of π_n.
        residual_iterations: RS-GAIL iterations of φ2 (π_φ).
        popsize: CMA-ES candidates per iteration.
        candidate_episodes: Episodes per candidate.
        curve_episodes: Episodes of the CMA-ES mean per iteration (learning curves).
        eval_episodes: Evaluation episodes per row and training seed.
        seeds: Training seeds (every policy is trained once per seed).
        study_samples: Workpieces of the inference study.
        recorded_episodes: Evaluation episodes per row recorded to rerun (first seed).
        sigma0: CMA-ES's initial step size.
    """

    name: str
    demonstrations: int
    bc_epochs: int
    nominal_iterations: int
    residual_iterations: int
    popsize: int
    candidate_episodes: int
    curve_episodes: int
    eval_episodes: int
    seeds: int
    study_samples: int
    recorded_episodes: int
    sigma0: float = 0.02

    def task(self, backend: str, expert: str, seed: int) -> TaskConfig:
        return TaskConfig(
            backend=backend, expert=expert, demonstrations=self.demonstrations, seed=seed
        )

    def bc(self) -> BCConfig:
        return BCConfig(epochs=self.bc_epochs)

    def rs_gail(self, method: str) -> RSGailConfig:
        guided = method == "tolerance-guided"
        return RSGailConfig(
            iterations=self.residual_iterations if guided else self.nominal_iterations,
            popsize=self.popsize,
            episodes=self.candidate_episodes,
            eval_episodes=self.curve_episodes,
            sigma0=self.sigma0,
            keep_best=True,
        )

    def residual(self) -> ResidualConfig:
        return ResidualConfig()


PROFILES: dict[str, Profile] = {
    # The paper's budgets: 100 RS-GAIL iterations, 100 evaluation episodes, 500 workpieces;
    # 5 training seeds, the unit of the verdicts' intervals (tolins.bench.statistics).
    "paper": Profile("paper", 50, 200, 100, 100, 16, 4, 8, 100, 5, 500, 3),
    # ≤ 15 min on 2 cores: RS-GAIL's reward rises most in its first 20-30 iterations.
    "quick": Profile("quick", 50, 200, 30, 20, 16, 4, 8, 100, 1, 500, 2),
    # Smoke test of the whole pipeline (CI): every stage runs, nothing is learnt.
    "tiny": Profile("tiny", 4, 5, 1, 1, 4, 1, 2, 2, 1, 6, 1),
}
