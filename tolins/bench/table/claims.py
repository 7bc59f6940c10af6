"""The paper's claims, checked against a run's ``results.json`` with interval estimates.

Each claim is a set of pairs ``(better, worse)`` of rows. A pair's evidence is the
difference of mean reward with its 95 % stratified-bootstrap CI and rliable's probability
of improvement P(better > worse), both over training seeds (the unit;
:mod:`tolins.bench.table.statistics`). Within one run the rows share training seeds and
evaluation episodes (seed ``s`` of every row starts from the same initial poses, and π_φ
of seed ``s`` is trained on π_n of seed ``s``), so the difference is *paired*: the
bootstrap resamples the per-seed differences.

Verdicts are four-valued, against each claim's smallest effect of interest ``δ``
(:attr:`Claim.delta`, written down before the run: docs/results.md). A pair *held* when
its CI lies above 0, *did not hold* when it lies below, shows *no practical difference*
when its CI lies inside ``[-δ, +δ]`` (an equivalence test over training seeds, TOST-style:
:func:`~tolins.bench.table.statistics.equivalent`), and is *inconclusive* otherwise; an
undecided pair states the training seeds that would decide it at the spread observed
(:func:`~tolins.bench.table.statistics.seeds_to_decide`). With one training seed the CI is
over evaluation episodes and decides only beyond ± :func:`~tolins.bench.table.statistics.margin`
(the training noise it cannot see, :func:`~tolins.bench.table.statistics.one_seed_margin`),
which is wider than ``δ``: one seed never shows equivalence. A claim is the conjunction of
its pairs: it did not hold when any pair did not, shows no practical difference when,
otherwise, any pair does (the claim cannot hold by ``δ`` there), is inconclusive when,
otherwise, any pair is, and held when every pair held; *not evaluated* when a row is
missing.

Each pair also states its **head-room**: how far the worse row's reward lies below
:func:`~tolins.envs.reward.sparse_return_ceiling`, the most any policy can expect, and the
same for the paper's figures where the paper has the row: a claim against a demonstrator
near the ceiling (ours) has less room to hold than against the paper's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from tolins.bench.table.rows import PAPER, ROWS
from tolins.bench.table.statistics import (
    EPISODES,
    Interval,
    difference,
    equivalent,
    margin,
    one_seed_spread,
    probability_of_improvement,
    seeds_to_decide,
    sign,
    unit_samples,
)
from tolins.envs.reward import sparse_return_ceiling

HELD, NOT_HELD, NOT_EVALUATED = "held", "did not hold", "not evaluated"
INCONCLUSIVE, NO_DIFFERENCE = "inconclusive", "no practical difference"
#: A claim's verdict from its pairs': the first of these any pair has, else held.
_PRECEDENCE = (NOT_HELD, NO_DIFFERENCE, INCONCLUSIVE)
ONE_SEED = "one training seed: training variance not measured"
_VERDICTS = {1: HELD, -1: NOT_HELD}
#: The smallest effect of interest of every claim (reward): one control step of 40 saved
#: on a successful insertion (c / k_max = 100 / 40), or 2.5 collisions.
SMALLEST_EFFECT = 2.5
#: The most sparse return a policy can expect on the bench's start poses (26.72).
CEILING = sparse_return_ceiling()


@dataclass(frozen=True)
class Claim:
    """A claim: in every pair ``(better, worse)`` the first row has the higher mean reward.

    ``equal_budgets``: the claim is about equal env-step budgets (RS-GAIL against deep RL),
    so it is not evaluated on a profile that gives the two sides different budgets.
    ``delta``: its smallest effect of interest (reward): a difference inside ``±delta`` is
    no practical difference.
    """

    name: str
    statement: str
    pairs: tuple[tuple[str, str], ...]
    equal_budgets: bool = False
    delta: float = SMALLEST_EFFECT


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
    its 95 % CI; ``margin``: the one-seed rule's; ``delta``: the claim's smallest effect of
    interest; ``spread``: the std of one training seed's difference (measured over seeds,
    else the training noise one seed cannot show; ``None`` for two expert rows)."""

    better: str
    worse: str
    better_reward: float
    worse_reward: float
    difference: Interval
    improvement: Interval
    margin: float = 0.0
    delta: float = SMALLEST_EFFECT
    spread: float | None = None

    @property
    def verdict(self) -> str:
        """:data:`HELD` or :data:`NOT_HELD` (the CI beyond ``±margin``), else
        :data:`NO_DIFFERENCE` (inside ``±(delta − margin)``), else :data:`INCONCLUSIVE`."""
        decided = sign(self.difference, self.margin)
        if decided:
            return _VERDICTS[decided]
        if equivalent(self.difference, self.delta, self.margin):
            return NO_DIFFERENCE
        return INCONCLUSIVE

    @property
    def seeds_to_decide(self) -> int | None:
        """Training seeds that would decide an inconclusive pair at the observed spread."""
        if self.verdict != INCONCLUSIVE or self.spread is None:
            return None
        return seeds_to_decide(self.difference.estimate, self.spread, self.delta)

    @property
    def headroom(self) -> float:
        """How far the worse row's reward lies below :data:`CEILING`."""
        return CEILING - self.worse_reward

    @property
    def paper_headroom(self) -> float | None:
        """The same for the paper's figure of the worse row, if the paper has it."""
        paper = PAPER.get(self.worse)
        return None if paper is None else CEILING - paper["reward"][0]

    def describe(self) -> str:
        beyond = f" (decisive beyond ±{self.margin:.1f})" if self.margin else ""
        seeds = self.seeds_to_decide
        needs = f", {seeds} seeds would decide" if seeds is not None else ""
        room = f"; head-room {self.headroom:.2f}"
        if self.paper_headroom is not None:
            room += f" (paper's: {self.paper_headroom:.2f})"
        return (
            f"{self.better} {self.better_reward:.2f} vs {self.worse} {self.worse_reward:.2f}: "
            f"{self.difference.format(signed=True)}{beyond}, "
            f"P({self.better} > {self.worse}) {self.improvement.format()}: "
            f"{self.verdict}{needs}{room}"
        )

    def to_json(self) -> dict[str, Any]:
        return {
            "better": self.better,
            "worse": self.worse,
            "difference": self.difference.to_json(),
            "probability_of_improvement": self.improvement.to_json(),
            "margin": self.margin,
            "delta": self.delta,
            "spread": self.spread,
            "verdict": self.verdict,
            "seeds_to_decide": self.seeds_to_decide,
            "headroom": self.headroom,
            "paper_headroom": self.paper_headroom,
        }


