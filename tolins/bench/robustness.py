"""The robustness table of ``tolins bench`` (beyond the paper; issue 22).

The 2*2 circle socket's policies (the safe and efficient experts, π_n, π_φ and π_φ*) under
conditions the paper never tried (:data:`CONDITIONS`): the tolerance grades (radial
clearance 200 µm, the paper's, then 100, 50 and 20 µm: ``tolins/Circle2x2Fit{um}-v1``),
each defect kind of :mod:`tolins.geometry.defects` at the 200 µm fit (``defects=``, drawn
every episode), and randomised physics (``randomization="default"``,
:data:`tolins.envs.randomization.DEFAULT_RANDOMIZATION`).

One stage per policy and training seed, ``robust-{policy}-seed{s}``: its config names the
trained policy's stage (name and key, as the evaluation stages do) so that a retrained
policy re-runs it; it evaluates the policy on every condition, from the evaluation seeds
of the table's rows (:func:`tolins.bench.evaluation.eval_seeds`, the profile's
``robustness_episodes`` of them; so the 200 µm cell repeats the first episodes of C2.1,
C1.1, C2.3), through :func:`tolins.bench.evaluation.evaluate` (the vector env; one env
after another for π_φ* and for blocked holes on MuJoCo, which the MuJoCo batch lacks).

Each cell (policy × condition) is summarised as a row of Table 1 is
(:func:`tolins.bench.results.row_entry`: means, ``*_per_seed``, 95 % CIs over training
seeds with ≥ 2 of them, else over the one seed's episodes) and goes into
``results.json["robustness"]``, ``results.md`` ("Robustness (beyond the paper)") and
``robustness.png``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from tolins.atomic import atomic_json
from tolins.bench.evaluation import episodes_to_json, eval_seeds, evaluate
from tolins.bench.integrity import StageFileError, checked_episodes, read_json
from tolins.bench.profiles import Profile
from tolins.bench.stages import StageCache
from tolins.bench.table import CIRCLE_2X2, Row
from tolins.envs.tasks import DEFECT_SIGMA
from tolins.geometry.specs import GRADES_UM

#: The file of a robustness stage: condition id -> its episodes.
ROBUSTNESS = "robustness.json"
#: ``results.json``'s key of the table.
KEY = "robustness"
#: The stage-name prefix.
PREFIX = "robust-"
#: Defect scales on the 2*2 (mm; pitch relative): bent as the defective preset's
#: (``tolins.envs.tasks.DEFECT_SIGMA``), pitch 2 % (±0.15 mm over the 7.62 mm row pitch),
#: burrs a quarter of the 0.2 mm clearance, pins shortened by 0.5 mm.
DEFECT_SCALES: dict[str, float | None] = {
    "bent": DEFECT_SIGMA,
    "pitch": 0.02,
    "burr": 0.05,
    "short": 0.5,
    "blocked": None,
}


@dataclass(frozen=True)
class Condition:
    """One column of the table: an env and what is changed in it.

    Attributes:
        id: e.g. ``fit50``, ``burr``, ``physics``.
        label: Its column header.
        group: ``grade``, ``defect`` or ``physics``.
        env_id: The gymnasium id.
        clearance_um: The radial clearance of its holes (µm).
        defects: ``(kind, sigma)`` for ``defects=``, or ``None``.
        randomization: For ``randomization=`` (``"default"``), or ``None``.
    """

    id: str
    label: str
    group: str
    env_id: str
    clearance_um: int
    defects: tuple[str, float | None] | None = None
    randomization: str | None = None

    @property
    def env_kwargs(self) -> dict[str, Any]:
        kwargs: dict[str, Any] = {}
        if self.defects is not None:
            kwargs["defects"] = self.defects
        if self.randomization is not None:
            kwargs["randomization"] = self.randomization
        return kwargs

    def vectorizable(self, backend: str) -> bool:
        """Whether the vector env has it (MuJoCo's batch has no plugged holes)."""
        return not (backend == "mujoco" and self.defects and self.defects[0] == "blocked")


def _grade_env(um: int) -> str:
    return CIRCLE_2X2 if um == GRADES_UM[0] else f"tolins/Circle2x2Fit{um}-v1"


#: The conditions, in the table's column order.
CONDITIONS: tuple[Condition, ...] = (
    *(Condition(f"fit{um}", f"{um} µm", "grade", _grade_env(um), um) for um in GRADES_UM),
    *(
        Condition(kind, kind, "defect", CIRCLE_2X2, GRADES_UM[0], (kind, sigma))
        for kind, sigma in DEFECT_SCALES.items()
    ),
    Condition("physics", "random physics", "physics", CIRCLE_2X2, GRADES_UM[0], None, "default"),
)


@dataclass(frozen=True)
class RobustPolicy:
    """One line of the table: a policy of the 2*2 circle's rows.

    Attributes:
        id: e.g. ``pi_phi_star``.
        label: The paper's name (``π_φ*``).
        agent: An expert name or a training of :data:`tolins.bench.table.TRAININGS`.
        inference: Wrapped in probabilistic inference (as row C4.2).
    """

    id: str
    label: str
    agent: str
    inference: bool = False

    @property
    def trained(self) -> bool:
        return self.agent not in ("safe", "efficient")


POLICIES: tuple[RobustPolicy, ...] = (
    RobustPolicy("safe", "π_e^safe", "safe"),
    RobustPolicy("efficient", "π_e^eff", "efficient"),
    RobustPolicy("pi_n", "π_n", "pi_n_safe"),
    RobustPolicy("pi_phi", "π_φ", "pi_phi_circle"),
    RobustPolicy("pi_phi_star", "π_φ*", "pi_phi_circle", inference=True),
)


def stage_name(policy: RobustPolicy, seed: int) -> str:
    return f"{PREFIX}{policy.id}-seed{seed}"


def stage_config(
    policy: RobustPolicy, seed: int, policy_stage: str | None, profile: Profile, backend: str
) -> dict[str, Any]:
    """The stage's config: the policy, its training stage (``name-key``), the conditions,
    the evaluation seeds, the backend and the tolins version."""
    import tolins

    return {
        "policy": asdict(policy),
        "policy_stage": policy_stage,
        "conditions": [asdict(c) for c in CONDITIONS],
        "backend": backend,
        "seeds": eval_seeds(seed, profile.robustness_episodes),
        "tolins_version": tolins.__version__,
    }


def plan_robustness(plan: Any, trainer: Any, seeds: int) -> list[str]:
    """Add the robustness stages of every policy whose training this run has (a
    :class:`tolins.bench.runner._Plan`); their names."""
    cache, profile, backend = trainer.cache, trainer.profile, trainer.backend
    names = []
    for policy in POLICIES:
        for seed in range(seeds):
            upstream, policy_stage = None, None
            if policy.trained:
                upstream = trainer.stage_name(policy.agent, seed)
                if upstream not in plan:
                    break  # the selected rows do not train it
                policy_stage = trainer.stage_folder_name(policy.agent, seed)
            name = stage_name(policy, seed)
            plan.add(
                name,
                stage_config(policy, seed, policy_stage, profile, backend),
                robustness_stage,
                (cache.root.parent, policy, seed, profile, backend),
                upstream,
                side_by_side=True,
            )
            names.append(name)
    return names


def evaluate_conditions(
    policy: RobustPolicy, policy_path: Path | None, backend: str, seeds: list[int]
) -> dict[str, list]:
    """``policy``'s episodes on every condition from ``seeds``: condition id -> episodes.

    A trained policy is bound to the paper's 2*2 (200 µm): the circle embedding of π_φ
    covers hole radii of 0.45–0.6 mm only, so π_φ sees every condition as the workpiece it
    was trained for (what a graded hole or a defect changes, it meets by contact)."""
    entry: Any = policy.agent
    if policy_path is not None:
        from tolins.envs.tasks import TASKS
        from tolins.learning.actors import make_actor

        socket = next(t.socket for t in TASKS if t.gym_id == CIRCLE_2X2)
        entry = make_actor(f"{policy.agent}={policy_path}", socket)
    return {
        c.id: evaluate(
            entry,
            c.env_id,
            backend,
            seeds,
            inference=policy.inference,
            vectorized=c.vectorizable(backend),
            env_kwargs=c.env_kwargs,
            inference_sigma=DEFECT_SIGMA if policy.inference else None,
        )
        for c in CONDITIONS
    }


def robustness_stage(
    root: Path, policy: RobustPolicy, seed: int, profile: Profile, backend: str, path: Path | None
) -> Path:
    """A job of :mod:`tolins.bench.executor`: ``policy`` (``path``: its trained policy file,
    ``None`` for an expert) on every condition for training seed ``seed``; its folder."""
    policy_stage = None if path is None else path.parent.name
    config = stage_config(policy, seed, policy_stage, profile, backend)

    def build(folder: Path) -> None:
        episodes = evaluate_conditions(policy, path, backend, config["seeds"])
        atomic_json(folder / ROBUSTNESS, {k: episodes_to_json(v) for k, v in episodes.items()})

    return StageCache(root).run(stage_name(policy, seed), config, build)[0]


def _stage_episodes(folder: Path, count: int) -> dict[str, list]:
    path = folder / ROBUSTNESS
    data = read_json(path)
    if not isinstance(data, dict) or set(data) != {c.id for c in CONDITIONS}:
        raise StageFileError(f"{path}: not a robustness stage; delete its folder to rerun")
    return {c.id: checked_episodes(path, data[c.id], count) for c in CONDITIONS}


def robustness_results(
    stage_folders: dict[str, Path], profile: Profile, seeds: int
) -> dict[str, Any] | None:
    """``results.json["robustness"]`` from the finished stages (``None`` when none ran):
    the conditions, the policies, and per policy and condition a Table 1 entry
    (:func:`tolins.bench.results.row_entry`) with ``condition`` and ``clearance_um``."""
    from tolins.bench.results import row_entry

    count = profile.robustness_episodes
    cells: dict[str, dict[str, Any]] = {}
    policies = []
    for policy in POLICIES:
        folders = [stage_folders.get(stage_name(policy, s)) for s in range(seeds)]
        if any(folder is None for folder in folders):
            continue
        per_seed = [_stage_episodes(folder, count) for folder in folders]
        policies.append(asdict(policy))
        cells[policy.id] = {}
        for c in CONDITIONS:
            row = Row(f"{policy.id}/{c.id}", policy.label, policy.agent, c.env_id, "2*2")
            entry = row_entry(row, [episodes[c.id] for episodes in per_seed])
            cells[policy.id][c.id] = {"condition": c.id, "clearance_um": c.clearance_um, **entry}
    if not cells:
        return None
    return {
        "conditions": [asdict(c) for c in CONDITIONS],
        "policies": policies,
        "episodes_per_seed": count,
        "seeds": seeds,
        "cells": cells,
    }


# --- reports -------------------------------------------------------------------------


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
        "`tolins/Circle2x2Fit{µm}-v1`), a defect kind drawn every episode at 200 µm "
        f"(`defects=`: {defects}; mm, pitch relative), randomised physics "
        "(`randomization='default'`). A blocked hole never inserts. π_φ* is π_φ with "
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


def plot_robustness(path: str | Path, robustness: dict[str, Any]) -> Path:
    """``robustness.png``: success against radial clearance (µm, log x) per policy, and
    success under each defect kind and randomised physics, with 95 % CI bars."""
    import numpy as np

    from tolins.bench.plots import _pyplot, _save

    plt = _pyplot()
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
    right.set_title("defects and randomised physics (2*2, 200 µm)")
    right.grid(axis="y", alpha=0.3)
    over = "training seeds" if robustness["seeds"] > 1 else "episodes"
    figure.suptitle(f"Robustness: success rate, 95 % CI over {over}")
    return _save(figure, path)
