"""The paper's four claims, checked against a run's ``results.json`` with interval estimates.

Each claim is a set of pairs ``(better, worse)`` of rows. A pair's evidence is the
difference of mean reward with its 95 % stratified-bootstrap CI and rliable's probability
of improvement P(better > worse), both over training seeds (the unit;
:mod:`tolins.bench.table.statistics`). Within one run the rows share training seeds and
evaluation episodes (seed ``s`` of every row starts from the same initial poses, and π_φ
of seed ``s`` is trained on π_n of seed ``s``), so the difference is *paired*: the
bootstrap resamples the per-seed differences.

Verdicts are three-valued. A pair *held* when its CI lies above 0, *did not hold* when it
lies below, and is *inconclusive* when it contains 0. With one training seed the CI is over
evaluation episodes and decides only beyond ± :func:`~tolins.bench.table.statistics.margin`
(the training noise it cannot see, :func:`~tolins.bench.table.statistics.one_seed_margin`; see
:mod:`tolins.bench.table.statistics`). A claim is the conjunction of its
pairs: held when every pair held, did not hold when any did not, inconclusive otherwise;
*not evaluated* when a row is missing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tolins.bench.table.rows import ROWS
from tolins.bench.table.statistics import (
    EPISODES,
    Interval,
    difference,
    margin,
    probability_of_improvement,
    sign,
    unit_samples,
)

HELD, NOT_HELD, NOT_EVALUATED = "held", "did not hold", "not evaluated"
INCONCLUSIVE = "inconclusive"
ONE_SEED = "one training seed: training variance not measured"
_VERDICTS = {1: HELD, -1: NOT_HELD, 0: INCONCLUSIVE}


@dataclass(frozen=True)
class Claim:
    """A claim: in every pair ``(better, worse)`` the first row has the higher mean reward.

    ``equal_budgets``: the claim is about equal env-step budgets (RS-GAIL against deep RL),
    so it is not evaluated on a profile that gives the two sides different budgets.
    """

    name: str
    statement: str
    pairs: tuple[tuple[str, str], ...]
    equal_budgets: bool = False


CLAIMS: tuple[Claim, ...] = (
    Claim(
        "rs_gail",
        "RS-GAIL (π_n) beats the expert and BC",
        (
            ("C1.3", "C1.1"),
            ("C1.3", "C1.2"),
            ("C2.3", "C2.1"),
            ("C2.3", "C2.2"),
            ("P1.3", "P1.1"),
            ("P1.3", "P1.2"),
        ),
    ),
    Claim("tolerance_guided", "π_φ beats π_n on the unseen 2*4", (("C3.2", "C3.1"),)),
    Claim("inference", "π_φ* beats π_φ on defective 2*1 sockets", (("C4.2", "C4.1"),)),
    Claim("polygon_transfer", "π_φ beats π_n on the unseen pentagon", (("P2.2", "P2.1"),)),
    Claim(
        "rs_gail_vs_deep_rl",
        "RS-GAIL (π_n) beats PPO/SAC from scratch on the sparse reward at equal env steps",
        (("C2.3", "R1.1"), ("C2.3", "R1.2"), ("P1.3", "R1.3"), ("P1.3", "R1.4")),
        equal_budgets=True,
    ),
    Claim(
        "rs_gail_vs_dense_deep_rl",
        "RS-GAIL (π_n) beats PPO/SAC from scratch on a dense reward at equal env steps "
        "(beyond the paper)",
        (("C2.3", "R2.1"), ("C2.3", "R2.2"), ("P1.3", "R2.3"), ("P1.3", "R2.4")),
        equal_budgets=True,
    ),
)


@dataclass(frozen=True)
class Comparison:
    """One pair of rows: the difference of mean reward and P(better > worse), each with
    its 95 % CI."""

    better: str
    worse: str
    better_reward: float
    worse_reward: float
    difference: Interval
    improvement: Interval
    margin: float = 0.0

    @property
    def verdict(self) -> str:
        """:data:`HELD`, :data:`NOT_HELD` or :data:`INCONCLUSIVE`: the CI of the difference
        above ``margin``, below ``-margin``, or neither."""
        return _VERDICTS[sign(self.difference, self.margin)]

    def describe(self) -> str:
        beyond = f" (decisive beyond ±{self.margin:.1f})" if self.margin else ""
        return (
            f"{self.better} {self.better_reward:.2f} vs {self.worse} {self.worse_reward:.2f}: "
            f"{self.difference.format(signed=True)}{beyond}, "
            f"P({self.better} > {self.worse}) {self.improvement.format()}: {self.verdict}"
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "better": self.better,
            "worse": self.worse,
            "difference": self.difference.to_json(),
            "probability_of_improvement": self.improvement.to_json(),
            "margin": self.margin,
            "verdict": self.verdict,
        }


@dataclass(frozen=True)
class ClaimCheck:
    """A claim's verdict (:data:`HELD`, :data:`NOT_HELD`, :data:`INCONCLUSIVE`,
    :data:`NOT_EVALUATED`), its pairs and what the intervals are over."""

    claim: Claim
    verdict: str
    comparisons: tuple[Comparison, ...]
    seeds: int = 0
    #: Why a claim whose rows ran was not evaluated (e.g. unequal budgets).
    note: str = ""

    @property
    def basis(self) -> str:
        """What the verdict rests on, e.g. ``5 training seeds`` or the one-seed caveat."""
        if self.note:
            return self.note
        if not self.comparisons:
            return "rows not run"
        if self.comparisons[0].difference.over == EPISODES:
            episodes = self.comparisons[0].difference.n
            return (
                f"{ONE_SEED}; 95 % CIs over {episodes} evaluation episodes, decisive only "
                "beyond the training noise one seed cannot show"
            )
        return f"{self.seeds} training seeds; 95 % CIs over seeds"

    def to_json(self) -> dict[str, Any]:
        return {
            "statement": self.claim.statement,
            "verdict": self.verdict,
            "basis": self.basis,
            "seeds": self.seeds,
            "evidence": [c.describe() for c in self.comparisons],
            "comparisons": [c.to_json() for c in self.comparisons],
        }


def check_claims(
    results: dict[str, dict[str, Any]], *, budgets: tuple[int, int] | None = None
) -> list[ClaimCheck]:
    """Each claim's verdict on ``results`` (row id → ``results.json`` entry); not evaluated
    when one of its rows is missing, or for an ``equal_budgets`` claim when ``budgets``
    ``(deep RL, RS-GAIL's π_n)`` env steps differ (the pairs are still given). Raises
    ``ValueError`` for entries without per-seed figures."""
    checks = []
    for claim in CLAIMS:
        if any(row not in results for pair in claim.pairs for row in pair):
            checks.append(ClaimCheck(claim, NOT_EVALUATED, ()))
            continue
        comparisons = tuple(_compare(results, better, worse) for better, worse in claim.pairs)
        verdicts = {c.verdict for c in comparisons}
        verdict = NOT_HELD if NOT_HELD in verdicts else HELD if verdicts == {HELD} else INCONCLUSIVE
        seeds = min(int(results[row]["seeds"]) for pair in claim.pairs for row in pair)
        note = ""
        if claim.equal_budgets and budgets is not None and budgets[0] != budgets[1]:
            verdict, note = (
                NOT_EVALUATED,
                (
                    f"unequal budgets: PPO/SAC {budgets[0]:,} env steps, RS-GAIL's π_n up to "
                    f"{budgets[1]:,} (after BC on expert demonstrations); the pairs below only "
                    "show where each stands at its own budget (env_step_curves.png)"
                ),
            )
        checks.append(ClaimCheck(claim, verdict, comparisons, seeds, note))
    return checks


def _compare(results: dict[str, dict[str, Any]], better: str, worse: str) -> Comparison:
    (x, over_x), (y, over_y) = unit_samples(results[better]), unit_samples(results[worse])
    over = EPISODES if EPISODES in (over_x, over_y) else over_x
    if over_x != over_y:  # one row has several seeds, the other one: compare their episodes
        x, y = _episodes(results[better]), _episodes(results[worse])
    paired = len(x) == len(y)
    interval = difference(x, y, over, paired=paired)
    trained = sum(row not in _EXPERTS for row in (better, worse))
    return Comparison(
        better,
        worse,
        float(results[better]["reward_mean"]),
        float(results[worse]["reward_mean"]),
        interval,
        probability_of_improvement(x, y, over),
        margin(interval, trained),
    )


#: Rows of a scripted expert: nothing trained, so no training variance in their means.
_EXPERTS = frozenset(row.id for row in ROWS if not row.trainings)


def _episodes(entry: dict[str, Any]) -> list[float]:
    return [r for seed in entry.get("reward_per_episode") or [] for r in seed]
