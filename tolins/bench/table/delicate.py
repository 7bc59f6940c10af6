"""The delicate-pins table of ``tolins bench`` (beyond the paper): the 2*2's policies on
the evaluation workpieces of Table 1's circle rows with pins that bend and stay bent
(docs/delicate.md).

The lines (:data:`DELICATE_POLICIES`) are every Table 1 policy of the circle rows, trained
on rigid pins: the experts, row C1's π_bc and π_n (which imitate the efficient expert),
row C2's (the safe one), π_φ and π_φ*; the columns
(:data:`CONDITIONS`) the paper's 2*2 at 200 µm, its 50 µm grade and the 2*4 with
``pins="elastic-plastic"`` (phosphor bronze, a pin damaged beyond half the radial
clearance), and the C4 rows' bent-pin 2*1 with those pins, where π_φ* re-plans after each
blocked attempt (as in row C4.2) and each attempt meets the part as the last one left it.
Its cells are the robustness table's
(:func:`~tolins.bench.table.robustness.robustness_table`) with the damage figures of
:func:`~tolins.bench.table.results.damage_figures` (the share of damaged parts and of
successes without damage, 95 % CIs over training seeds); its stages
``delicate-{policy}-seed{s}`` (:mod:`tolins.bench.jobs.robustness`); its key in
``results.json`` ``delicate``, which also holds the claim :func:`damage_claim` checks and
the gentlest learned policy (:func:`gentlest`). MuJoCo only: the kinematic simulator's
pins cannot bend.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from tolins.bench.table.claims import HELD, INCONCLUSIVE, NO_DIFFERENCE, NOT_HELD
from tolins.bench.table.robot import ROBOT_POLICIES
from tolins.bench.table.robustness import Condition, ConditionTable, RobustPolicy
from tolins.bench.table.rows import bench_id
from tolins.bench.table.statistics import EPISODES, SEEDS, difference, equivalent, sign
from tolins.geometry.specs import GRADES_UM

#: ``results.json``'s key of the table.
KEY = "delicate"


@dataclass(frozen=True)
class BendingCondition(Condition):
    """A column on a workpiece whose id has rigid pins, with ``pins`` given to it."""

    pins: str = "elastic-plastic"

    @property
    def env_kwargs(self) -> dict[str, Any]:
        return {**super().env_kwargs, "pins": self.pins}


#: The columns: the evaluation workpieces of the circle rows, the 2*2 (C1, C2), the 2*4
#: (C3) and the bent-pin 2*1 (C4), and the 2*2's 50 µm grade, with pins that bend.
CONDITIONS: tuple[Condition, ...] = (
    Condition("delicate", "2*2", "delicate", bench_id("Circle2x2Delicate"), GRADES_UM[0]),
    Condition("delicate_fit50", "2*2 at 50 µm", "delicate", bench_id("Circle2x2Fit50Delicate"), 50),
    Condition("delicate_2x4", "2*4 (C3)", "delicate", bench_id("Circle2x4Delicate"), GRADES_UM[0]),
    BendingCondition(
        "delicate_c4", "bent-pin 2*1 (C4)", "delicate", bench_id("Circle2x1Defective"), GRADES_UM[0]
    ),
)
#: The lines: the Panda table's (:data:`~tolins.bench.table.robot.ROBOT_POLICIES`), with
#: row C1's π_bc and π_n beside row C2's, each pair labelled with its row.
DELICATE_POLICIES: tuple[RobustPolicy, ...] = (
    *ROBOT_POLICIES[:2],
    RobustPolicy("bc_efficient", "π_bc (C1)", "bc_efficient"),
    RobustPolicy("pi_n_efficient", "π_n (C1)", "pi_n_efficient"),
    *(dataclasses.replace(policy, label=f"{policy.label} (C2)") for policy in ROBOT_POLICIES[2:4]),
    *ROBOT_POLICIES[4:],
)
#: The table.
DELICATE = ConditionTable(KEY, "delicate-", DELICATE_POLICIES, CONDITIONS)
#: The claim the table checks, in the words of results.md.
CLAIM = "the safe expert damages fewer parts than the efficient one"
#: The smallest difference of damage rate that matters (a share of episodes), written
#: down before the run: one part in twenty.
DAMAGE_DELTA = 0.05


def damage_claim(table: dict[str, Any], condition: str = "delicate") -> dict[str, Any]:
    """The verdict on :data:`CLAIM` on ``condition``'s column of ``table``
    (``results.json["delicate"]``): the efficient expert's damage rate minus the safe
    one's, with its 95 % CI, paired over training seeds (each evaluates both experts from
    the same initial poses) or over the one seed's episodes; *held* when the CI lies above
    0, *did not hold* below, *no practical difference* inside ± :data:`DAMAGE_DELTA`,
    else *inconclusive*, as is a difference of one sample (the four-valued verdicts of
    :mod:`tolins.bench.table.claims`; the experts are not trained, so one seed needs no
    training margin)."""
    cells = table["cells"]
    if "safe" not in cells or "efficient" not in cells:
        return {"claim": CLAIM, "verdict": "not evaluated", "condition": condition}
    safe, efficient = cells["safe"][condition], cells["efficient"][condition]
    if len(safe["damage_per_seed"]) > 1:
        x, y, over = efficient["damage_per_seed"], safe["damage_per_seed"], SEEDS
    else:
        x, y, over = efficient["damage_per_episode"][0], safe["damage_per_episode"][0], EPISODES
    interval = difference(x, y, over, paired=True)
    verdict = {1: HELD, -1: NOT_HELD}.get(sign(interval))
    if verdict is None:
        verdict = NO_DIFFERENCE if equivalent(interval, DAMAGE_DELTA) else INCONCLUSIVE
    if interval.n < 2:  # one sample's bootstrap interval has no width: it decides nothing
        verdict = INCONCLUSIVE
    return {
        "claim": CLAIM,
        "condition": condition,
        "verdict": verdict,
        "difference": interval.to_json(),
        "delta": DAMAGE_DELTA,
    }


def gentlest(table: dict[str, Any]) -> dict[str, Any] | None:
    """The learned policy of ``table`` that damaged the fewest parts over all its
    conditions (their mean damage rate; ties: the one with more successes without damage,
    then the table's order), with both means; ``None`` when no learned policy ran."""
    learned = [p for p in table["policies"] if p["agent"] not in ("safe", "efficient")]
    if not learned:
        return None

    def means(policy: dict[str, Any]) -> tuple[float, float]:
        cells = table["cells"][policy["id"]].values()
        damage = sum(cell["damage_mean"] for cell in cells) / len(cells)
        success = sum(cell["success_undamaged_mean"] for cell in cells) / len(cells)
        return damage, success

    def rank(policy: dict[str, Any]) -> tuple[float, float]:
        damage, success = means(policy)
        return damage, -success

    best = min(learned, key=rank)
    damage, success = means(best)
    return {
        "policy": best["id"],
        "label": best["label"],
        "damage_mean": damage,
        "success_undamaged_mean": success,
    }


def with_verdicts(table: dict[str, Any] | None) -> dict[str, Any] | None:
    """``table`` with its ``claim`` (:func:`damage_claim`, on the paper's 2*2), the same
    claim on each column (``claim_by_condition``) and ``gentlest`` (:func:`gentlest`)
    (``None`` stays ``None``)."""
    if table is None:
        return None
    by_condition = {c["id"]: damage_claim(table, c["id"]) for c in table["conditions"]}
    return {
        **table,
        "claim": damage_claim(table),
        "claim_by_condition": by_condition,
        "gentlest": gentlest(table),
    }
