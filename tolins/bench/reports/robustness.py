"""The robustness table in a bench's reports: its section of ``results.md`` and
``robustness.png`` (the table itself: :mod:`tolins.bench.table.robustness`); and the
Panda's table's section (:mod:`tolins.bench.table.robot`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from tolins.bench.reports.plots import pyplot, save_figure
from tolins.bench.table.robustness import DEFECT_SCALES
from tolins.envs.tasks import DEFECT_SIGMA


def format_table(robustness: dict[str, Any]) -> str:
    """The success rate of each policy (rows) under each condition (columns), with its
    95 % CI."""
    conditions = robustness["conditions"]
    header = "| policy | " + " | ".join(c["label"] for c in conditions) + " |"
    lines = [header, "|---|" + "---|" * len(conditions)]
    for policy in robustness["policies"]:
        cells = robustness["cells"][policy["id"]]
        texts = []
        for c in conditions:
            entry = cells[c["id"]]
            low, high = entry["success_ci"]
            texts.append(f"{entry['success_mean']:.2f} [{low:.2f}, {high:.2f}]")
        lines.append(f"| {policy['label']} | " + " | ".join(texts) + " |")
    return "\n".join(lines)


def format_section(robustness: dict[str, Any] | None) -> list[str]:
    """``results.md``'s lines of the table (none without one)."""
    if robustness is None:
        return []
    seeds, count = robustness["seeds"], robustness["episodes_per_seed"]
    over = f"the {seeds} training seeds" if seeds > 1 else "the episodes of the one seed"
    defects = ", ".join(
        f"{kind} {'' if sigma is None else sigma}".strip() for kind, sigma in DEFECT_SCALES.items()
    )
    note = (
        f"Success rate [95 % CI over {over}] of the 2*2 circle's policies, {count} "
        f"episode{'s' if count > 1 else ''} per cell and training seed (the rows' evaluation "
        "seeds). Columns: the radial "
        "clearance of the holes (200 µm is the paper's 2*2, the others "
        "`tolins/Circle2x2Fit{µm}-v2`), a defect kind drawn every episode at 200 µm "
        f"(`defects=`: {defects}; mm, pitch relative), randomised physics "
        "(`randomization='default'`), and, where the bench ran its Panda table, a Franka "
        "Panda holding the part with a grasp error (the next section's column). A blocked "
        "hole never inserts. π_φ* is π_φ with "
        "inference in the loop, as in C4.2 "
        f"(its prior: bent pins of std {DEFECT_SIGMA} mm, whatever the condition); π_n and "
        "π_φ are bound to the paper's 2*2, the workpiece π_φ's embedding knows (hole radii "
        "0.45–0.6 mm)."
    )
    return [
        "",
        "## Robustness (beyond the paper)",
        "",
        note,
        "",
        format_table(robustness),
        "",
        "![success against clearance and under defects](robustness.png)",
    ]


def format_robot_section(robot: dict[str, Any] | None) -> list[str]:
    """``results.md``'s lines of the Panda's table (none without one)."""
    if robot is None:
        return []
    seeds, count = robot["seeds"], robot["episodes_per_seed"]
    over = f"the {seeds} training seeds" if seeds > 1 else "the episodes of the one seed"
    grasp = next(c for c in robot["conditions"] if c.get("grasp_error"))
    note = (
        f"Success rate [95 % CI over {over}] of the 2*2 circle's policies with a Franka "
        f"Panda holding the part (`{grasp['env_id']}`: task-space impedance control, a "
        "friction grasp, the pose from forward kinematics and the force from the wrist; "
        f"docs/robot.md), {count} episode{'s' if count > 1 else ''} per cell and training "
        "seed (the rows' evaluation seeds). Every policy was trained on the free body, the "
        "paper's ideal servos. Columns: the nominal grasp, and the part put off in the hand "
        f"every episode (`grasp_error={list(grasp['grasp_error'])}`, std of x, y (mm) and yaw "
        "(rad) in the hand; the closing fingers centre it across the pads). π_φ* is π_φ with "
        "inference in the loop, as in C4.2."
    )
    means = " ".join(
        f"{policy['label']} {robot['cells'][policy['id']]['panda']['reward_mean']:.2f};"
        for policy in robot["policies"]
    )
    return [
        "",
        "## A robot holding the part (beyond the paper)",
        "",
        note,
        "",
        format_table(robot),
        "",
        f"Mean reward with the nominal grasp: {means.rstrip(';')}.",
    ]


def plot_robustness(path: str | Path, robustness: dict[str, Any]) -> Path:
    """``robustness.png``: success against radial clearance (µm, log x) per policy, and
    success under each defect kind and randomised physics, with 95 % CI bars."""
    plt = pyplot()
    conditions = robustness["conditions"]
    grades = [c for c in conditions if c["group"] == "grade"]
    others = [c for c in conditions if c["group"] != "grade"]
    policies = robustness["policies"]
    figure, (left, right) = plt.subplots(1, 2, figsize=(13, 4.5), constrained_layout=True)
    width = 0.8 / max(len(policies), 1)
    for k, policy in enumerate(policies):
        cells = robustness["cells"][policy["id"]]

        def bars(cs, cells=cells):
            mean = np.array([cells[c["id"]]["success_mean"] for c in cs])
            ci = np.array([cells[c["id"]]["success_ci"] for c in cs]).reshape(-1, 2)
            return mean, np.clip([mean - ci[:, 0], ci[:, 1] - mean], 0, None)

        mean, error = bars(grades)
        x = np.array([c["clearance_um"] for c in grades], dtype=float)
        shift = 1.0 + 0.03 * (k - (len(policies) - 1) / 2)  # side by side on a log axis
        left.errorbar(x * shift, mean, yerr=error, marker="o", capsize=3, label=policy["label"])
        mean, error = bars(others)
        offset = np.arange(len(others)) + (k - (len(policies) - 1) / 2) * width
        right.bar(offset, mean, width, yerr=error, capsize=2, label=policy["label"])
    left.set_xscale("log")
    ticks = [c["clearance_um"] for c in grades]
    left.set_xticks(ticks, [str(t) for t in ticks])
    left.minorticks_off()
    left.set_xlabel("radial clearance (µm)")
    left.set_ylabel("success rate")
    left.set_ylim(-0.05, 1.05)
    left.set_title("tolerance grades (2*2)")
    left.grid(alpha=0.3)
    left.legend()
    right.set_xticks(np.arange(len(others)), [c["label"] for c in others])
    right.set_ylim(-0.05, 1.05)
    robot = any(c["group"] == "robot" for c in others)
    held = ", a Panda with a grasp error" if robot else ""
    right.set_title(f"defects, randomised physics{held} (2*2, 200 µm)")
    right.grid(axis="y", alpha=0.3)
    over = "training seeds" if robustness["seeds"] > 1 else "episodes"
    figure.suptitle(f"Robustness: success rate, 95 % CI over {over}")
    return save_figure(figure, path)
