"""The training configuration of the embedding (torch-free, so the CLI builds fast)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from tolins.geometry.validation import check_seed
from tolins.learning.embedding.ranges import MODELS, RANGES


@dataclass(frozen=True)
class EmbeddingTrainConfig:
    """How to train the embedding of one family (every field is a CLI option)."""

    family: Literal["circle", "polygon"] = "circle"
    """Workpiece family: circle sockets 2*1…2*20 or polygon pegs with 3…6 sides."""
    seed: int = 0
    """Seeds the sampled workpieces (numpy Generator), the initial weights and the batches."""
    workpieces: int = 2000
    """Number of training workpieces (one tolerance image each), drawn from the ranges."""
    epochs: int = 40
    """Passes over the training images."""
    batch_size: int = 32
    """Images per gradient step."""
    learning_rate: float = 3e-3
    """Adam's peak learning rate (one-cycle: 10 % warm-up, then cosine annealing)."""
    theta_weight: float = 1.0
    """Weight ``w`` of the θ regression term against the region BCE in the loss."""
    threads: int = 2
    """CPU threads torch may use while training."""
    model: Literal["paper", "graded"] = "paper"
    """paper: the shipped ranges and linear window; graded: the tolerance grades' ranges
    (circle clearance 0.015–0.35 mm, polygon gap 0.02–0.2 mm) on the warped window."""

    def __post_init__(self) -> None:
        if self.family not in RANGES:
            raise ValueError(f"family={self.family!r}; allowed: {', '.join(RANGES)}")
        check_seed("seed", self.seed)
        if self.model not in MODELS:
            raise ValueError(f"model={self.model!r}; allowed: {', '.join(MODELS)}")
        for name in ("workpieces", "epochs", "batch_size", "threads"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name}={getattr(self, name)!r}; allowed: an integer ≥ 1")
        for name in ("learning_rate", "theta_weight"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name}={value!r}; allowed: a finite number > 0")
