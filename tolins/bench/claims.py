"""The paper's four claims, checked against a run's ``results.json``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tolins.bench.results import standard_error

HELD, NOT_HELD, NOT_EVALUATED = "held", "did not hold", "not evaluated"


@dataclass(frozen=True)
class Claim:
    """A claim: in every pair ``(better, worse)`` the first row has the higher mean reward."""

    name: str
    statement: str
    pairs: tuple[tuple[str, str], ...]


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
)


@dataclass(frozen=True)
class Comparison:
    """One pair of rows: reward difference and its standard error."""

    better: str
    worse: str
    better_reward: float
    worse_reward: float
    difference: float
    standard_error: float

    @property
    def held(self) -> bool:
        return self.difference > 0

    def describe(self) -> str:
        text = (
            f"{self.better} {self.better_reward:.2f} vs {self.worse} {self.worse_reward:.2f}: "
            f"{self.difference:+.2f} ± {self.standard_error:.2f}"
        )
        if self.standard_error > 0:
            text += f" ({self.difference / self.standard_error:+.1f} s.e.)"
        return text


@dataclass(frozen=True)
class ClaimCheck:
    """A claim's verdict (:data:`HELD`, :data:`NOT_HELD`, :data:`NOT_EVALUATED`) and numbers."""

    claim: Claim
    verdict: str
    comparisons: tuple[Comparison, ...]

    def to_json(self) -> dict[str, Any]:
        return {
            "statement": self.claim.statement,
            "verdict": self.verdict,
            "evidence": [c.describe() for c in self.comparisons],
        }


def check_claims(results: dict[str, dict[str, Any]]) -> list[ClaimCheck]:
    """Each claim's verdict on ``results`` (row id → entry with ``reward_mean``, ``reward_std``,
    ``episodes``, ``seeds``): held iff the first row's mean reward is higher in every pair;
    not evaluated when a row is missing."""
    checks = []
    for claim in CLAIMS:
        if any(row not in results for pair in claim.pairs for row in pair):
            checks.append(ClaimCheck(claim, NOT_EVALUATED, ()))
            continue
        comparisons = tuple(_compare(results, better, worse) for better, worse in claim.pairs)
        verdict = HELD if all(c.held for c in comparisons) else NOT_HELD
        checks.append(ClaimCheck(claim, verdict, comparisons))
    return checks


def _compare(results: dict[str, dict[str, Any]], better: str, worse: str) -> Comparison:
    a, b = results[better], results[worse]
    error = float(np.hypot(standard_error(a), standard_error(b)))
    difference = float(a["reward_mean"] - b["reward_mean"])
    return Comparison(better, worse, a["reward_mean"], b["reward_mean"], difference, error)
