"""Reconstruction quality of the shipped embedding checkpoints, and the Fig. 3-like figure.

    python benchmarks/embedding_quality.py                 # 500 held-out workpieces a family
    python benchmarks/embedding_quality.py --count 50 --figure ''   # quick, no figure
    python benchmarks/embedding_quality.py --model graded --figure ''  # the graded model

Prints, per family, the mean region IoU (``image >= 0``) over held-out workpieces
(:func:`tolins.learning.embedding.evaluation.held_out_specs`), the worst IoU, and the θ error inside
the true region; then writes ground truth beside prediction for a few named workpieces.
With ``--model graded``: the graded checkpoints on held-out workpieces of the graded
ranges, then on each tolerance-grade preset (``GRADE_TASKS``) and each paper preset.
"""

from __future__ import annotations

import argparse
import time

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np

from tolins import CircularSocket, PolygonSocket, embedding, tolerance
from tolins.envs.tasks import GRADE_TASKS, TASKS
from tolins.learning.embedding.evaluation import held_out_specs, measure

#: Shown in the figure: the paper's Fig. 3 pair first (2*2, pins 0.3 / holes 0.5 mm,
#: 2.5 mm intervals; square peg 1.5 / 1.575 mm), then other shapes of each family.
FIGURE_SPECS = [
    ("2*2, 0.3/0.5 mm, 2.5 mm", CircularSocket(2, 2, 0.3, 0.5, 2.5, 2.5)),
    ("2*12, 0.27/0.55 mm", CircularSocket(2, 12, 0.27, 0.55, 7.62, 2.54)),
    ("square 1.5/1.575 mm", PolygonSocket(4, 1.5, 1.575)),
    ("triangle 1.4/1.58 mm", PolygonSocket(3, 1.4, 1.58)),
    ("hexagon 1.2/1.26 mm", PolygonSocket(6, 1.2, 1.26)),
]


def report(count: int, model: str = "paper") -> None:
    print(
        "| family | held-out workpieces | region IoU (mean) | worst IoU | θ error (rad) "
        "| θ error / image max |"
    )
    print("|---|---|---|---|---|---|")
    for family in ("circle", "polygon"):
        quality = measure(
            embedding.load_model(family, model), held_out_specs(family, count, model=model)
        )
        print(
            f"| {family} | {quality.count} | {quality.iou:.3f} | {quality.worst_iou:.3f} "
            f"| {quality.theta_error:.4f} | {quality.relative_theta_error:.1%} |"
        )


def presets(model: str) -> None:
    """Region IoU and θ error of each grade preset (then each paper preset) under ``model``."""
    print("\n| preset | clearance (µm) | region IoU | θ error (rad) |")
    print("|---|---|---|---|")
    ious: dict[str, list[float]] = {"grade": [], "paper": []}
    for group, tasks in (("grade", GRADE_TASKS), ("paper", TASKS)):
        for task in tasks:
            spec = task.socket
            if spec.is_defective:
                continue
            quality = measure(embedding.load_model(spec.family, model), [spec])
            ious[group].append(quality.iou)
            print(
                f"| {task.name} | {spec.clearance * 1e3:.0f} | {quality.iou:.3f} "
                f"| {quality.theta_error:.4f} |"
            )
    for group, values in ious.items():
        print(f"{group} presets: mean IoU {np.mean(values):.3f}, worst {np.min(values):.3f}")


def figure(path: str) -> None:
    fig, axes = plt.subplots(2, len(FIGURE_SPECS), figsize=(3.1 * len(FIGURE_SPECS), 6.2))
    for column, (title, spec) in enumerate(FIGURE_SPECS):
        window = tolerance.WINDOWS[spec.family]
        half = window.half_width
        truth, predicted = tolerance.image(spec), embedding.reconstruct(spec)
        top = max(float(truth.max()), 1e-6)
        for row, (name, values) in enumerate((("truth", truth), ("prediction", predicted))):
            ax = axes[row, column]
            shown = np.ma.masked_less(values, 0.0)
            picture = ax.imshow(
                shown,
                origin="lower",
                extent=(-half, half, -half, half),
                cmap="viridis",
                vmin=0.0,
                vmax=top,
            )
            ax.set_title(f"{title}\n{name}" if row == 0 else name, fontsize=9)
            ax.set_xlabel("x (mm)", fontsize=8)
            ax.set_ylabel("y (mm)", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.set_facecolor("#dddddd")
            bar = fig.colorbar(picture, ax=ax, shrink=0.8)
            bar.set_label("θ (rad)", fontsize=8)
            bar.ax.tick_params(labelsize=7)
    fig.suptitle(
        "Tolerance images (largest θ ≥ 0 per (x, y); grey: no tolerance) "
        "and their 5-d autoencoder reconstructions",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=500, help="held-out workpieces a family")
    parser.add_argument(
        "--figure", default="docs/embedding_reconstruction.png", help="PNG ('' for none)"
    )
    parser.add_argument(
        "--model", choices=("paper", "graded"), default="paper", help="embedding checkpoints"
    )
    args = parser.parse_args()
    start = time.perf_counter()
    report(args.count, args.model)
    if args.model != "paper":
        presets(args.model)
    if args.figure and args.model == "paper":
        figure(args.figure)
    print(f"{time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
