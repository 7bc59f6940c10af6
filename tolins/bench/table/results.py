"""Table 1's figures of a row from its episodes (``results.json``'s entries), and the
versioned ``results.json`` document (:data:`SCHEMA`) that holds them."""

from __future__ import annotations

import datetime
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from tolins.bench.table.rows import Row
from tolins.bench.table.seeds import FIRST_SEED
from tolins.bench.table.statistics import mean_intervals, row_intervals
from tolins.json_input import read_json_file, shorten
from tolins.rollouts.episodes import Episode
from tolins.rollouts.forces import FORCE_FIGURES

FIGURES = ("reward", "success", "steps", "collisions")
#: The version of ``results.json``'s layout, its ``schema`` field (/2: the force figures;
#: /3: four-valued claims with their smallest effect of interest, seeds to decide and
#: head-room, and the deep-RL rows R1 on the sparse reward, R2 on the dense one).
SCHEMA = "tolins.results/3"
#: The schemas :func:`read_results` reads (/1 has no force figures; in /1 and /2 the rows
#: R1.x learnt from the dense reward).
READABLE = ("tolins.results/1", "tolins.results/2", SCHEMA)
#: The values a figure of one episode can take (and so its means, CIs and per-seed
#: values): a success is 0 or 1, steps, collisions and the force figures are counts or
#: magnitudes, a reward may be negative.
RANGES: dict[str, tuple[float, float]] = {
    "reward": (-math.inf, math.inf),
    "success": (0.0, 1.0),
    "steps": (0.0, math.inf),
    "collisions": (0.0, math.inf),
    **dict.fromkeys(FORCE_FIGURES, (0.0, math.inf)),
}


