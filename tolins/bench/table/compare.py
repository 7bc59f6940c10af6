"""``tolins compare A B``: two results side by side per row, with the interval of the
difference, so that "did my run reproduce the reference?" has an answer.

A and B are results folders, ``results.json`` files or shipped references
(``reference:NAME``, :mod:`tolins.bench.reference`). For every row in both, the
difference of mean reward A − B gets a 95 % bootstrap CI (:mod:`tolins.bench.table.statistics`):
over **training seeds** when both runs have ≥ 2 (their per-seed means resampled
independently: two runs share no training), else over the **episodes** of each (all
seeds' episodes pooled), which leaves training variance out, and so, as for the claims,
such a difference decides only beyond :func:`~tolins.bench.table.statistics.margin`
(:data:`~tolins.bench.table.statistics.ONE_SEED_MARGIN` for a trained row, 0 for an expert row,
whose runs differ by evaluation alone).

A row *differs* when its CI lies beyond that margin (A higher or B higher) and is
*consistent* otherwise: no difference was detected at that resolution, which is what a
reproduction can show. A row is *not comparable* when its eval env differs between A and
B (its workpiece: the ``-v1`` and ``-v2`` ids of one preset compare), its policy does (the
R1 rows of schemas /1 and /2 learnt from the dense reward, today's from the sparse one:
"PPO" against "PPO (sparse)"), or the runs' backend
or profile do (a field a run does not state, such as the profile
of ``tolins evaluate --out``, is not held against it): its interval is still given.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from tolins.bench.reference import PREFIX, reference_path
from tolins.bench.table.results import read_results
from tolins.bench.table.rows import ROW_IDS, ROWS
from tolins.bench.table.statistics import (
    EPISODES,
    SEEDS,
    Interval,
    difference,
    margin,
    sign,
    unit_samples,
)
from tolins.envs.tasks import env_label

CONSISTENT, A_HIGHER, B_HIGHER = "consistent", "differs: A higher", "differs: B higher"
NOT_COMPARABLE = "not comparable"
#: Rows of a scripted expert: nothing trained, no training variance.
_EXPERTS = frozenset(row.id for row in ROWS if not row.trainings)


@dataclass(frozen=True)
class RowDifference:
    """One row in both runs: its entries and the interval of reward A − B."""

    row: str
    a: dict[str, Any]
    b: dict[str, Any]
    difference: Interval
    margin: float
    not_comparable: str | None = None
    """What differs between the two runs of the row (eval env, backend, profile), if any."""

    @property
    def status(self) -> str:
        """:data:`CONSISTENT`, :data:`A_HIGHER`, :data:`B_HIGHER` or, when the runs differ
        in what they measured, :data:`NOT_COMPARABLE` (``... (why)``)."""
        if self.not_comparable:
            return f"{NOT_COMPARABLE} ({self.not_comparable})"
        return {0: CONSISTENT, 1: A_HIGHER, -1: B_HIGHER}[sign(self.difference, self.margin)]


@dataclass(frozen=True)
class Comparison:
    """Two runs compared: each one's label and document, the rows in both, the others."""

    label_a: str
    label_b: str
    document_a: dict[str, Any]
    document_b: dict[str, Any]
    rows: tuple[RowDifference, ...]
    only_a: tuple[str, ...]
    only_b: tuple[str, ...]


def load_results(source: str) -> dict[str, Any]:
    """The ``results.json`` document of ``source``: a results folder, a ``results.json``
    file or ``reference:NAME``. Raises ``ValueError`` (one line) when it is missing or
    not a results document."""
    path = reference_path(source.removeprefix(PREFIX)) if source.startswith(PREFIX) else source
    document = read_results(path)
    if not document["rows"]:
        raise ValueError(f"{source}: no rows; allowed: a results.json with ≥ 1 row")
    return document


def compare(source_a: str, source_b: str) -> Comparison:
    """Load both sources and compare every row they share (table order, then the rest)."""
    a, b = load_results(source_a), load_results(source_b)
    rows_a, rows_b = a["rows"], b["rows"]
    shared = [r for r in rows_a if r in rows_b]
    order = {row_id: i for i, row_id in enumerate(ROW_IDS)}
    shared.sort(key=lambda r: order.get(r, len(order)))
    if not shared:
        raise ValueError(
            f"{source_a} and {source_b} share no row; rows of A: {', '.join(rows_a)}; "
            f"of B: {', '.join(rows_b)}"
        )
    rows = []
    for row_id in shared:
        try:
            row = _row_difference(row_id, rows_a[row_id], rows_b[row_id])
        except ValueError as error:
            raise ValueError(f"row {row_id}: {error}") from None
        why = _not_comparable(a, b, rows_a[row_id], rows_b[row_id])
        rows.append(dataclasses.replace(row, not_comparable=why) if why else row)
    return Comparison(
        source_a,
        source_b,
        a,
        b,
        tuple(rows),
        tuple(r for r in rows_a if r not in rows_b),
        tuple(r for r in rows_b if r not in rows_a),
    )


