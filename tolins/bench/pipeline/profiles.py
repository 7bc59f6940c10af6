"""Budgets of the benchmark suite: ``quick`` (the default), ``paper`` and ``tiny`` (CI)."""

from __future__ import annotations

from dataclasses import dataclass

from tolins.learning.agents.sb3_config import Sb3Config
from tolins.learning.imitation.config import BCConfig, ResidualConfig, RSGailConfig, TaskConfig
from tolins.paper import HORIZON

#: Training envs per deep-RL baseline, stepped in one batch. PPO's rollout stays SB3's
#: 2,048 transitions per update (``n_steps`` 256 per env; 2.1× the env steps per second
#: on 2*2, benchmarks/README.md); SAC's cost is its one gradient step per transition, which
#: more envs would not cut without changing that ratio.
BASELINE_ENVS = {"ppo": 8, "sac": 1}


@dataclass(frozen=True, kw_only=True)
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
        baselines: Train the deep-RL baselines (rows R1.x, R2.x) unless rows are named;
            without them the table shows theirs from ``reference:paper``.
        rl_env_steps: Env steps of each deep-RL baseline (PPO, SAC);
            ``None``: :attr:`rs_gail_env_steps`, RS-GAIL's own budget for π_n.
        rl_curve_points: Points of each baseline's learning curve.
        robustness_episodes: Episodes per cell of the robustness table (policy ×
            condition, :mod:`tolins.bench.table.robustness`) and training seed.
        study_particles: Posterior samples per goal query of the inference study;
            ``None``: the study's own default (``StudyConfig.particles``).
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
    baselines: bool = True
    rl_env_steps: int | None = None
    rl_curve_points: int = 20
    robustness_episodes: int = 6
    study_particles: int | None = None

    @property
    def iteration_episodes(self) -> int:
        """The episodes of one RS-GAIL iteration (per workpiece): ``popsize ×
        candidate_episodes`` candidate episodes and ``curve_episodes`` of the mean."""
        return self.popsize * self.candidate_episodes + self.curve_episodes

    @property
    def rs_gail_env_steps(self) -> int:
        """The most env steps RS-GAIL takes for π_n: :attr:`iteration_episodes` per
        iteration, each at most ``HORIZON`` steps (BC's expert demonstrations not
        counted)."""
        return self.nominal_iterations * self.iteration_episodes * HORIZON

    @property
    def deep_rl_env_steps(self) -> int:
        """Env steps of each PPO/SAC training: ``rl_env_steps``, else RS-GAIL's for π_n."""
        return self.rl_env_steps or self.rs_gail_env_steps

    def sb3(
        self, algorithm: str, env_id: str, backend: str, seed: int, reward_mode: str
    ) -> Sb3Config:
        steps = self.deep_rl_env_steps
        return Sb3Config(
            algorithm,
            env_id,
            backend=backend,
            reward_mode=reward_mode,
            env_steps=steps,
            curve_every=max(steps // self.rl_curve_points, 1),
            curve_episodes=self.curve_episodes,
            seed=seed,
            n_envs=BASELINE_ENVS[algorithm],
        )

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
    # 5 training seeds, the unit of the verdicts' intervals (tolins.bench.table.statistics).
    # The deep-RL baselines get RS-GAIL's budget for π_n: 100 × (16 × 4 + 8) × 40 = 288,000.
    "paper": Profile(
        name="paper",
        demonstrations=50,
        bc_epochs=200,
        nominal_iterations=100,
        residual_iterations=100,
        popsize=16,
        candidate_episodes=4,
        curve_episodes=8,
        eval_episodes=100,
        seeds=5,
        study_samples=500,
        recorded_episodes=3,
        robustness_episodes=20,
    ),
    # About 8 min on 2 idle cores with three training seeds (the unit of the verdicts): a tenth
    # of the paper's per-seed budgets (10 RS-GAIL iterations for π_n, 8 for φ2), 50
    # evaluation episodes per row and seed; 6 episodes per robustness cell and seed (the
    # default; 50 cells, docs/benchmark.md). No deep-RL baselines: at RS-GAIL's quick
    # budget (28,800 env steps) SAC alone would take 3 min per run (48 runs), and on the
    # sparse reward their curves stay at zero; the table shows theirs from reference:paper.
    "quick": Profile(
        name="quick",
        demonstrations=50,
        bc_epochs=200,
        nominal_iterations=10,
        residual_iterations=8,
        popsize=16,
        candidate_episodes=4,
        curve_episodes=8,
        eval_episodes=50,
        seeds=3,
        study_samples=500,
        recorded_episodes=2,
        baselines=False,
    ),
    # Smoke test of the whole pipeline (CI): every stage runs, nothing is learnt.
    "tiny": Profile(
        name="tiny",
        demonstrations=4,
        bc_epochs=5,
        nominal_iterations=1,
        residual_iterations=1,
        popsize=4,
        candidate_episodes=1,
        curve_episodes=2,
        eval_episodes=2,
        seeds=1,
        study_samples=6,
        recorded_episodes=1,
        rl_env_steps=200,
        rl_curve_points=1,
        robustness_episodes=1,
        study_particles=200,
    ),
}
