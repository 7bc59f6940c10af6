"""The configuration of an SB3 baseline run (:mod:`tolins.learning.agents.sb3`); importable
without stable-baselines3."""

from __future__ import annotations

from dataclasses import dataclass

from tolins.envs.reward import check_reward_mode
from tolins.geometry.validation import check_int, check_seed

ALGORITHM_NAMES = ("ppo", "sac")
#: The trained model in a run's folder (an SB3 zip), its learning curve, and the checkpoint
#: of a training that has not finished (:mod:`tolins.learning.agents.sb3_checkpoint`).
MODEL = "model.zip"
CURVES = "curves.csv"
CHECKPOINT = "checkpoint.pt"

#: SB3's default PPO rollout (``n_steps`` on one env): the transitions of one update.
PPO_ROLLOUT = 2048
#: What differs from SB3's defaults, per algorithm (measured: benchmarks/README.md).
HYPERPARAMETERS: dict[str, dict] = {
    "ppo": {},
    # SB3's 256×256 networks cost 4× the time per gradient step for nothing here.
    "sac": {"policy_kwargs": {"net_arch": [64, 64]}, "learning_starts": 1000},
}


@dataclass(frozen=True)
class Sb3Config:
    """One SB3 training run.

    Attributes:
        algorithm: ``ppo`` or ``sac`` (SB3 defaults otherwise, ``MlpPolicy``).
        env_id: Training env (gymnasium id).
        backend: ``mujoco`` or ``kinematic``.
        reward_mode: The reward it learns from (:mod:`tolins.envs.reward`).
        env_steps: Training budget in env steps (control steps).
        curve_every: Env steps between two points of the learning curve.
        curve_episodes: Sparse-reward episodes per point.
        seed: Seed of the model and the training env.
        n_envs: Training envs stepped side by side (one batch: SB3's ``n_envs``; PPO
            collects ``2048 / n_envs`` steps per env per update, SAC one transition per
            env per step).
        checkpoint_every: Env steps between two checkpoints (``checkpoint.pt`` in the run's
            folder, written at the start of the first rollout after them, and whenever
            SIGINT or SIGTERM arrives): 20,000 is about 2 minutes of a paper-profile SAC
            training on MuJoCo on 2 idle cores, and a checkpoint costs at most 0.13 s
            (27 MB at 288,000 transitions; benchmarks/README.md, "Deep-RL checkpoints").
            The result does not depend on it.
    """

    algorithm: str
    env_id: str
    backend: str = "mujoco"
    reward_mode: str = "dense"
    env_steps: int = 100_000
    curve_every: int = 10_000
    curve_episodes: int = 8
    seed: int = 0
    n_envs: int = 1
    checkpoint_every: int = 20_000

    def __post_init__(self) -> None:
        if self.algorithm not in ALGORITHM_NAMES:
            allowed = ", ".join(ALGORITHM_NAMES)
            raise ValueError(f"algorithm={self.algorithm!r}; allowed: {allowed}")
        check_reward_mode(self.reward_mode)
        for name in ("env_steps", "curve_every", "curve_episodes", "n_envs", "checkpoint_every"):
            check_int(name, getattr(self, name), minimum=1)
        check_seed("seed", self.seed)

    def settings(self) -> str:
        """The algorithm's settings as trained, in a line (SB3's defaults but these)."""
        changed = {**HYPERPARAMETERS[self.algorithm]}
        if self.algorithm == "ppo":
            changed["n_steps"] = max(PPO_ROLLOUT // self.n_envs, 1)
        changed["n_envs"] = self.n_envs
        shown = ", ".join(f"{key} {value}" for key, value in changed.items())
        return f"{self.algorithm.upper()}, SB3 defaults but {shown}"
