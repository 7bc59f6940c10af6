"""The Panda's table of ``tolins bench`` (beyond the paper): the 2*2's policies with a
Franka Panda holding the part, with and without a grasp error.

The lines (:data:`ROBOT_POLICIES`): the safe and efficient experts, π_bc, π_n, π_φ and π_φ*,
trained on the free body (the paper's ideal servos) and evaluated on
``tolins/Circle2x2Panda-v2`` (:mod:`tolins.physics.panda`). The columns
(:data:`ROBOT_CONDITIONS`): the nominal grasp, and a grasp error drawn every episode
(:data:`GRASP_ERROR`). Its cells are the robustness table's (95 % CIs over training
seeds; :func:`~tolins.bench.table.robustness.robustness_table`), its stages
``robot-{policy}-seed{s}`` (:mod:`tolins.bench.jobs.robustness`), its key in
``results.json`` ``robot``. MuJoCo only: the other simulators have no arm. Its grasp-error
column joins the robustness table as a condition of its own (:func:`with_grasp_column`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tolins.bench.table.robustness import POLICIES, Condition, ConditionTable, RobustPolicy
from tolins.bench.table.rows import bench_id
from tolins.geometry.specs import GRADES_UM

#: ``results.json``'s key of the table.
KEY = "robot"
#: The Panda's 2*2.
ROBOT_ENV = bench_id("Circle2x2Panda")
#: The grasp error's std ``[x, y, yaw]`` (mm, mm, rad, the hand's frame): about one
#: clearance along the pads (across them the closing fingers centre the part, pushing it
#: along the pads by 0.2 mm on average; docs/robot.md).
GRASP_ERROR = (0.2, 0.2, 0.02)


@dataclass(frozen=True)
class RobotCondition(Condition):
    """A column of the Panda's table: the robustness table's :class:`Condition` with the
    grasp error's std, or ``None`` (the nominal grasp)."""

    grasp_error: tuple[float, float, float] | None = None

    @property
    def env_kwargs(self) -> dict[str, Any]:
        kwargs = super().env_kwargs
        if self.grasp_error is not None:
            kwargs["grasp_error"] = list(self.grasp_error)
        return kwargs


ROBOT_CONDITIONS: tuple[RobotCondition, ...] = (
    RobotCondition("panda", "Panda", "robot", ROBOT_ENV, GRADES_UM[0]),
    RobotCondition(
        "grasp", "Panda, grasp error", "robot", ROBOT_ENV, GRADES_UM[0], grasp_error=GRASP_ERROR
    ),
)
_BY_ID = {policy.id: policy for policy in POLICIES}
ROBOT_POLICIES: tuple[RobustPolicy, ...] = (
    _BY_ID["safe"],
    _BY_ID["efficient"],
    RobustPolicy("pi_bc", "π_bc", "bc_safe"),
    _BY_ID["pi_n"],
    _BY_ID["pi_phi"],
    _BY_ID["pi_phi_star"],
)
#: The table.
ROBOT = ConditionTable(KEY, "robot-", ROBOT_POLICIES, ROBOT_CONDITIONS)


def with_grasp_column(
    robustness: dict[str, Any] | None, robot: dict[str, Any] | None
) -> dict[str, Any] | None:
    """``results.json["robustness"]`` with the Panda table's grasp-error column (its cells,
    the same episodes) when the Panda's table has every policy of it; else as it was."""
    if robustness is None or robot is None:
        return robustness
    ids = [policy["id"] for policy in robustness["policies"]]
    if not all(policy in robot["cells"] for policy in ids):
        return robustness
    grasp = next(c for c in robot["conditions"] if c["id"] == "grasp")
    cells = {
        policy: {**robustness["cells"][policy], "grasp": robot["cells"][policy]["grasp"]}
        for policy in ids
    }
    return {**robustness, "conditions": [*robustness["conditions"], grasp], "cells": cells}
