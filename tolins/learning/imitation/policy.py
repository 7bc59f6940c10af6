"""Policies (torch, CPU): the nominal MLP π(ŝ*) and the tolerance-guided π_φ(ŝ*, ψ).

Nominal (φ1): ``a = a_max · tanh(f1(ŝ / s0))`` with ``f1`` an MLP ``8 → h → h → 4``
(tanh hidden units, h = 32 by default: 1,476 parameters, small enough for CMA-ES).
``s0`` is a fixed observation scale (:data:`OBS_SCALE`) so that the inputs are O(1).

Tolerance-guided: ``a = a_max · tanh(f1(ŝ / s0) + f2([ŝ / s0, ψ / ψ0]))`` with ``f1``
copied from π_n and frozen, and ``f2`` (φ2) an MLP ``13 → h2 → 4`` whose last layer
starts at zero, so that π_φ equals π_n bit for bit before training (``x + 0.0 == x``).

:meth:`Policy.get_flat` / :meth:`Policy.set_flat` read and write the trainable part
only (φ1 for the nominal policy, φ2 for the tolerance-guided one) as a float64 vector
for CMA-ES. :func:`save_policy` / :func:`load_policy` store the architecture, the run's
config, seed and the tolins version beside the weights.
"""

from __future__ import annotations

import copy
import itertools
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import torch
from torch import nn

from tolins.json_input import shorten
from tolins.learning.artefacts import atomic_torch_save, load_payload
from tolins.learning.imitation.config import HIDDEN_MAX
from tolins.paper import A_MAX

#: Bumped when the stored layout or the meaning of the inputs changes.
FORMAT = "tolins.policy/1"
#: Divides the observation ``[x̂−x*, ŷ−y*, θ̂−θ*, ẑ, F̂x, F̂y, q̂θ, F̂z]`` (mm, rad, N, N·mm).
OBS_SCALE = (2.0, 2.0, 0.05, 10.0, 1.0, 1.0, 1.0, 1.0)
#: Divides the tolerance embedding ψ (its entries are O(10)).
EMBEDDING_SCALE = 10.0
OBS_DIM, ACTION_DIM, EMBEDDING_DIM = 8, 4, 5


#: The kinds of policy (:class:`PolicyArchitecture`).
KINDS = ("nominal", "tolerance_guided")


@dataclass(frozen=True)
class PolicyArchitecture:
    """What a policy checkpoint must match: kind and layer widths (each 1 …
    :data:`~tolins.learning.imitation.config.HIDDEN_MAX`: a π_φ of the widest layers has
    17 M parameters, 135 MB). ``ValueError`` for any other, so that a policy file's sizes
    are checked before anything is built from them."""

    kind: Literal["nominal", "tolerance_guided"] = "nominal"
    hidden: int = 32
    residual_hidden: int = 32

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"architecture.kind={self.kind!r}; allowed: {', '.join(KINDS)}")
        for name in ("hidden", "residual_hidden"):
            value = getattr(self, name)
            if type(value) is not int or not 1 <= value <= HIDDEN_MAX:
                raise ValueError(
                    f"architecture.{name}={value!r}; allowed: an integer 1 … {HIDDEN_MAX}"
                )


def _mlp(sizes: list[int]) -> nn.Sequential:
    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(itertools.pairwise(sizes)):
        layers.append(nn.Linear(a, b, dtype=torch.float64))
        if i < len(sizes) - 2:
            layers.append(nn.Tanh())
    return nn.Sequential(*layers)


