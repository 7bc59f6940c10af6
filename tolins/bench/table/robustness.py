"""The robustness table of ``tolins bench`` (beyond the paper): its lines, its columns and
its cells.

The 2*2 circle socket's policies (:data:`POLICIES`: the safe and efficient experts, π_n,
π_φ and π_φ*) under conditions the paper never tried (:data:`CONDITIONS`): the tolerance
grades (radial clearance 200 µm, the paper's, then 100, 50 and 20 µm:
``tolins/Circle2x2Fit{um}-v2``), each defect kind of :mod:`tolins.geometry.defects` at the
200 µm fit (``defects=``, drawn every episode), and randomised physics
(``randomization="default"``, :data:`tolins.physics.randomization.DEFAULT_RANDOMIZATION`).

Each cell (policy × condition) is summarised as a row of Table 1 is
(:func:`tolins.bench.table.results.row_entry`: means, ``*_per_seed``, 95 % CIs over
training seeds with ≥ 2 of them, else over the one seed's episodes) and goes into
``results.json["robustness"]`` (:func:`robustness_table`). Its stages:
:mod:`tolins.bench.jobs.robustness`; its section and figure:
:mod:`tolins.bench.reports.robustness`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from tolins.bench.table.results import row_entry
from tolins.bench.table.rows import CIRCLE_2X2, Row, bench_id
from tolins.envs.tasks import DEFECT_SIGMA
from tolins.geometry.specs import GRADES_UM
from tolins.physics.registry import simulator
from tolins.rollouts.episodes import Episode

#: ``results.json``'s key of the table.
KEY = "robustness"
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
        """Whether the vector env of ``backend`` takes its defects (MuJoCo's batch has no
        plugged holes)."""
        return not self.defects or self.defects[0] in simulator(backend).batch.defect_kinds


def _grade_env(um: int) -> str:
    return CIRCLE_2X2 if um == GRADES_UM[0] else bench_id(f"Circle2x2Fit{um}")


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
        agent: An expert name or a training of :data:`tolins.bench.table.rows.TRAININGS`.
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

#: A policy's episodes of one training seed: condition id -> episodes.
SeedEpisodes = dict[str, list[Episode]]


@dataclass(frozen=True)
class ConditionTable:
    """A table of policies under conditions: this robustness table, or another built the
    same way (the Panda's, :mod:`tolins.bench.table.robot`).

    Attributes:
        key: Its key in ``results.json``.
        prefix: Its stages' name prefix (``{prefix}{policy}-seed{s}``).
        policies: Its lines.
        conditions: Its columns.
    """

    key: str
    prefix: str
    policies: tuple[RobustPolicy, ...]
    conditions: tuple[Condition, ...]


#: This module's table.
ROBUSTNESS = ConditionTable(KEY, "robust-", POLICIES, CONDITIONS)


def robustness_table(
    episodes: dict[str, list[SeedEpisodes]],
    count: int,
    seeds: int,
    table: ConditionTable = ROBUSTNESS,
) -> dict[str, Any] | None:
    """``results.json["robustness"]`` from the episodes of each policy that ran (policy id
    -> one :data:`SeedEpisodes` per training seed; ``None`` when none ran): the
    conditions, the policies, and per policy and condition a Table 1 entry
    (:func:`~tolins.bench.table.results.row_entry`) with ``condition`` and
    ``clearance_um``; ``count`` episodes per cell and training seed (of ``table``)."""
    cells: dict[str, dict[str, Any]] = {}
    policies = []
    for policy in table.policies:
        if policy.id not in episodes:
            continue
        per_seed = episodes[policy.id]
        policies.append(asdict(policy))
        cells[policy.id] = {}
        for c in table.conditions:
            row = Row(f"{policy.id}/{c.id}", policy.label, policy.agent, c.env_id, "2*2")
            entry = row_entry(row, [seed[c.id] for seed in per_seed])
            cells[policy.id][c.id] = {"condition": c.id, "clearance_um": c.clearance_um, **entry}
    if not cells:
        return None
    return {
        "conditions": [asdict(c) for c in table.conditions],
        "policies": policies,
        "episodes_per_seed": count,
        "seeds": seeds,
        "cells": cells,
    }
