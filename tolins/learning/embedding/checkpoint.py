"""Embedding checkpoints: atomic writes and checked loads.

A checkpoint is a ``torch.save`` dict of plain values and tensors (loaded with
``weights_only=True``): ``format``, ``family``, ``architecture``, ``config`` (the
training config), ``seed``, ``tolins_version``, ``ranges`` (the family's spec ranges),
``window`` (the image window) and ``state_dict``.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from tolins.geometry.tolerance import GRADED_WINDOWS, WINDOWS, ImageWindow
from tolins.learning.artefacts import atomic_torch_save, load_payload
from tolins.learning.embedding.autoencoder import Architecture, ToleranceAutoencoder
from tolins.learning.embedding.ranges import FamilyRanges, ranges_from_dict

#: Bumped when the stored layout or the meaning of the model's inputs changes.
FORMAT = "tolins.embedding/1"


@dataclass(frozen=True)
class EmbeddingModel:
    """A loaded checkpoint: the network (in eval mode) and what it was trained on."""

    family: str
    network: ToleranceAutoencoder
    window: ImageWindow
    ranges: FamilyRanges
    config: dict[str, Any]
    seed: int
    tolins_version: str


def save_checkpoint(path: str | os.PathLike, model: EmbeddingModel) -> Path:
    """Write ``model`` to ``path`` atomically (temp file in the same folder + ``os.replace``)."""
    payload = {
        "format": FORMAT,
        "family": model.family,
        "architecture": asdict(model.network.architecture),
        "config": dict(model.config),
        "seed": int(model.seed),
        "tolins_version": model.tolins_version,
        "ranges": asdict(model.ranges),
        "window": asdict(model.window),
        "state_dict": model.network.state_dict(),
    }
    return atomic_torch_save(path, payload)


def load_checkpoint(path: str | os.PathLike, family: str | None = None) -> EmbeddingModel:
    """Load and check a checkpoint written by :func:`save_checkpoint`.

    Raises ``ValueError`` when the file is not such a checkpoint, was written for another
    family than ``family`` (if given), for another image window than this tolins uses, or
    when its weights do not fit the architecture it declares.
    """
    path = Path(path)
    payload = load_payload(path, FORMAT)
    stored = payload["family"]
    if family is not None and stored != family:
        raise ValueError(f"{path} is a {stored!r} checkpoint; allowed: {family!r}")
    window = ImageWindow(**payload["window"])
    # Checkpoints before the graded model have no ``model`` in their config: the paper's.
    model = payload["config"].get("model", "paper")
    if model not in ("paper", "graded"):
        raise ValueError(f"{path} is a {model!r} model; allowed: 'paper', 'graded'")
    expected = (WINDOWS if model == "paper" else GRADED_WINDOWS)[stored]
    if window != expected:
        raise ValueError(
            f"{path} was trained on the window {window}; this tolins images {stored} "
            f"workpieces of the {model} model in {expected}: retrain with `tolins embed train`"
        )
    network = _network(path, payload["architecture"], payload["state_dict"])
    return EmbeddingModel(
        family=stored,
        network=network,
        window=window,
        ranges=ranges_from_dict(stored, payload["ranges"], model),
        config=payload["config"],
        seed=payload["seed"],
        tolins_version=payload["tolins_version"],
    )


def _network(path: Path, stored: dict[str, Any], state: dict[str, Any]) -> ToleranceAutoencoder:
    names = {item.name for item in dataclasses.fields(Architecture)}
    if set(stored) != names:
        raise ValueError(
            f"{path} declares architecture fields {sorted(stored)}; allowed: {sorted(names)}"
        )
    architecture = Architecture(**{**stored, "channels": tuple(stored["channels"])})
    network = ToleranceAutoencoder(architecture)
    try:
        network.load_state_dict(state)
    except RuntimeError as error:
        first = str(error).splitlines()[1:3]
        raise ValueError(
            f"{path}: its weights do not fit the architecture it declares ({architecture}): "
            f"{' '.join(line.strip() for line in first)}"
        ) from error
    return network.eval()
