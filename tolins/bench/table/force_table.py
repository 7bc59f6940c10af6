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


#: (figure, column heading) of the columns added where a row's pins could bend
#: (docs/delicate.md; :func:`~tolins.bench.table.results.damage_figures`).
DAMAGE_COLUMNS = (("damage", "damaged"), ("success_undamaged", "success, undamaged"))


def has_forces(entry: dict[str, Any]) -> bool:
    """Whether ``entry`` carries every force figure."""
    return all(f"{name}_mean" in entry for name, _ in FORCE_COLUMNS)


def format_force_table(rows: dict[str, dict[str, Any]]) -> str:
    """The rows that carry force figures as a Markdown table (``""`` when none does), with
    the damage rate and the rate of successes without damage where a row's pins could
    bend (``–`` for a row with rigid pins)."""
    shown = {row_id: entry for row_id, entry in rows.items() if has_forces(entry)}
    if not shown:
        return ""
    damage = any(f"{DAMAGE_COLUMNS[0][0]}_mean" in entry for entry in shown.values())
    columns = FORCE_COLUMNS + (DAMAGE_COLUMNS if damage else ())
    lines = [
        "| ID | policy | eval env | " + " | ".join(head for _, head in columns) + " |",
        "|---|---|---|" + "---|" * len(columns),
    ]
    for row_id, entry in shown.items():
        cells = [row_id, entry["policy"], env_label(entry["eval_env"])]
        for name, _ in columns:
            if f"{name}_mean" in entry:
                cells.append(f"{entry[f'{name}_mean']:.2f} ± {entry[f'{name}_std']:.2f}")
            else:
                cells.append("–")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)