@dataclass(frozen=True)
class ClaimCheck:
    """A claim's verdict (:data:`HELD`, :data:`NOT_HELD`, :data:`NO_DIFFERENCE`,
    :data:`INCONCLUSIVE`, :data:`NOT_EVALUATED`), its pairs and what the intervals are over."""

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

    @property
    def seeds_to_decide(self) -> int | None:
        """Training seeds that would decide every inconclusive pair (``None``: none is)."""
        needed = [c.seeds_to_decide for c in self.comparisons if c.seeds_to_decide is not None]
        return max(needed) if needed and self.verdict == INCONCLUSIVE else None

    def to_json(self) -> dict[str, Any]:
        return {
            "statement": self.claim.statement,
            "verdict": self.verdict,
            "basis": self.basis,
            "seeds": self.seeds,
            "delta": self.claim.delta,
            "seeds_to_decide": self.seeds_to_decide,
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
        comparisons = tuple(
            _compare(results, better, worse, claim.delta) for better, worse in claim.pairs
        )
        verdicts = {c.verdict for c in comparisons}
        verdict = next((v for v in _PRECEDENCE if v in verdicts), HELD)
        seeds = min(int(results[row]["seeds"]) for pair in claim.pairs for row in pair)
        note = ""
        if claim.equal_budgets and budgets is not None and budgets[0] != budgets[1]:
            verdict, note = (
                NOT_EVALUATED,
                (
                    f"unequal budgets: PPO/SAC {budgets[0]:,} env steps, RS-GAIL's π_n up to "
                    f"{budgets[1]:,} (after BC on expert demonstrations); the pairs below only "
                    "show where each stands at its own budget (their curves: the deep-RL section)"
                ),
            )
        checks.append(ClaimCheck(claim, verdict, comparisons, seeds, note))
    return checks


def _compare(
    results: dict[str, dict[str, Any]], better: str, worse: str, delta: float
) -> Comparison:
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
        delta,
        _spread(np.asarray(x, dtype=float), np.asarray(y, dtype=float), over, paired, trained),
    )


def _spread(x: np.ndarray, y: np.ndarray, over: str, paired: bool, trained: int) -> float | None:
    """The std of one training seed's difference: of the paired per-seed differences, of
    the two rows' per-seed means, or (one seed) the training noise it cannot show."""
    if over == EPISODES:
        return one_seed_spread(trained) if trained else None
    if paired:
        return float(np.std(x - y, ddof=1))
    return float(math.sqrt(np.var(x, ddof=1) + np.var(y, ddof=1)))


#: Rows of a scripted expert: nothing trained, so no training variance in their means.
_EXPERTS = frozenset(row.id for row in ROWS if not row.trainings)


def _episodes(entry: dict[str, Any]) -> list[float]:
    return [r for seed in entry.get("reward_per_episode") or [] for r in seed]
