"""The force-aware figures of rows (``results.json`` schema /2) as a Markdown table.

The figures are defined in :mod:`tolins.rollouts.forces`; an entry of schema /1 (or of
episodes recorded without force scores) has none, and is left out of the table.
"""

from __future__ import annotations

from typing import Any

from tolins.envs.tasks import env_label

#: (figure, column heading) of the table, in order.
FORCE_COLUMNS = (
    ("peak_force", "peak force (N)"),
    ("contact_force", "force in contact (N)"),
    ("impulse", "impulse (N·s)"),
    ("jams", "jams"),
    ("cycle_time", "cycle time (s)"),
)

#: What the table's columns mean, for the reports beside it.
FORCE_NOTE = (
    "Per episode, then mean ± std as in Table 1: the largest summed normal force between "
    "the pins and the board; its mean over the steps in contact (> 0.01 N); Σ peak · dt "
    "over those steps; jams (4 consecutive steps above the collision force with the pins "
    "less than 0.01 mm deeper); steps · dt. Definitions: `tolins.rollouts.forces`. The "
    "kinematic backend reports 1 N on a colliding step and 0 otherwise."
)


def has_forces(entry: dict[str, Any]) -> bool:
    """Whether ``entry`` carries every force figure."""
    return all(f"{name}_mean" in entry for name, _ in FORCE_COLUMNS)


def format_force_table(rows: dict[str, dict[str, Any]]) -> str:
    """The rows that carry force figures as a Markdown table (``""`` when none does)."""
    shown = {row_id: entry for row_id, entry in rows.items() if has_forces(entry)}
    if not shown:
        return ""
    lines = [
        "| ID | policy | eval env | " + " | ".join(head for _, head in FORCE_COLUMNS) + " |",
        "|---|---|---|" + "---|" * len(FORCE_COLUMNS),
    ]
    for row_id, entry in shown.items():
        cells = [row_id, entry["policy"], env_label(entry["eval_env"])]
        for name, _ in FORCE_COLUMNS:
            cells.append(f"{entry[f'{name}_mean']:.2f} ± {entry[f'{name}_std']:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)
