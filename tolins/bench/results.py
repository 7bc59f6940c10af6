"""Table 1's figures of a row from its episodes (``results.json``'s entries)."""

from __future__ import annotations

from typing import Any

import numpy as np

from tolins.bench.table import Row
from tolins.rollout import Episode

FIGURES = ("reward", "success", "steps", "collisions")


def row_entry(row: Row, per_seed: list[list[Episode]]) -> dict[str, Any]:
    """The ``results.json`` entry of ``row`` from its episodes, one list per training seed.

    ``*_mean`` is over every episode. ``*_std`` follows the paper (± over runs): the std
    of the per-seed means when there are several seeds, else the std over episodes
    (``std_over`` says which).
    """
    if not per_seed or not all(per_seed):
        raise ValueError(f"row {row.id}: no episodes; allowed: ≥ 1 episode per seed")
    values = {
        "reward": [[e.reward for e in seed] for seed in per_seed],
        "success": [[float(e.success) for e in seed] for seed in per_seed],
        "steps": [[float(e.steps) for e in seed] for seed in per_seed],
        "collisions": [[float(e.collisions) for e in seed] for seed in per_seed],
    }
    over_seeds = len(per_seed) > 1
    entry: dict[str, Any] = {
        "policy": row.policy,
        "train_env": row.train_env,
        "eval_env": row.eval_env,
    }
    for name in FIGURES:
        flat = np.concatenate([np.asarray(v, dtype=float) for v in values[name]])
        spread = [np.mean(v) for v in values[name]] if over_seeds else flat
        entry[f"{name}_mean"] = float(flat.mean())
        entry[f"{name}_std"] = float(np.std(spread))
    entry["episodes"] = int(sum(len(seed) for seed in per_seed))
    entry["seeds"] = len(per_seed)
    entry["std_over"] = "seeds" if over_seeds else "episodes"
    entry["faults"] = int(sum(e.error is not None for seed in per_seed for e in seed))
    return entry


def standard_error(entry: dict[str, Any], figure: str = "reward") -> float:
    """Standard error of ``entry``'s mean ``figure`` (std over seeds or over episodes)."""
    count = entry["seeds"] if entry.get("std_over") == "seeds" else entry["episodes"]
    return float(entry[f"{figure}_std"]) / np.sqrt(max(int(count), 1))