class Policy(nn.Module):
    """π(ŝ*) or π_φ(ŝ*, ψ); call :meth:`bind` to get an ``observation -> action`` function."""

    def __init__(self, architecture: PolicyArchitecture, *, seed: int = 0) -> None:
        super().__init__()
        self.architecture = architecture
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            self.nominal = _mlp([OBS_DIM, architecture.hidden, architecture.hidden, ACTION_DIM])
            self.residual: nn.Sequential | None = None
            if architecture.kind == "tolerance_guided":
                size = [OBS_DIM + EMBEDDING_DIM, architecture.residual_hidden, ACTION_DIM]
                self.residual = _mlp(size)
                nn.init.zeros_(self.residual[-1].weight)
                nn.init.zeros_(self.residual[-1].bias)
                self.nominal.requires_grad_(False)
        self.register_buffer("obs_scale", torch.tensor(OBS_SCALE, dtype=torch.float64))
        self.register_buffer("a_max", torch.tensor(A_MAX, dtype=torch.float64))

    @classmethod
    def tolerance_guided(cls, nominal: Policy, *, residual_hidden: int = 32) -> Policy:
        """π_φ with φ1 copied from the nominal policy ``nominal`` (frozen) and φ2 = 0."""
        if nominal.architecture.kind != "nominal":
            raise ValueError("tolerance_guided() needs a nominal policy as its φ1")
        arch = PolicyArchitecture("tolerance_guided", nominal.architecture.hidden, residual_hidden)
        policy = cls(arch)
        policy.nominal.load_state_dict(nominal.nominal.state_dict())
        return policy

    def forward(self, observation: torch.Tensor, embedding: torch.Tensor | None = None):
        """Actions ``(..., 4)`` of observations ``(..., 8)`` (and embeddings ``(..., 5)``)."""
        x = observation / self.obs_scale
        pre = self.nominal(x)
        if self.residual is not None:
            if embedding is None:
                raise ValueError("a tolerance-guided policy needs the embedding ψ")
            psi = (embedding / EMBEDDING_SCALE).expand(*x.shape[:-1], EMBEDDING_DIM)
            pre = pre + self.residual(torch.cat([x, psi], dim=-1))
        return self.a_max * torch.tanh(pre)

    def bind(self, embedding: np.ndarray | None = None):
        """``observation (8,) -> action (4,)`` (numpy float64) for the workpiece ``ψ``."""
        psi = None if embedding is None else torch.as_tensor(embedding, dtype=torch.float64)

        def act(observation: np.ndarray) -> np.ndarray:
            with torch.no_grad():
                obs = torch.as_tensor(np.asarray(observation, dtype=np.float64))
                return self(obs, psi).numpy()

        return act

    def trainable(self) -> list[nn.Parameter]:
        """φ1 for a nominal policy, φ2 for a tolerance-guided one."""
        return list((self.residual or self.nominal).parameters())

    def get_flat(self) -> np.ndarray:
        """The trainable parameters as one float64 vector."""
        return nn.utils.parameters_to_vector(self.trainable()).detach().numpy().copy()

    def set_flat(self, vector: np.ndarray) -> None:
        """Write ``vector`` (as from :meth:`get_flat`) into the trainable parameters."""
        vector = torch.as_tensor(np.asarray(vector, dtype=np.float64))
        if vector.shape != (self.size,):
            raise ValueError(f"vector has shape {tuple(vector.shape)}; allowed: ({self.size},)")
        with torch.no_grad():
            nn.utils.vector_to_parameters(vector, self.trainable())

    @property
    def size(self) -> int:
        """Number of trainable parameters."""
        return sum(p.numel() for p in self.trainable())

    def with_flat(self, vector: np.ndarray) -> Policy:
        """A copy whose trainable part is ``vector`` (for one CMA-ES candidate)."""
        clone = copy.deepcopy(self)
        clone.set_flat(vector)
        return clone


def save_policy(path: str | os.PathLike, policy: Policy, metadata: dict[str, Any]) -> Path:
    """Write ``policy`` atomically with ``metadata`` (config, seed, tolins version...)."""
    payload = {
        "format": FORMAT,
        "architecture": asdict(policy.architecture),
        "metadata": metadata,
        "state_dict": policy.state_dict(),
    }
    return atomic_torch_save(path, payload)


def load_policy(path: str | os.PathLike, kind: str | None = None) -> tuple[Policy, dict[str, Any]]:
    """The policy at ``path`` and its metadata.

    Raises ``ValueError`` when the file is not a policy checkpoint, is of another kind
    than ``kind`` (if given), or its weights do not fit the architecture it declares.
    """
    payload = load_payload(path, FORMAT)
    missing = sorted({"architecture", "metadata", "state_dict"} - set(payload))
    if missing:
        raise ValueError(f"{path} has no {', '.join(missing)}; allowed: a file tolins wrote")
    architecture = _architecture(path, payload["architecture"])
    if kind is not None and architecture.kind != kind:
        raise ValueError(f"{path} holds a {architecture.kind!r} policy; allowed: {kind!r}")
    policy = Policy(architecture)
    try:
        policy.load_state_dict(payload["state_dict"])
    except (RuntimeError, TypeError) as error:  # TypeError: no dict of tensors
        lines = [line.strip() for line in str(error).splitlines()]
        detail = " ".join(lines[1:3] or lines[:1])
        raise ValueError(
            f"{path}: its weights do not fit the architecture it declares ({architecture}): "
            f"{detail}"
        ) from error
    return policy, payload["metadata"]


def _architecture(path: str | os.PathLike, stored: Any) -> PolicyArchitecture:
    """The architecture a policy file declares, checked (its fields, each size and the
    kind) before anything is built from it."""
    fields = set(PolicyArchitecture.__dataclass_fields__)
    if not isinstance(stored, dict) or set(stored) != fields:
        shown = shorten(repr(stored))
        raise ValueError(f"{path} declares architecture {shown}; allowed fields: {sorted(fields)}")
    try:
        return PolicyArchitecture(**stored)
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None
