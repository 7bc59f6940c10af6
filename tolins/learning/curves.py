"""Learning curves of a training run: CSV after every iteration, PNG at the end."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from tolins.atomic import atomic_write


def write_curves_csv(path: str | Path, history: list[dict[str, float]]) -> Path:
    """One row per iteration, the keys of the first row as the header (atomic write)."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(history[0]))
    writer.writeheader()
    writer.writerows(history)
    return atomic_write(path, lambda file: file.write(buffer.getvalue()), mode="w")


def plot_curves(path: str | Path, history: list[dict[str, float]], title: str = "") -> Path:
    """Env reward, success rate and D's expert probability of the student against iteration."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = [row["iteration"] for row in history]
    panels = (
        ("reward", "env reward (mean policy)"),
        ("success", "success rate"),
        ("d_expert", "D(student) expert prob."),
    )
    figure, axes = plt.subplots(1, 3, figsize=(12, 3.2), constrained_layout=True)
    for axis, (key, label) in zip(axes, panels, strict=True):
        axis.plot(x, [row[key] for row in history], marker=".")
        axis.set_xlabel("iteration")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    axes[2].axhspan(0.4, 0.6, color="tab:green", alpha=0.15)
    figure.suptitle(title)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=100)
    plt.close(figure)
    return atomic_write(path, lambda file: file.write(buffer.getvalue()))
