"""The study's table, plot and atomically written JSON."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tolins.atomic import atomic_json, atomic_write
from tolins.inference.study import PAPER, StudyResult


def format_table(result: StudyResult) -> str:
    """Methods beside the paper's figures, success also as a share of insertable ones."""
    insertable = 1.0 - result.impossible
    lines = [
        f"{result.config.samples} workpieces: {result.nominal_insertable:.1%} insert at the "
        f"nominal goal, {result.impossible:.1%} nowhere",
        f"{'method':<18} {'within 10':>9} {'of insertable':>13} {'mean attempts':>13}   paper",
    ]
    for method in result.config.methods:
        s = result.summary(method)
        paper = PAPER.get(method)
        cite = f"{paper[0]:.1%} at {paper[1]:.3f}" if paper else ""
        lines.append(
            f"{method:<18} {s['success_within_10']:>9.1%} "
            f"{s['success_within_10'] / insertable:>13.1%} {s['mean_attempts']:>13.3f}   {cite}"
        )
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
