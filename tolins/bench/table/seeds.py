"""The evaluation seeds of the bench: every row, robustness cell and ``tolins evaluate``
run draws its episodes from these, and no training run uses them."""

from __future__ import annotations

#: Evaluation seeds start here; seed index ``s`` of the training gets
#: ``FIRST_SEED + 1000 s, FIRST_SEED + 1000 s + 1, ...``.
FIRST_SEED = 10_000


def eval_seeds(seed_index: int, episodes: int) -> list[int]:
    """The ``episodes`` evaluation seeds of training seed ``seed_index``."""
    return [FIRST_SEED + 1000 * seed_index + i for i in range(episodes)]