def row_entry(row: Row, per_seed: list[list[Episode]]) -> dict[str, Any]:
    """The ``results.json`` entry of ``row`` from its episodes, one list per training seed.

    ``*_mean`` is over every episode. ``*_std`` follows the paper (± over runs): the std
    of the per-seed means when there are several seeds, else the std over episodes
    (``std_over`` says which). ``*_per_seed`` are the per-seed means,
    ``reward_per_episode`` every episode's reward (one list per seed), and the interval
    keys of :func:`tolins.bench.table.statistics.row_intervals` (``*_ci``, ``reward_iqm``...).
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
    for name in FIGURES:
        entry[f"{name}_per_seed"] = [float(np.mean(v)) for v in values[name]]
    entry["reward_per_episode"] = [[float(r) for r in seed] for seed in values["reward"]]
    entry.update(row_intervals(values))
    entry.update(force_figures(per_seed))
    entry.update(damage_figures(per_seed))
    return entry


#: The figures of episodes whose pins bend (docs/delicate.md).
DAMAGE_FIGURES = ("damage", "success_undamaged")


def damage_figures(per_seed: list[list[Episode]]) -> dict[str, Any]:
    """Where every episode's pins could bend (``Episode.damaged``): the share of episodes
    that damaged the part (``damage``) and that succeeded without damaging it
    (``success_undamaged``), each with its ``_mean``, ``_std`` and ``_per_seed`` (as
    :func:`row_entry`'s) and ``_ci``; empty otherwise (rigid pins)."""
    if any(e.damaged is None for seed in per_seed for e in seed):
        return {}
    values = {
        "damage": [[float(e.damaged) for e in seed] for seed in per_seed],
        "success_undamaged": [
            [float(e.success and not e.damaged) for e in seed] for seed in per_seed
        ],
    }
    over_seeds = len(per_seed) > 1
    entry: dict[str, Any] = {}
    for name in DAMAGE_FIGURES:
        flat = np.concatenate([np.asarray(v) for v in values[name]])
        spread = [np.mean(v) for v in values[name]] if over_seeds else flat
        entry[f"{name}_mean"] = float(flat.mean())
        entry[f"{name}_std"] = float(np.std(spread))
        entry[f"{name}_per_seed"] = [float(np.mean(v)) for v in values[name]]
        entry[f"{name}_per_episode"] = values[name]
    entry.update(mean_intervals(values))
    return entry


def force_figures(per_seed: list[list[Episode]]) -> dict[str, Any]:
    """The force-aware figures of a row (:mod:`tolins.rollouts.forces`): for each of
    ``peak_force``, ``contact_force``, ``impulse``, ``jams``, ``cycle_time`` its ``_mean``
    and ``_std`` (as :func:`row_entry`'s), ``_per_seed`` and ``_per_episode``; empty when
    an episode has no force scores (one recorded before they were kept)."""
    if any(e.forces is None for seed in per_seed for e in seed):
        return {}
    over_seeds = len(per_seed) > 1
    entry: dict[str, Any] = {}
    for name in FORCE_FIGURES:
        values = [[float(getattr(e.forces, name)) for e in seed] for seed in per_seed]
        flat = np.concatenate([np.asarray(v) for v in values])
        spread = [np.mean(v) for v in values] if over_seeds else flat
        entry[f"{name}_mean"] = float(flat.mean())
        entry[f"{name}_std"] = float(np.std(spread))
        entry[f"{name}_per_seed"] = [float(np.mean(v)) for v in values]
        entry[f"{name}_per_episode"] = values
    return entry


def results_document(
    rows: dict[str, dict[str, Any]], *, source: str, backend: str, profile: str | None
) -> dict[str, Any]:
    """The ``results.json`` of ``rows`` (entries of :func:`row_entry`) in the schema
    :data:`SCHEMA` (every field: docs/benchmark.md)."""
    import tolins

    return {
        "schema": SCHEMA,
        "source": source,
        "tolins_version": tolins.__version__,
        "date": datetime.date.today().isoformat(),
        "backend": backend,
        "profile": profile,
        "first_eval_seed": FIRST_SEED,
        "rows": rows,
    }


def read_results(path: str | os.PathLike) -> dict[str, Any]:
    """The ``results.json`` document at ``path`` (a file, or a folder holding one).

    A file without a schema (row entries at the top, no ``schema``) is read as the rows of
    a document whose other fields are ``None``. Raises ``ValueError`` for anything else.
    """
    path = _results_file(Path(path))
    document = read_json_file(path, "a results.json of tolins bench or tolins evaluate")
    if not isinstance(document, dict):
        raise ValueError(f"{path}: not a results document; allowed: schema {READABLE[-1]!r}")
    if "schema" not in document and all(
        isinstance(v, dict) and "reward_mean" in v for v in document.values()
    ):
        fields = ("source", "tolins_version", "date", "backend", "profile", "first_eval_seed")
        return {"schema": None, **dict.fromkeys(fields), "rows": document}
    if document.get("schema") not in READABLE:
        allowed = " or ".join(repr(s) for s in READABLE)
        raise ValueError(f"{path}: schema {document.get('schema')!r}; allowed: {allowed}")
    if not isinstance(document.get("rows"), dict):
        found = "no" if "rows" not in document else type(document["rows"]).__name__
        raise ValueError(f"{path}: {found} 'rows'; allowed: an object of row id -> row entry")
    for row_id, entry in document["rows"].items():
        problem = entry_problem(entry)
        if problem:
            raise ValueError(f"{path}: row {row_id}: {problem}")
    return document


def _results_file(path: Path) -> Path:
    """``path``, or the ``results.json`` in it when it is a folder; ``ValueError`` when
    there is no such file (naming a path the system refuses, e.g. too long, shortened)."""
    try:
        file = path / "results.json" if path.is_dir() else path
        found, shown = file.is_file(), str(file)
    except OSError:
        found, shown = False, shorten(path)
    if not found:
        raise ValueError(f"{shown}: no such file; allowed: a results.json or its folder")
    return file


def entry_problem(entry: Any) -> str | None:
    """What is wrong with a ``results.json`` row entry (``None``: nothing found): its
    means and counts are finite numbers, its per-seed and per-episode figures lists of
    them (one per seed), every figure's values possible ones (:data:`RANGES`: a success
    rate in [0, 1], no negative count, a std at most half the range, a CI in order), and
    ``reward_mean`` the mean of its per-episode (or per-seed) rewards."""
    if not isinstance(entry, dict):
        return f"a {type(entry).__name__}; allowed: an object of figures"
    for key in ("reward_mean", "success_mean"):
        if key not in entry:
            return f"no {key}; allowed: a row entry of tolins bench or evaluate"
        if not _finite(entry[key]):
            return f"{key} {entry[key]!r}; allowed: a finite number"
    for key in ("seeds", "episodes"):
        value = entry.get(key, 1)
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            return f"{key} {value!r}; allowed: an integer ≥ 1"
    for figure in FIGURES:
        values = entry.get(f"{figure}_per_seed")
        if values is None:
            continue
        if not isinstance(values, list) or not all(_finite(v) for v in values):
            return f"{figure}_per_seed {values!r}; allowed: a list of finite numbers"
        if "seeds" in entry and len(values) != entry["seeds"]:
            return f"{figure}_per_seed has {len(values)} values; allowed: one per seed"
    episodes = entry.get("reward_per_episode")
    if episodes is not None and not (
        isinstance(episodes, list)
        and all(isinstance(seed, list) and all(_finite(r) for r in seed) for seed in episodes)
    ):
        return "reward_per_episode is not a list of lists of finite numbers (one per seed)"
    problem = _count_problem(entry) or _range_problem(entry)
    if problem:
        return problem
    per_seed = entry.get("reward_per_seed")
    if episodes and per_seed is not None:
        means = [float(np.mean(seed)) if seed else None for seed in episodes]
        if len(means) != len(per_seed) or not all(
            m is not None and np.isclose(m, v, rtol=1e-9, atol=1e-9)
            for m, v in zip(means, per_seed, strict=False)
        ):
            return (
                f"reward_per_seed {per_seed!r} are not the means of its reward_per_episode; "
                "allowed: the file as tolins wrote it"
            )
    flat = [r for seed in episodes or [] for r in seed] or per_seed or []
    if flat and not np.isclose(float(np.mean(flat)), entry["reward_mean"], rtol=1e-9, atol=1e-9):
        source = "reward_per_episode" if episodes else "reward_per_seed"
        return (
            f"reward_mean {entry['reward_mean']!r} is not the mean of its {source} "
            f"({float(np.mean(flat))!r}); allowed: the file as tolins wrote it"
        )
    return None


def _finite(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and np.isfinite(value)


def _count_problem(entry: dict[str, Any]) -> str | None:
    """What is wrong with an entry's counts: a seed has ≥ 1 episode, faults are episodes."""
    seeds, episodes = entry.get("seeds", 1), entry.get("episodes")
    if episodes is not None and seeds > episodes:
        return f"seeds {seeds} > episodes {episodes}; allowed: ≥ 1 episode per seed"
    faults = entry.get("faults")
    if faults is None:
        return None
    if not isinstance(faults, int) or isinstance(faults, bool) or faults < 0:
        return f"faults {faults!r}; allowed: an integer ≥ 0"
    if episodes is not None and faults > episodes:
        return f"faults {faults} > episodes {episodes}; allowed: at most one per episode"
    return None


def _range_text(low: float, high: float) -> str:
    """``low … high`` in words, as an error message's "allowed"."""
    if math.isinf(high):
        return "a finite number" if math.isinf(low) else f"a finite number ≥ {low:g}"
    return f"a number {low:g} … {high:g}"


def _range_problem(entry: dict[str, Any]) -> str | None:
    """The first of an entry's figures (means, stds, per-seed and per-episode values,
    CIs) outside what one episode's figure can come to (:data:`RANGES`)."""
    for figure, (low, high) in RANGES.items():
        allowed = _range_text(low, high)

        def inside(value: Any, low: float = low, high: float = high) -> bool:
            return _finite(value) and low <= value <= high

        mean = entry.get(f"{figure}_mean")
        if mean is not None and not inside(mean):
            return f"{figure}_mean {mean!r}; allowed: {allowed}"
        std, most = entry.get(f"{figure}_std"), (high - low) / 2
        if std is not None and not inside(std, 0.0, most + 1e-12):  # 1e-12: float rounding
            return f"{figure}_std {std!r}; allowed: {_range_text(0.0, most)}"
        per_seed = entry.get(f"{figure}_per_seed")
        if isinstance(per_seed, list) and not all(inside(v) for v in per_seed):
            return f"{figure}_per_seed {per_seed!r}; allowed: a list of {allowed} each"
        per_episode = entry.get(f"{figure}_per_episode")
        if per_episode is not None and not (
            isinstance(per_episode, list)
            and all(isinstance(seed, list) and all(inside(v) for v in seed) for seed in per_episode)
        ):
            return f"{figure}_per_episode: allowed: a list (one per seed) of lists of {allowed}"
        for key in (f"{figure}_ci", f"{figure}_iqm_ci"):
            ci = entry.get(key)
            if ci is not None and not (
                isinstance(ci, list) and len(ci) == 2 and all(map(inside, ci)) and ci[0] <= ci[1]
            ):
                return f"{key} {ci!r}; allowed: [low, high] of {allowed} each, low ≤ high"
    return None


def standard_error(entry: dict[str, Any], figure: str = "reward") -> float:
    """Standard error of ``entry``'s mean ``figure`` (std over seeds or over episodes)."""
    count = entry["seeds"] if entry.get("std_over") == "seeds" else entry["episodes"]
    return float(entry[f"{figure}_std"]) / np.sqrt(max(int(count), 1))
