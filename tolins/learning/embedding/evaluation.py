"""Reconstruction quality on held-out workpieces: region IoU and θ error."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from tolins.geometry.specs import SocketSpec
from tolins.learning.embedding.autoencoder import to_image, to_targets
from tolins.learning.embedding.checkpoint import EmbeddingModel
from tolins.learning.embedding.data import family_ranges, make_images, sample_specs

#: Seed of the held-out workpieces. Specs have continuous fields, so a set drawn from
#: another stream than the training data shares no workpiece with it.
HELD_OUT_SEED = 20261122


@dataclass(frozen=True)
class Quality:
    """Per-image figures over a set of workpieces (means, and the worst IoU).

    ``theta_error`` is the mean ``|θ̂ − θ|`` (rad) over the cells of the true region,
    with ``θ̂`` the decoded value whether or not the cell was predicted inside;
    ``relative_theta_error`` divides each image's error by its largest θ.
    """

    count: int
    iou: float
    worst_iou: float
    theta_error: float
    relative_theta_error: float


def reconstruct_images(model: EmbeddingModel, images: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Decoded images (``-1`` outside the predicted region) and decoded θ everywhere."""
    cap = model.window.theta_cap
    with torch.no_grad():
        outputs = model.network(to_targets(images, cap))
    theta = cap * outputs[:, 1].clamp(0.0, 1.0).numpy().astype(np.float64) ** 2
    return to_image(outputs, cap), theta


def region_iou(truth: np.ndarray, predicted: np.ndarray) -> np.ndarray:
    """IoU of the regions ``image >= 0`` per image (1 where both are empty)."""
    a, b = truth >= 0, predicted >= 0
    union = (a | b).sum(axis=(-2, -1))
    inter = (a & b).sum(axis=(-2, -1))
    return np.where(union > 0, inter / np.maximum(union, 1), 1.0)


def measure(model: EmbeddingModel, specs: list[SocketSpec]) -> Quality:
    """Reconstruct the tolerance images of ``specs`` and score them."""
    truth = make_images(specs, model.network.architecture.resolution, model.window)
    predicted, theta = reconstruct_images(model, truth)
    iou = region_iou(truth, predicted)
    inside = truth >= 0
    errors, relative = [], []
    for true, guess, mask in zip(truth, theta, inside, strict=True):
        if mask.any():
            error = float(np.mean(np.abs(guess[mask] - true[mask])))
            errors.append(error)
            relative.append(error / max(float(true[mask].max()), 1e-12))
    return Quality(
        count=len(specs),
        iou=float(iou.mean()),
        worst_iou=float(iou.min()),
        theta_error=float(np.mean(errors)),
        relative_theta_error=float(np.mean(relative)),
    )


def held_out_specs(
    family: str, count: int, seed: int = HELD_OUT_SEED, *, model: str = "paper"
) -> list[SocketSpec]:
    """``count`` workpieces of ``family`` drawn from the ranges of ``model`` ("paper",
    "graded") with a held-out seed."""
    ranges = family_ranges(family, model)
    return sample_specs(family, count, np.random.default_rng([seed, 1]), ranges)