def _row_difference(row_id: str, a: dict[str, Any], b: dict[str, Any]) -> RowDifference:
    (x, over_x), (y, over_y) = unit_samples(a), unit_samples(b)
    if over_x != SEEDS or over_y != SEEDS:
        x, y = _episodes(a), _episodes(b)
    over = SEEDS if over_x == over_y == SEEDS else EPISODES
    interval = difference(x, y, over)
    trained = 0 if row_id in _EXPERTS else 2  # a row unknown to the table counts as trained
    return RowDifference(row_id, a, b, interval, margin(interval, trained))


def _not_comparable(
    a: dict[str, Any], b: dict[str, Any], row_a: dict[str, Any], row_b: dict[str, Any]
) -> str | None:
    """What differs between two runs of one row (``None`` stated on a side: not held)."""
    # The physics versions of one workpiece give the same outcomes (tolins.physics.versions):
    # a -v2 row compares with its -v1 row.
    envs = [
        env if env is None else env_label(str(env))
        for env in (row_a.get("eval_env"), row_b.get("eval_env"))
    ]
    pairs = [("eval env", *envs), ("policy", row_a.get("policy"), row_b.get("policy"))]
    pairs += [(key, a.get(key), b.get(key)) for key in ("backend", "profile")]
    differ = [f"{key} {x} vs {y}" for key, x, y in pairs if None not in (x, y) and x != y]
    return ", ".join(differ) or None


def _episodes(entry: dict[str, Any]) -> list[float]:
    episodes = [r for seed in entry.get("reward_per_episode") or [] for r in seed]
    if not episodes:
        raise ValueError("no reward_per_episode; allowed: a results.json of tolins ≥ 0.3")
    return episodes


def _describe(label: str, document: dict[str, Any]) -> str:
    rows = document["rows"]
    seeds = sorted({int(e.get("seeds", 0)) for e in rows.values()})
    episodes = sorted(
        {int(e.get("episodes", 0)) // max(int(e.get("seeds", 1)), 1) for e in rows.values()}
    )
    facts = [
        f"{document.get('backend') or 'unknown'} backend",
        f"{document.get('profile') or 'no'} profile",
        f"{'/'.join(map(str, seeds))} training seed(s)",
        f"{'/'.join(map(str, episodes))} episodes per seed",
        f"tolins {document.get('tolins_version') or '?'}",
        str(document.get("date") or "undated"),
    ]
    return f"{label} ({', '.join(facts)})"


def format_comparison(result: Comparison) -> str:
    """The comparison as Markdown: what A and B are, one line per shared row (reward of
    each, A − B [95 % CI], what the CI is over, the status; success of each), a summary."""
    lines = [
        f"A: {_describe(result.label_a, result.document_a)}",
        f"B: {_describe(result.label_b, result.document_b)}",
        "",
        "| ID | policy | eval env | reward A | reward B | A − B [95 % CI] | over | status "
        "| success A | success B |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in result.rows:
        a, b, d = row.a, row.b, row.difference
        over = f"{d.n} {d.over}" + (f", margin ±{row.margin:.1f}" if row.margin else "")
        cells = [
            row.row,
            str(a.get("policy", "")),
            env_label(str(a.get("eval_env", ""))),
            f"{a['reward_mean']:.2f}",
            f"{b['reward_mean']:.2f}",
            d.format(signed=True),
            over,
            row.status,
            f"{a['success_mean']:.2f}",
            f"{b['success_mean']:.2f}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    consistent = sum(r.status == CONSISTENT for r in result.rows)
    lines += ["", f"{consistent} of {len(result.rows)} shared rows consistent."]
    apart = sum(r.not_comparable is not None for r in result.rows)
    if apart:
        lines.append(f"{apart} not comparable: their runs measured something else (status).")
    if any(r.difference.over == EPISODES for r in result.rows):
        lines.append(
            "Over episodes: a run has one training seed, so the CI leaves training variance "
            "out; a trained row differs only beyond the margin (docs/benchmark.md)."
        )
    for label, missing in (("A", result.only_a), ("B", result.only_b)):
        if missing:
            lines.append(f"Only in {label}: {', '.join(missing)}.")
    return "\n".join(lines)


def comparison_json(result: Comparison) -> dict[str, Any]:
    """The comparison as JSON: the two sources, each shared row's means, interval, margin
    and status, the rows only one has."""
    return {
        "a": result.label_a,
        "b": result.label_b,
        "rows": {
            row.row: {
                "reward_a": row.a["reward_mean"],
                "reward_b": row.b["reward_mean"],
                "difference": row.difference.to_json(),
                "margin": row.margin,
                "status": row.status,
                "not_comparable": row.not_comparable,
            }
            for row in result.rows
        },
        "only_a": list(result.only_a),
        "only_b": list(result.only_b),
    }
