"""Tolerance-guided training (the paper's second phase, Fig. 2c): φ1 copied from π_n and
frozen, the residual φ2 (zero at the start) trained by RS-GAIL over a set of workpieces,
each seen with its tolerance embedding ψ (:func:`tolins.learning.embedding.encoding.encode`)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from tolins.learning.embedding.encoding import encode
from tolins.learning.imitation.config import ResidualConfig, RSGailConfig
from tolins.learning.imitation.policy import Policy
from tolins.learning.imitation.rs_gail import RSGailResult, Workpiece, train_rs_gail
from tolins.rollouts.episodes import Episode


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


def tolerance_guided_policy(
    nominal: Policy, pieces: list[Workpiece], residual: ResidualConfig
) -> Policy:
    """π_φ at its start: φ1 copied from ``nominal`` (frozen) and φ2 zero, for ``pieces``
    (``ValueError`` unless each has its embedding ψ)."""
    if any(piece.embedding is None for piece in pieces):
        raise ValueError("every workpiece needs its embedding ψ; see workpieces()")
    return Policy.tolerance_guided(nominal, residual_hidden=residual.residual_hidden)


def train_tolerance_guided(
    nominal: Policy,
    pieces: list[Workpiece],
    expert: list[Episode],
    config: RSGailConfig,
    residual: ResidualConfig,
    **run: Any,
) -> RSGailResult:
    """π_φ from ``nominal`` (φ1, frozen) with φ2 searched by RS-GAIL on ``pieces``; the
    episodes of each candidate cycle through the workpieces. ``run``: the keywords of
    :func:`~tolins.learning.imitation.rs_gail.train_rs_gail` (``seed``, ``backend``,
    ``out``, ``metadata`` and its options)."""
    policy = tolerance_guided_policy(nominal, pieces, residual)
    return train_rs_gail(policy, pieces, expert, config, **run)
