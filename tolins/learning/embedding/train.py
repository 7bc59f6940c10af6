"""Training of the tolerance autoencoder of one family (``tolins embed train``)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

import tolins
from tolins.learning.artefacts import check_finite_training
from tolins.learning.embedding.autoencoder import (
    Architecture,
    ToleranceAutoencoder,
    reconstruction_loss,
    to_targets,
)
from tolins.learning.embedding.checkpoint import EmbeddingModel
from tolins.learning.embedding.config import EmbeddingTrainConfig
from tolins.learning.embedding.data import (
    family_ranges,
    make_images,
    model_window,
    sample_specs,
)


@dataclass
class TrainResult:
    """A trained model and the mean training loss of each epoch."""

    model: EmbeddingModel
    epoch_losses: list[float]
    first_loss: float


def train_embedding(
    config: EmbeddingTrainConfig,
    *,
    on_epoch: Callable[[int, float], None] | None = None,
) -> TrainResult:
    """Train an autoencoder on fresh, seeded images of ``config.family``.

    Deterministic on CPU for a given config (seeded numpy Generator for the workpieces,
    ``torch.manual_seed`` for weights and batch order, a fixed thread count).
    ``on_epoch(epoch, mean_loss)`` is called after each epoch (a progress bar).
    """
    previous_threads = torch.get_num_threads()
    torch.set_num_threads(config.threads)
    try:
        return _train(config, on_epoch)
    finally:
        torch.set_num_threads(previous_threads)


def _train(
    config: EmbeddingTrainConfig, on_epoch: Callable[[int, float], None] | None
) -> TrainResult:
    rng = np.random.default_rng(config.seed)
    window = model_window(config.family, config.model)
    ranges = family_ranges(config.family, config.model)
    architecture = Architecture()
    specs = sample_specs(config.family, config.workpieces, rng, ranges)
    targets = to_targets(make_images(specs, architecture.resolution, window), window.theta_cap)
    torch.manual_seed(config.seed)
    network = ToleranceAutoencoder(architecture)
    optimizer = torch.optim.Adam(network.parameters(), lr=config.learning_rate)
    steps_per_epoch = math.ceil(len(targets) / config.batch_size)
    schedule = torch.optim.lr_scheduler.OneCycleLR(
        optimizer,
        max_lr=config.learning_rate,
        total_steps=steps_per_epoch * config.epochs,
        pct_start=0.1,
    )
    order = torch.Generator().manual_seed(config.seed)
    epoch_losses: list[float] = []
    first_loss = math.nan
    network.train()
    for epoch in range(config.epochs):
        losses = []
        for batch in torch.randperm(len(targets), generator=order).split(config.batch_size):
            loss = reconstruction_loss(network(targets[batch]), targets[batch], config.theta_weight)
            optimizer.zero_grad()
            loss.backward()
            optimizer.step()
            schedule.step()
            losses.append(loss.item())
            if math.isnan(first_loss):
                first_loss = losses[0]
        epoch_losses.append(float(np.mean(losses)))
        check_finite_training(
            "embedding training", epoch, epoch_losses[-1], network, config.learning_rate
        )
        if on_epoch is not None:
            on_epoch(epoch, epoch_losses[-1])
    network.eval()
    with torch.no_grad():  # weights finite but so large that the outputs are not
        probe = targets[: config.batch_size]
        loss = float(reconstruction_loss(network(probe), probe, config.theta_weight))
    check_finite_training(
        "embedding training", config.epochs - 1, loss, network, config.learning_rate
    )
    model = EmbeddingModel(
        family=config.family,
        network=network.eval(),
        window=window,
        ranges=ranges,
        config=dataclasses.asdict(config),
        seed=config.seed,
        tolins_version=tolins.__version__,
    )
    return TrainResult(model=model, epoch_losses=epoch_losses, first_loss=first_loss)
