"""The paper's 5-d tolerance embedding ψ(ε) of a workpiece (users import it as
:mod:`tolins.embedding`).

``encode(spec)`` images the spec's tolerance (:func:`tolins.tolerance.image`, 64×64, the
family's window) and runs the encoder of the shipped checkpoint of ``spec.family``
(``tolins/assets/embedding_circle.pt``, ``tolins/assets/embedding_polygon.pt``, package
data; loaded once, cached).

``model="graded"`` uses the graded checkpoints instead
(``tolins/assets/embedding_<family>_graded.pt``):
trained on the tolerance grades' ranges (circle radial clearance 0.015–0.35 mm, polygon
gap 0.02–0.2 mm; :data:`tolins.learning.embedding.ranges.GRADED_RANGES`) imaged on a warped grid
(:data:`tolins.geometry.tolerance.GRADED_WINDOWS`). The default ``model="paper"`` is the
checkpoint the paper's policies were trained with, unchanged.

Out of range: a spec outside the ranges its family was trained on
(:mod:`tolins.learning.embedding.ranges`, e.g. a 2*30 socket, a 3-row socket, bent pins, an
octagon) raises ``ValueError`` listing what is outside. Pass ``strict=False`` to
extrapolate anyway; that emits an :class:`ExtrapolationWarning`.
"""

from __future__ import annotations

import functools
import warnings
from pathlib import Path

import numpy as np
import torch

from tolins.geometry.specs import SocketSpec
from tolins.geometry.tolerance import image
from tolins.learning.embedding.autoencoder import to_image, to_targets
from tolins.learning.embedding.checkpoint import EmbeddingModel, load_checkpoint
from tolins.learning.embedding.ranges import MODELS
from tolins.resources import package_path

#: The package's ``tolins/assets/`` folder, where the shipped checkpoints are.
ASSETS = package_path("tolins.assets")


class ExtrapolationWarning(UserWarning):
    """A spec outside the family's training ranges was encoded with ``strict=False``."""


def checkpoint_path(family: str, model: str = "paper") -> Path:
    """The shipped checkpoint of ``family``: ``tolins/assets/embedding_<family>.pt``, or
    ``tolins/assets/embedding_<family>_graded.pt`` for ``model="graded"``."""
    if family not in ("circle", "polygon"):
        raise ValueError(f"family={family!r}; allowed: 'circle', 'polygon'")
    if model not in MODELS:
        raise ValueError(f"model={model!r}; allowed: {', '.join(map(repr, MODELS))}")
    suffix = "" if model == "paper" else f"_{model}"
    return package_path("tolins.assets", f"embedding_{family}{suffix}.pt")


@functools.cache
def load_model(family: str, model: str = "paper") -> EmbeddingModel:
    """The shipped model of ``family`` (``model``: "paper" or "graded"), loaded once per
    process."""
    path = checkpoint_path(family, model)
    if not path.is_file():
        flag = "" if model == "paper" else f" --model {model}"
        raise FileNotFoundError(
            f"{path} is missing; it ships as package data of tolins (reinstall tolins, or "
            f"train it with `tolins embed train --family {family}{flag} --out {path}`)"
        )
    loaded = load_checkpoint(path, family=family)
    stored = loaded.config.get("model", "paper")
    if stored != model:
        raise ValueError(f"{path} holds the {stored!r} model; allowed: {model!r}")
    return loaded


def encode(spec: SocketSpec, *, strict: bool = True, model: str = "paper") -> np.ndarray:
    """The embedding ``(5,)`` (float64) of ``spec``'s tolerance image (``model``: the
    paper's checkpoints, the default, or ``"graded"``)."""
    model = _checked_model(spec, strict, model)
    images = image(spec, model.network.architecture.resolution, window=model.window)[None]
    with torch.no_grad():
        latent = model.network.encode(to_targets(images, model.window.theta_cap))
    return latent[0].numpy().astype(np.float64)


def decode(embedding: np.ndarray, family: str, *, model: str = "paper") -> np.ndarray:
    """The tolerance image ``(64, 64)`` the decoder of ``family`` makes of ``embedding``
    (in the model's window: the graded model's is warped)."""
    model = load_model(family, model)
    latent = torch.as_tensor(np.asarray(embedding, dtype=np.float32)).reshape(1, -1)
    dim = model.network.architecture.latent_dim
    if latent.shape[1] != dim:
        raise ValueError(f"embedding has {latent.shape[1]} values; allowed: {dim}")
    with torch.no_grad():
        return to_image(model.network.decode(latent), model.window.theta_cap)[0]


def reconstruct(spec: SocketSpec, *, strict: bool = True, model: str = "paper") -> np.ndarray:
    """``decode(encode(spec))``: the autoencoder's version of ``spec``'s tolerance image."""
    return decode(encode(spec, strict=strict, model=model), spec.family, model=model)


def _checked_model(spec: SocketSpec, strict: bool, name: str = "paper") -> EmbeddingModel:
    family = getattr(spec, "family", None)
    if family not in ("circle", "polygon"):
        raise ValueError(f"spec={spec!r}; allowed: a CircularSocket or PolygonSocket")
    model = load_model(family, name)
    outside = model.ranges.violations(spec)
    if outside:
        which = "" if name == "paper" else f"{name} "
        message = (
            f"{spec!r} is outside the {family} {which}embedding's training ranges: "
            f"{'; '.join(outside)}"
        )
        if strict:
            raise ValueError(f"{message}; pass strict=False to extrapolate")
        warnings.warn(message, ExtrapolationWarning, stacklevel=3)
    return model
