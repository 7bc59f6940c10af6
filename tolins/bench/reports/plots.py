"""The benchmark's figures (matplotlib, Agg, written atomically as PNG)."""

from __future__ import annotations

import io
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

from tolins.atomic import atomic_write
from tolins.bench.table.results import standard_error
from tolins.bench.table.rows import unseeded
from tolins.geometry.specs import SocketSpec
from tolins.geometry.tolerance import NO_TOLERANCE, WINDOWS, image


def pyplot():
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(figure, path: str | Path) -> Path:
    """Write ``figure`` to ``path`` as a PNG, atomically, and close it; the path."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=100)
    pyplot().close(figure)
    return atomic_write(path, lambda file: file.write(buffer.getvalue()))


def plot_table(
    path: str | Path,
    results: dict[str, dict[str, Any]],
    paper: dict[str, dict[str, tuple[float, float]]],
) -> Path:
    """Reward and success rate of every row, this run (with the 95 % CI of its mean,
    ``{figure}_ci``; ± standard error for entries without one) beside the paper (± its
    std over runs); with the force figures (schema /2) a third panel of each row's peak
    and mean in-contact force."""

    plt = pyplot()
    rows = list(results)
    x = np.arange(len(rows))
    over = next(iter(results.values()), {}).get("ci_over", "episodes")
    forces = bool(rows) and all("peak_force_mean" in results[r] for r in rows)
    panels = 3 if forces else 2
    figure, axes = plt.subplots(
        panels, 1, figsize=(max(6, 0.7 * len(rows) + 2), 3 * panels), sharex=True
    )
    if forces:  # the paper reports no forces: this run's peak and in-contact force only
        peak = [results[r]["peak_force_mean"] for r in rows]
        contact = [results[r]["contact_force_mean"] for r in rows]
        peak_error = [standard_error(results[r], "peak_force") for r in rows]
        axes[2].bar(x - 0.2, peak, 0.4, yerr=peak_error, label="peak force (± s.e.)", capsize=2)
        axes[2].bar(x + 0.2, contact, 0.4, label="mean force in contact", alpha=0.7)
        axes[2].set_ylabel("contact force (N)")
        axes[2].grid(axis="y", alpha=0.3)
        axes[2].legend()
    for axis, figure_name in zip(axes[:2], ("reward", "success"), strict=True):
        ours = [results[r][f"{figure_name}_mean"] for r in rows]
        ours_error = np.array([_error_bar(results[r], figure_name) for r in rows]).T
        theirs = [paper[r][figure_name][0] if r in paper else np.nan for r in rows]
        theirs_std = [paper[r][figure_name][1] if r in paper else 0.0 for r in rows]
        label = f"tolins (95 % CI over {over})"
        axis.bar(x - 0.2, ours, 0.4, yerr=ours_error, label=label, capsize=2)
        axis.bar(x + 0.2, theirs, 0.4, yerr=theirs_std, label="paper (± std)", capsize=2, alpha=0.7)
        axis.set_ylabel("success rate" if figure_name == "success" else "reward")
        axis.grid(axis="y", alpha=0.3)
    axes[0].legend()
    axes[-1].set_xticks(x, rows)
    figure.tight_layout()
    return save_figure(figure, path)


def _error_bar(entry: dict[str, Any], figure: str) -> tuple[float, float]:
    """(below, above) the mean: to the ends of its CI, or one standard error."""
    mean = entry[f"{figure}_mean"]
    if f"{figure}_ci" in entry:
        low, high = entry[f"{figure}_ci"]
        return max(mean - low, 0.0), max(high - mean, 0.0)
    error = standard_error(entry, figure)
    return error, error


def plot_claim(path: str | Path, check: Any, results: dict[str, dict[str, Any]]) -> Path:
    """rliable-style interval plot of one claim (a :class:`tolins.bench.table.claims.ClaimCheck`):
    each row's mean reward, each pair's difference (with the claim's ``±δ`` band) and
    P(better > worse), as 95 % CIs (bars) around point estimates (ticks)."""
    plt = pyplot()
    pairs = check.comparisons
    rows = list(dict.fromkeys(row for c in pairs for row in (c.better, c.worse)))
    height = 1.5 + 0.42 * max(len(rows), len(pairs))
    figure, axes = plt.subplots(1, 3, figsize=(13, height), constrained_layout=True)
    colours = {
        "held": "tab:green",
        "did not hold": "tab:red",
        "no practical difference": "tab:purple",
        "inconclusive": "tab:grey",
    }
    row_bars = [(r, results[r]["reward_mean"], *results[r]["reward_ci"], "tab:blue") for r in rows]
    difference = [
        (
            f"{c.better} − {c.worse}: {c.verdict}",
            c.difference.estimate,
            c.difference.low,
            c.difference.high,
            colours[c.verdict],
        )
        for c in pairs
    ]
    improvement = [
        (
            f"P({c.better} > {c.worse})",
            c.improvement.estimate,
            c.improvement.low,
            c.improvement.high,
            colours[c.verdict],
        )
        for c in pairs
    ]
    panels = (
        (row_bars, "mean reward", None),
        (difference, "difference of mean reward", 0.0),
        (improvement, "probability of improvement", 0.5),
    )
    delta = check.claim.delta  # inside ±δ: no practical difference
    axes[1].axvspan(-delta, delta, color="tab:purple", alpha=0.08, lw=0)
    axes[1].axvline(-delta, color="tab:purple", lw=0.8, ls=":")
    axes[1].axvline(delta, color="tab:purple", lw=0.8, ls=":")
    for i, pair in enumerate(pairs):  # one training seed: the margin a CI must clear
        if pair.margin:
            axes[1].barh(i, 2 * pair.margin, 0.95, left=-pair.margin, color="grey", alpha=0.15)
    for axis, (bars, title, reference) in zip(axes, panels, strict=True):
        for i, (_, estimate, low, high, colour) in enumerate(bars):
            axis.barh(i, high - low, 0.6, left=low, color=colour, alpha=0.75)
            axis.plot([low, high], [i, i], "|", color=colour, ms=14, mew=2)  # width-0 CIs too
            axis.vlines(estimate, i - 0.28, i + 0.22, color="black", alpha=0.6)
        if reference is not None:
            axis.axvline(reference, color="black", lw=0.8, ls="--")
        left, right = axis.get_xlim()  # room around the bars, and the reference line inside
        if reference is not None:
            left, right = min(left, reference), max(right, reference)
        pad = 0.08 * (right - left) or 0.5
        axis.set_xlim(left - pad, right + pad)
        axis.set_yticks(range(len(bars)), [b[0] for b in bars])
        axis.invert_yaxis()
        axis.set_title(title)
        axis.grid(axis="x", alpha=0.25)
        for side in ("top", "right"):
            axis.spines[side].set_visible(False)
    axes[2].set_xlim(-0.02, 1.02)
    title = f"{check.claim.statement}: {check.verdict} ({check.basis})"
    figure.suptitle("\n".join(textwrap.wrap(title, 150)), fontsize=9)
    return save_figure(figure, path)


def plot_learning_curves(path: str | Path, curves: dict[str, list[dict[str, float]]]) -> Path:
    """RS-GAIL's curves (reward, success, D(student) of the CMA-ES mean), one line per run."""
    plt = pyplot()
    panels = (("reward", "env reward"), ("success", "success rate"), ("d_expert", "D(student)"))
    figure, axes = plt.subplots(1, 3, figsize=(14, 3.6), constrained_layout=True)
    for label, history in curves.items():
        iterations = [row["iteration"] for row in history]
        for axis, (key, _) in zip(axes, panels, strict=True):
            axis.plot(iterations, [row[key] for row in history], marker=".", label=label)
    for axis, (_, name) in zip(axes, panels, strict=True):
        axis.set_xlabel("RS-GAIL iteration")
        axis.set_ylabel(name)
        axis.grid(alpha=0.3)
    axes[2].axhspan(0.4, 0.6, color="tab:green", alpha=0.12)
    axes[0].legend(fontsize=7)
    return save_figure(figure, path)


def plot_env_step_curves(path: str | Path, curves: dict[str, dict[str, np.ndarray]]) -> Path:
    """Sparse reward and success rate against env steps, one line per training stage
    (RS-GAIL's π_n and the deep-RL baselines, :func:`tolins.bench.table.baselines.env_step_curves`):
    one colour and legend entry per training, one line per seed (baselines on the sparse
    reward dotted, on the dense one dashed)."""
    plt = pyplot()
    figure, axes = plt.subplots(1, 2, figsize=(12, 3.8), constrained_layout=True)
    colours: dict[str, str] = {}
    for stage, curve in curves.items():
        training = unseeded(stage)
        first = training not in colours
        colours.setdefault(training, f"C{len(colours) % 10}")
        # RS-GAIL solid, baselines on the sparse reward dotted, on the dense one dashed
        style = (
            {"ls": ":" if training.endswith("_sparse") else "--"}
            if training.startswith(("ppo", "sac"))
            else {}
        )
        for axis, key in zip(axes, ("reward", "success"), strict=True):
            axis.plot(
                curve["env_steps"],
                curve[key],
                color=colours[training],
                marker=".",
                lw=1.2,
                alpha=0.8,
                label=training if first else None,
                **style,
            )
    for axis, name in zip(axes, ("reward (sparse, the paper's)", "success rate"), strict=True):
        axis.set(xlabel="env steps", ylabel=name)
        axis.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    figure.suptitle(
        "RS-GAIL (π_n, from BC) vs PPO and SAC (from scratch) against env steps, a line per seed"
    )
    return save_figure(figure, path)


def plot_training_trajectories(
    path: str | Path,
    trajectories: dict[str, np.ndarray],
    title: str,
) -> Path:
    """Pose trajectories ``(steps, 4)`` of one episode per label (the paper's Fig. 4a):
    top view (x, y) and the approach (horizontal distance to the goal against z)."""
    plt = pyplot()
    figure, (top, side) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    colours = plt.get_cmap("viridis")(np.linspace(0, 0.9, max(len(trajectories), 1)))
    for (label, poses), colour in zip(trajectories.items(), colours, strict=False):
        style = {"color": "black", "ls": "--"} if label.startswith("expert") else {"color": colour}
        top.plot(poses[:, 0], poses[:, 1], marker=".", ms=3, label=label, **style)
        side.plot(np.hypot(poses[:, 0], poses[:, 1]), poses[:, 3], marker=".", ms=3, **style)
        top.plot(*poses[0, :2], "o", color=style["color"], ms=5)
    top.plot(0, 0, "r+", ms=14, mew=2, label="goal")
    top.set(xlabel="x (mm)", ylabel="y (mm)", title="top view")
    top.set_aspect("equal", adjustable="datalim")
    side.axhline(0.0, color="grey", lw=1)
    side.set(xlabel="distance to the goal in x-y (mm)", ylabel="z (mm)", title="approach")
    for axis in (top, side):
        axis.grid(alpha=0.3)
    top.legend(fontsize=7)
    figure.suptitle(title)
    return save_figure(figure, path)


def plot_tolerance_images(path: str | Path, specs: dict[str, SocketSpec]) -> Path:
    """The flattened tolerance (largest θ per x-y cell) of each workpiece."""
    plt = pyplot()
    figure, axes = plt.subplots(
        1, len(specs), figsize=(2.6 * len(specs), 2.9), constrained_layout=True, squeeze=False
    )
    for axis, (label, spec) in zip(axes[0], specs.items(), strict=True):
        window = WINDOWS[spec.family]
        values = np.ma.masked_equal(image(spec, 64), NO_TOLERANCE)
        extent = [-window.half_width, window.half_width] * 2
        picture = axis.imshow(values, origin="lower", extent=extent, cmap="viridis", vmin=0)
        axis.set(title=label, xlabel="x (mm)")
        figure.colorbar(picture, ax=axis, shrink=0.8, label="θ (rad)")
    axes[0][0].set_ylabel("y (mm)")
    return save_figure(figure, path)
