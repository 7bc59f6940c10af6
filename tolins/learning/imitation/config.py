"""Run configurations of the policy learning (torch-free, so the CLI builds fast).

Every field is a CLI option of ``tolins train`` (see :mod:`tolins.cli.args`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from tolins.geometry.validation import check_seed


def _check_at_least(config: object, names: tuple[str, ...], minimum: int) -> None:
    for name in names:
        value = getattr(config, name)
        if value < minimum:
            raise ValueError(f"{name}={value!r}; allowed: an integer ≥ {minimum}")


#: The most units a hidden layer may have (a 4096 × 4096 layer is 67 MB of float32; a
#: billion units would not fit in memory, and CMA-ES searches every weight).
HIDDEN_MAX = 4096


def _check_hidden(config: object, names: tuple[str, ...]) -> None:
    for name in names:
        value = getattr(config, name)
        if not isinstance(value, int) or isinstance(value, bool) or not 1 <= value <= HIDDEN_MAX:
            raise ValueError(f"{name}={value!r}; allowed: an integer 1 … {HIDDEN_MAX}")


def _check_positive(config: object, names: tuple[str, ...]) -> None:
    for name in names:
        value = getattr(config, name)
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name}={value!r}; allowed: a finite number > 0")


@dataclass(frozen=True)
class TaskConfig:
    """The environment, the expert and its demonstrations (shared by every trainer)."""

    backend: Literal["mujoco", "kinematic"] = "mujoco"
    """Simulator: MuJoCo contact physics or the paper's kinematic simulator."""
    expert: Literal["safe", "efficient"] = "safe"
    """Scripted expert whose demonstrations are cloned and imitated."""
    demonstrations: int = 50
    """Expert episodes collected per training environment."""
    seed: int = 0
    """Seeds the demonstrations, the network weights, the batches, CMA-ES and every rollout."""

    def __post_init__(self) -> None:
        _check_at_least(self, ("demonstrations",), 2)
        check_seed("seed", self.seed)


@dataclass(frozen=True)
class BCConfig:
    """Behaviour cloning of the expert (the start of Algorithm 1)."""

    hidden: int = 32
    """Units in each of the nominal policy's two hidden layers."""
    epochs: int = 200
    """Passes over the training demonstrations."""
    batch_size: int = 256
    """(observation, action) pairs per gradient step."""
    learning_rate: float = 3e-3
    """Adam's learning rate."""
    held_out: float = 0.2
    """Fraction of the demonstration episodes kept out of training to measure the fit."""

    def __post_init__(self) -> None:
        _check_at_least(self, ("epochs", "batch_size"), 1)
        _check_hidden(self, ("hidden",))
        _check_positive(self, ("learning_rate",))
        if not 0 < self.held_out < 1:
            raise ValueError(f"held_out={self.held_out!r}; allowed: 0 < held_out < 1")


@dataclass(frozen=True)
class RSGailConfig:
    """RS-GAIL (Algorithm 1): discriminator + environment reward, policy searched by CMA-ES."""

    iterations: int = 100
    """CMA-ES iterations (the paper's maximum: 100)."""
    popsize: int = 16
    """Candidate policies per CMA-ES iteration."""
    episodes: int = 4
    """Episodes per candidate (each seeded from seed, iteration, candidate, episode)."""
    sigma0: float = 0.05
    """Initial CMA-ES step size on the flat parameter vector."""
    alpha: float = 0.8
    """Weight of the environment reward against the discriminator term (the paper: 0.8)."""
    alpha_start: float | None = None
    """If set, alpha rises linearly from this value to ``alpha`` over the iterations."""
    discriminator_every: int = 5
    """Iterations between discriminator updates (the paper: 5)."""
    discriminator_steps: int = 50
    """Full-batch Adam steps of each discriminator update."""
    discriminator_hidden: int = 64
    """Units in each of the discriminator's two hidden layers."""
    eval_episodes: int = 8
    """Episodes of the CMA-ES mean per iteration for the learning curves (fixed seeds)."""
    workers: int = 2
    """Threads rolling out candidates; results do not depend on it."""
    stop_rule: bool = False
    """Stop early by the paper's rule: reward stopped rising and D(student) in 40-60 percent."""
    patience: int = 10
    """Iterations without a new best evaluation reward before the stop rule may fire."""
    keep_best: bool = False
    """Return the CMA-ES mean with the best evaluation reward (on the fixed evaluation
    seeds of the learning curves) instead of the last one."""

    def __post_init__(self) -> None:
        _check_at_least(self, ("iterations", "discriminator_every", "eval_episodes"), 1)
        _check_at_least(self, ("episodes", "discriminator_steps", "workers", "patience"), 1)
        _check_hidden(self, ("discriminator_hidden",))
        _check_at_least(self, ("popsize",), 2)
        _check_positive(self, ("sigma0",))
        for name in ("alpha", "alpha_start"):
            value = getattr(self, name)
            if value is not None and not 0 <= value <= 1:
                raise ValueError(f"{name}={value!r}; allowed: 0 ≤ {name} ≤ 1")

    def alpha_at(self, iteration: int) -> float:
        """The reward weight α of ``iteration`` (0-based) under the optional linear schedule."""
        if self.alpha_start is None or self.iterations == 1:
            return self.alpha
        fraction = iteration / (self.iterations - 1)
        return self.alpha_start + fraction * (self.alpha - self.alpha_start)


@dataclass(frozen=True)
class ResidualConfig:
    """The tolerance-guided residual φ2 (trained by RS-GAIL with φ1 frozen)."""

    residual_hidden: int = 32
    """Units in the residual network's hidden layer (input: observation and ψ)."""

    def __post_init__(self) -> None:
        _check_hidden(self, ("residual_hidden",))
