"""The tolerance autoencoder: a tolerance image to a 5-d embedding and back.

Images (:func:`tolins.tolerance.image`) hold ``theta ≥ 0`` in the tolerance region and
``NO_TOLERANCE = -1`` outside it. That -1 is a label, not a rotation, so the network
never regresses it. An image is split into two targets per cell,

    m = 1[θ ≥ 0]                  (the region)
    t = sqrt(min(θ, θ_cap) / θ_cap)    inside the region, 0 outside

(the square root spreads the small rotations of long sockets, ~0.005 rad, against the
0.5 rad cap). ``(m, t)`` is the encoder's 2-channel input; the decoder returns a region
logit ``ℓ`` and a value ``v`` per cell. See :func:`reconstruction_loss` and
:func:`to_image`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from tolins.geometry.tolerance import NO_TOLERANCE


@dataclass(frozen=True)
class Architecture:
    """Sizes of the autoencoder (stored in checkpoints and checked on load).

    Attributes:
        resolution: Side of the square input image (a multiple of ``2 ** len(channels)``).
        channels: Channels of the stride-2 convolutions (the decoder mirrors them).
        latent_dim: Size of the embedding (the paper's 5).
    """

    resolution: int = 64
    channels: tuple[int, ...] = (16, 32, 32, 32)
    latent_dim: int = 5

    def __post_init__(self) -> None:
        side = self.resolution // 2 ** len(self.channels)
        if side < 1 or side * 2 ** len(self.channels) != self.resolution:
            raise ValueError(
                f"resolution={self.resolution} with {len(self.channels)} stride-2 layers; "
                f"allowed: a multiple of {2 ** len(self.channels)}"
            )
        if self.latent_dim < 1 or min(self.channels, default=0) < 1:
            raise ValueError(f"{self!r}: allowed: latent_dim ≥ 1 and channels ≥ 1")


class ToleranceAutoencoder(nn.Module):
    """Stride-2 4×4 convolutions + a linear layer to the embedding; the decoder mirrors it.

    64×64×2 → 32×32×16 → 16×16×32 → 8×8×32 → 4×4×32 → 5, then back to 64×64×2
    (region logit, value). About 90,000 parameters.
    """

    def __init__(self, architecture: Architecture = Architecture()) -> None:
        super().__init__()
        self.architecture = architecture
        widths = (2, *architecture.channels)
        self._side = architecture.resolution // 2 ** len(architecture.channels)
        flat = widths[-1] * self._side**2
        down: list[nn.Module] = []
        for a, b in itertools.pairwise(widths):
            down += [nn.Conv2d(a, b, 4, stride=2, padding=1), nn.GELU()]
        self.encoder = nn.Sequential(*down, nn.Flatten(), nn.Linear(flat, architecture.latent_dim))
        self.expand = nn.Linear(architecture.latent_dim, flat)
        up: list[nn.Module] = []
        back = widths[::-1]
        for i, (a, b) in enumerate(itertools.pairwise(back)):
            last = i == len(back) - 2
            up.append(nn.ConvTranspose2d(a, b if not last else a, 4, stride=2, padding=1))
            up.append(nn.GELU())
        up.append(nn.Conv2d(back[-2], 2, 3, padding=1))
        self.decoder = nn.Sequential(*up)

    def encode(self, inputs: torch.Tensor) -> torch.Tensor:
        """``(batch, 2, res, res)`` targets ``(m, t)`` → ``(batch, latent_dim)``."""
        return self.encoder(inputs)

    def decode(self, latent: torch.Tensor) -> torch.Tensor:
        """``(batch, latent_dim)`` → ``(batch, 2, res, res)``: region logit, value."""
        width = self.architecture.channels[-1]
        hidden = F.gelu(self.expand(latent)).view(-1, width, self._side, self._side)
        return self.decoder(hidden)

    def forward(self, inputs: torch.Tensor) -> torch.Tensor:
        return self.decode(self.encode(inputs))


def to_targets(images: np.ndarray, theta_cap: float) -> torch.Tensor:
    """Images ``(batch, res, res)`` → float32 targets ``(batch, 2, res, res)`` = ``(m, t)``."""
    images = np.asarray(images, dtype=np.float64)
    region = images >= 0
    value = np.sqrt(np.clip(images, 0.0, theta_cap) / theta_cap) * region
    return torch.from_numpy(np.stack([region, value], axis=1).astype(np.float32))


def to_image(outputs: torch.Tensor, theta_cap: float) -> np.ndarray:
    """Decoder outputs → images: ``θ̂ = θ_cap · clip(v, 0, 1)²`` where ``ℓ ≥ 0``, else -1."""
    logit, value = outputs[:, 0], outputs[:, 1]
    theta = theta_cap * value.clamp(0.0, 1.0) ** 2
    image = torch.where(logit >= 0, theta, torch.full_like(theta, NO_TOLERANCE))
    return image.detach().cpu().numpy().astype(np.float64)


def reconstruction_loss(
    outputs: torch.Tensor, targets: torch.Tensor, theta_weight: float = 1.0
) -> torch.Tensor:
    """Region BCE over all cells plus θ regression inside the true region.

    With region logit ``ℓ``, value ``v`` and targets ``(m, t)`` over the cells ``c`` of a
    batch,

        L = mean_c BCE(σ(ℓ_c), m_c)  +  w · Σ_c m_c (v_c − t_c)² / Σ_c m_c

    where ``BCE(p, m) = −m log p − (1 − m) log(1 − p)`` and ``w = theta_weight``. The
    value is only fitted where a rotation exists; outside, the region head alone decides
    (no regression towards the -1 label).
    """
    logit, value = outputs[:, 0], outputs[:, 1]
    region, target = targets[:, 0], targets[:, 1]
    bce = F.binary_cross_entropy_with_logits(logit, region)
    inside = region.sum().clamp_min(1.0)
    theta = ((value - target) ** 2 * region).sum() / inside
    return bce + theta_weight * theta
