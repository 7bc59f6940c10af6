"""Behaviour cloning: regress the nominal policy on expert demonstrations.

Loss: ``mean ‖(π(ŝ) − a_e) / a_max‖²`` over (ŝ, a_e) pairs (actions normalised per axis).
The fit is reported on demonstration episodes held out of training (split by episode).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch

from tolins.learning.artefacts import RunRefused, check_finite_training, single_threaded_torch
from tolins.learning.imitation.config import BCConfig
from tolins.learning.imitation.demonstrations import pairs
from tolins.learning.imitation.policy import Policy, PolicyArchitecture
from tolins.paper import A_MAX
from tolins.rollouts.episodes import Episode


@dataclass(frozen=True)
class BCResult:
    """The cloned policy, its loss per epoch and the held-out fit."""

    policy: Policy
    losses: list[float]
    train_loss: float
    held_out_loss: float
    held_out_episodes: int


def action_loss(policy: Policy, observations: np.ndarray, actions: np.ndarray) -> float:
    """``mean ‖(π(ŝ) − a) / a_max‖²`` over the pairs."""
    with torch.no_grad():
        predicted = policy(torch.as_tensor(observations)).numpy()
    return float(np.mean(np.sum(((predicted - actions) / A_MAX) ** 2, axis=1)))


def behaviour_clone(
    demonstrations: list[Episode],
    config: BCConfig,
    *,
    seed: int,
    on_epoch: Callable[[int, float], None] | None = None,
) -> BCResult:
    """Train a nominal policy on ``demonstrations`` (weights, split and batches from ``seed``)."""
    with single_threaded_torch():
        return _clone(demonstrations, config, seed, on_epoch)


def _clone(demonstrations, config, seed, on_epoch) -> BCResult:
    rng = np.random.default_rng([seed, 0xBC])
    order = rng.permutation(len(demonstrations))
    held = max(1, round(config.held_out * len(demonstrations)))
    if held >= len(demonstrations):
        raise RunRefused(
            f"{len(demonstrations)} demonstrations leave none to train on (held_out="
            f"{config.held_out:g} keeps {held} aside); allowed: more demonstrations"
        )
    test = [demonstrations[i] for i in order[:held]]
    train = [demonstrations[i] for i in order[held:]]
    obs, act = pairs(train)
    policy = Policy(PolicyArchitecture("nominal", hidden=config.hidden), seed=seed)
    optimiser = torch.optim.Adam(policy.trainable(), lr=config.learning_rate)
    obs_t, target = torch.as_tensor(obs), torch.as_tensor(act / A_MAX)
    a_max = torch.as_tensor(A_MAX)
    generator = torch.Generator().manual_seed(seed)
    losses = []
    for epoch in range(config.epochs):
        total = 0.0
        for batch in torch.randperm(len(obs), generator=generator).split(config.batch_size):
            loss = ((policy(obs_t[batch]) / a_max - target[batch]) ** 2).sum(dim=1).mean()
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item() * len(batch)
        losses.append(total / len(obs))
        check_finite_training("behaviour cloning", epoch, losses[-1], policy, config.learning_rate)
        if on_epoch is not None:
            on_epoch(epoch, losses[-1])
    policy.eval()
    return BCResult(
        policy, losses, action_loss(policy, obs, act), action_loss(policy, *pairs(test)), held
    )
