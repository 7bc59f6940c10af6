"""The GAIL discriminator D(s, a): which (observation, action) pairs look like the expert's.

``D(s, a) = σ(ℓ(s, a))`` with ``ℓ`` an MLP ``12 → h → h → 1`` on ``[ŝ / s0, a / a_max]``.
Trained by binary cross-entropy with logits, expert = 1, student = 0, each class
averaged on its own (so unequal counts do not bias it):

    L(d) = −E_e[log σ(ℓ)] − E_π[log(1 − σ(ℓ))]

which is the log-loss form of the paper's ``max_d E_e[D] − E_π[D]``. RS-GAIL scores a
student pair by :meth:`Discriminator.probability` ``D(s, a)`` (the paper's term);
:meth:`Discriminator.reward`, ``softplus(ℓ) = −log(1 − D)`` (``imitation``'s generator
reward), is kept for comparison. Updates are full-batch Adam steps: no
randomness, so a resumed run repeats them exactly.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from tolins.learning.imitation.policy import ACTION_DIM, OBS_DIM, OBS_SCALE
from tolins.paper import A_MAX


class Discriminator(nn.Module):
    """D(s, a); :meth:`update` trains it, :meth:`reward` and :meth:`expert_probability` score."""

    def __init__(self, hidden: int = 64, *, seed: int = 0, learning_rate: float = 3e-3) -> None:
        super().__init__()
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed)
            self.net = nn.Sequential(
                nn.Linear(OBS_DIM + ACTION_DIM, hidden, dtype=torch.float64),
                nn.Tanh(),
                nn.Linear(hidden, hidden, dtype=torch.float64),
                nn.Tanh(),
                nn.Linear(hidden, 1, dtype=torch.float64),
            )
        scale = np.concatenate([OBS_SCALE, A_MAX])
        self.register_buffer("scale", torch.tensor(scale, dtype=torch.float64))
        self.optimiser = torch.optim.Adam(self.net.parameters(), lr=learning_rate)

    def logits(self, observations: np.ndarray, actions: np.ndarray) -> torch.Tensor:
        x = torch.as_tensor(np.concatenate([observations, actions], axis=-1)) / self.scale
        return self.net(x).squeeze(-1)

    def update(
        self,
        expert: tuple[np.ndarray, np.ndarray],
        student: tuple[np.ndarray, np.ndarray],
        steps: int,
    ) -> float:
        """``steps`` full-batch Adam steps on L(d); returns the last loss."""
        loss = torch.tensor(0.0)
        for _ in range(steps):
            loss = F.binary_cross_entropy_with_logits(
                self.logits(*expert), torch.ones(len(expert[0]), dtype=torch.float64)
            ) + F.binary_cross_entropy_with_logits(
                self.logits(*student), torch.zeros(len(student[0]), dtype=torch.float64)
            )
            self.optimiser.zero_grad()
            loss.backward()
            self.optimiser.step()
        return float(loss.detach())

    def reward(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """``softplus(ℓ(s, a))`` per pair."""
        with torch.no_grad():
            return F.softplus(self.logits(observations, actions)).numpy()

    def probability(self, observations: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """``D(s, a) = σ(ℓ(s, a))`` per pair."""
        with torch.no_grad():
            return torch.sigmoid(self.logits(observations, actions)).numpy()

    def expert_probability(self, observations: np.ndarray, actions: np.ndarray) -> float:
        """Mean ``D(s, a) = σ(ℓ)`` over the pairs: how expert-like they look."""
        with torch.no_grad():
            return float(torch.sigmoid(self.logits(observations, actions)).mean())

    def full_state(self) -> dict:
        """Weights and optimiser state (for checkpoints)."""
        return {"net": self.state_dict(), "optimiser": self.optimiser.state_dict()}

    def load_full_state(self, state: dict) -> None:
        self.load_state_dict(state["net"])
        self.optimiser.load_state_dict(state["optimiser"])
