"""The delicate-pins table in a bench's reports: its section of ``results.md`` (the table
itself: :mod:`tolins.bench.table.delicate`)."""

from __future__ import annotations

from typing import Any

from tolins.bench.table.delicate import CLAIM


def _figure(entry: dict[str, Any], name: str) -> str:
    low, high = entry[f"{name}_ci"]
    return f"{entry[f'{name}_mean']:.2f} [{low:.2f}, {high:.2f}]"


def _verdict(claim: dict[str, Any]) -> str:
    """A claim's verdict with its difference, e.g. ``inconclusive (−0.17 [−0.33, +0.00])``."""
    if "difference" not in claim:
        return claim["verdict"]
    d = claim["difference"]
    low, high = d["ci"]
    return f"{claim['verdict']} ({d['estimate']:+.2f} [{low:+.2f}, {high:+.2f}])"


def format_delicate_table(delicate: dict[str, Any]) -> str:
    """Per policy (rows) and workpiece (column groups): the success rate, the damage rate
    and the rate of successes without damage, each with its 95 % CI."""
    conditions = delicate["conditions"]
    header = "| policy | " + " | ".join(
        f"{c['label']}: success | damaged | success, undamaged" for c in conditions
    )
    lines = [header + " |", "|---|" + "---|---|---|" * len(conditions)]
    for policy in delicate["policies"]:
        cells = delicate["cells"][policy["id"]]
        texts = [
            _figure(cells[c["id"]], name)
            for c in conditions
            for name in ("success", "damage", "success_undamaged")
        ]
        lines.append(f"| {policy['label']} | " + " | ".join(texts) + " |")
    return "\n".join(lines)


def format_delicate_section(delicate: dict[str, Any] | None) -> list[str]:
    """``results.md``'s lines of the delicate-pins table, its claim and its gentlest
    learned policy (none without the table)."""
    if delicate is None:
        return []
    seeds, count = delicate["seeds"], delicate["episodes_per_seed"]
    over = f"the {seeds} training seeds" if seeds > 1 else "the episodes of the one seed"
    ids = ", ".join(
        f"`{c['env_id']}`" + (f" with `pins={c['pins']!r}`" if c.get("pins") else "")
        for c in delicate["conditions"]
    )
    note = (
        f"The 2*2 circle's policies, trained on rigid pins, on workpieces with pins that "
        f"bend and stay bent ({ids}: phosphor bronze, damaged beyond half the radial "
        f"clearance; docs/delicate.md), {count} episode{'s' if count > 1 else ''} per cell "
        f"and training seed (the rows' evaluation seeds); rates [95 % CI over {over}]. "
        "Success is the paper's (every pin in its hole, bent ones included). On the bent-pin "
        "2*1 of rows C4, π_φ* re-plans after each blocked attempt, each attempt meeting the "
        "part as the last one left it."
    )
    claim = delicate["claim"]
    lines = [
        "",
        "## Delicate pins (beyond the paper)",
        "",
        note,
        "",
        format_delicate_table(delicate),
    ]
    lines += ["", f"**Claim**: {CLAIM}: **{claim['verdict']}**"]
    if "difference" in claim:
        d = claim["difference"]
        low, high = d["ci"]
        lines[-1] += (
            f" (efficient − safe damage rate {d['estimate']:+.2f} [{low:+.2f}, {high:+.2f}] "
            f"over {d['n']} {d['over']}; no practical difference within ±{claim['delta']:g})."
        )
    by_condition = delicate.get("claim_by_condition")
    if by_condition:
        labels = {c["id"]: c["label"] for c in delicate["conditions"]}
        lines += [
            "",
            "The same claim on each workpiece: "
            + "; ".join(f"{labels[c]}: {_verdict(v)}" for c, v in by_condition.items())
            + ".",
        ]
    gentle = delicate.get("gentlest")
    if gentle is not None:
        lines += [
            "",
            f"Gentlest learned policy: {gentle['label']} (damage rate "
            f"{gentle['damage_mean']:.2f}, success without damage "
            f"{gentle['success_undamaged_mean']:.2f}, means over the columns).",
        ]
    return lines
