"""The study's table, plot and atomically written JSON."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tolins.atomic import atomic_json, atomic_write
from tolins.inference.study import PAPER, StudyResult


def _rows(summary: dict) -> list[tuple[str, float, float, float, str]]:
    """Per method of ``summary`` (:meth:`StudyResult.to_json`): inserted within 10, the
    same as a share of the insertable workpieces, mean attempts, the paper's figures."""
    insertable = 1.0 - summary["impossible"]
    rows = []
    for method, figures in summary["methods"].items():
        paper = PAPER.get(method)
        cite = f"{paper[0]:.1%} at {paper[1]:.3f}" if paper else ""
        within = figures["success_within_10"]
        rows.append((method, within, within / insertable, figures["mean_attempts"], cite))
    return rows


def format_table(result: StudyResult) -> str:
    """Methods beside the paper's figures, success also as a share of insertable ones."""
    lines = [
        f"{result.config.samples} workpieces: {result.nominal_insertable:.1%} insert at the "
        f"nominal goal, {result.impossible:.1%} nowhere",
        f"{'method':<18} {'within 10':>9} {'of insertable':>13} {'mean attempts':>13}   paper",
    ]
    summary = result.to_json()
    for method, within, share, attempts, cite in _rows(summary):
        lines.append(f"{method:<18} {within:>9.1%} {share:>13.1%} {attempts:>13.3f}   {cite}")
    if "pins" in summary:
        pins = summary["pins"]
        lines += ["", f"{pins['model']} pins ({pins['material']}): parts left damaged"]
        for method, figures in summary["methods"].items():
            lines.append(
                f"{method:<18} damaged {figures['damaged']:.1%}, inserted undamaged "
                f"{figures['success_undamaged']:.1%}"
            )
    if summary.get("kinds"):
        lines += ["", "per defect kind (method: within 10, mean attempts, not insertable)"]
        for kind, figures in summary["kinds"].items():
            lines.append(
                f"{kind} ({figures['workpieces']} workpieces, {figures['impossible']:.1%} "
                "nowhere): "
                + ", ".join(
                    f"{m} {f['success_within_10']:.0%} {f['mean_attempts']:.2f} "
                    f"{f['not_insertable']:.0%}"
                    for m, f in figures["methods"].items()
                )
            )
    return "\n".join(lines)


def format_kinds_markdown(summary: dict) -> str:
    """The per-kind part of the study's JSON (``summary["kinds"]``) as a Markdown table;
    empty for a result without it (an earlier run's)."""
    kinds = summary.get("kinds")
    if not kinds:
        return ""
    lines = [
        "Per defect kind (pitch, burr, blocked: bent workpieces with that defect too, the "
        "inference with the defect model; not insertable: the inference stopped and said so):",
        "",
        "| kind | workpieces | insertable nowhere | method | inserted within 10 attempts "
        "| mean attempts | reported not insertable |",
        "|---|---|---|---|---|---|---|",
    ]
    for kind, figures in kinds.items():
        for method, f in figures["methods"].items():
            lines.append(
                f"| {kind} | {figures['workpieces']} | {figures['impossible']:.1%} | {method} "
                f"| {f['success_within_10']:.1%} | {f['mean_attempts']:.3f} "
                f"| {f['not_insertable']:.1%} |"
            )
    return "\n".join(lines)


def format_markdown(summary: dict) -> str:
    """The study's JSON (:meth:`StudyResult.to_json`) as a Markdown table beside the paper."""
    lines = [
        f"Realised: {summary['nominal_insertable']:.1%} insert at the nominal goal, "
        f"{summary['impossible']:.1%} nowhere.",
        "",
        "| method | inserted within 10 attempts | of the insertable | mean attempts | paper |",
        "|---|---|---|---|---|",
    ]
    for method, within, share, attempts, cite in _rows(summary):
        lines.append(f"| {method} | {within:.1%} | {share:.1%} | {attempts:.3f} | {cite or '—'} |")
    kinds = format_kinds_markdown(summary)
    if kinds:
        lines += ["", kinds]
    return "\n".join(lines)


def write_json(result: StudyResult, path: str | Path) -> Path:
    """Write :meth:`StudyResult.to_json` atomically (temporary file, then rename)."""
    return atomic_json(path, result.to_json())


def save_plot(result: StudyResult, path: str | Path) -> Path:
    """Cumulative fraction inserted against attempts per method, with the paper's points."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k = np.arange(1, result.config.max_attempts + 1)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for method in result.config.methods:
        a = result.attempts[method]
        line = ax.plot(k, [(a[a > 0] <= j).sum() / len(a) for j in k], marker=".", label=method)
        if method in PAPER:
            ax.scatter(
                [PAPER[method][1]], [PAPER[method][0]], marker="x", s=60, color=line[0].get_color()
            )
    ax.axhline(1 - result.impossible, color="grey", ls=":", label="insertable")
    ax.set_xlabel("attempts")
    ax.set_ylabel("fraction inserted")
    ax.set_title("2*1 bent pins: inserted within k attempts (x: paper, success at mean attempts)")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    try:
        return atomic_write(path, lambda file: fig.savefig(file, format="png", dpi=120))
    finally:
        plt.close(fig)
