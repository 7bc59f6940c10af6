"""Tolerance-guided training (the paper's second phase, Fig. 2c): φ1 copied from π_n and
frozen, the residual φ2 (zero at the start) trained by RS-GAIL over a set of workpieces,
each seen with its tolerance embedding ψ (:func:`tolins.learning.embedding.encode`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from tolins.learning.demonstrations import Rollout
from tolins.learning.embedding import encode
from tolins.learning.policy import Policy
from tolins.learning.policy_config import ResidualConfig, RSGailConfig
from tolins.learning.rs_gail import RSGailResult, Workpiece, train_rs_gail
from tolins.rollouts.pool import CandidatePool


def workpieces(
    env_ids: list[str], embeddings: list[np.ndarray] | None = None, *, model: str = "paper"
) -> list[Workpiece]:
    """The envs with their embeddings (encoded from each env's socket unless given, with
    the embedding ``model``: the paper's, or ``"graded"`` for the tolerance grades)."""
    if embeddings is None:
        embeddings = [encode(gym.spec(env_id).kwargs["socket"], model=model) for env_id in env_ids]
    if len(embeddings) != len(env_ids):
        raise ValueError(f"{len(embeddings)} embeddings for {len(env_ids)} envs; allowed: one each")
    return [
        Workpiece(e, np.asarray(psi, dtype=float))
        for e, psi in zip(env_ids, embeddings, strict=True)
    ]


def train_tolerance_guided(
    nominal: Policy,
    pieces: list[Workpiece],
    expert: list[Rollout],
    config: RSGailConfig,
    residual: ResidualConfig,
    *,
    seed: int,
    backend: str,
    out: str | Path,
    metadata: dict[str, Any],
    resume: bool = False,
    progress: bool = True,
    pool: CandidatePool | None = None,
) -> RSGailResult:
    """π_φ from ``nominal`` (φ1, frozen) with φ2 searched by RS-GAIL on ``pieces``; the
    episodes of each candidate cycle through the workpieces."""
    if any(piece.embedding is None for piece in pieces):
        raise ValueError("every workpiece needs its embedding ψ; see workpieces()")
    policy = Policy.tolerance_guided(nominal, residual_hidden=residual.residual_hidden)
    return train_rs_gail(
        policy,
        pieces,
        expert,
        config,
        seed=seed,
        backend=backend,
        out=out,
        metadata=metadata,
        resume=resume,
        progress=progress,
        pool=pool,
    )
