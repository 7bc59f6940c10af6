"""Interval estimates (rliable) and the three-valued claims on synthetic data with known
answers."""

from __future__ import annotations

import copy
import functools
import math

import numpy as np
import pytest

from tolins.bench.table.claims import (
    CEILING,
    CLAIMS,
    HELD,
    INCONCLUSIVE,
    NO_DIFFERENCE,
    NOT_EVALUATED,
    NOT_HELD,
    ONE_SEED,
    SMALLEST_EFFECT,
    check_claims,
)
from tolins.bench.table.results import row_entry
from tolins.bench.table.rows import ALL_ROWS, PAPER
from tolins.bench.table.statistics import (
    EPISODES,
    ONE_SEED_MARGIN,
    SEEDS,
    TRAINING_SPREAD,
    difference,
    improvement,
    iqm,
    margin,
    probability_of_improvement,
    row_intervals,
    sign,
    training_spread,
    unit_samples,
)
from tolins.rollouts.episodes import Episode

BY_ID = {row.id: row for row in ALL_ROWS}
#: The paper's four claims (other claims may compare rows beyond Table 1).
PAPER_CLAIMS = ("rs_gail", "tolerance_guided", "inference", "polygon_transfer")


def _entry(row_id: str, per_seed: list[list[float]]) -> dict:
    """The results.json entry of ``row_id`` whose seed s has episodes of these rewards."""
    key = (row_id, tuple(tuple(seed) for seed in per_seed))
    return copy.deepcopy(_cached_entry(key))


@functools.cache
def _cached_entry(key: tuple) -> dict:  # the bootstraps of 15 rows take seconds
    row_id, per_seed = key
    episodes = [[Episode(float(r), True, 30, 0) for r in seed] for seed in per_seed]
    return row_entry(BY_ID[row_id], episodes)


def _seeds(means: list[float], episodes: int = 4, spread: float = 1.0) -> list[list[float]]:
    """Per-seed episode rewards with exactly these per-seed means."""
    offsets = np.linspace(-spread, spread, episodes)
    return [list(mean + offsets) for mean in means]


# --- intervals ------------------------------------------------------------------------------


def test_disjoint_seeds_are_positive_identical_undecided_reversed_negative():
    better, worse = [10.0, 11.0, 12.0, 10.5, 11.5], [5.0, 6.0, 5.5, 6.5, 4.5]
    assert sign(difference(better, worse, SEEDS)) == 1
    assert sign(difference(worse, better, SEEDS)) == -1
    same = difference(better, better, SEEDS)
    assert same.estimate == 0 and same.low < 0 < same.high  # resampled independently
    assert sign(same) == 0
    paired = difference(better, better, SEEDS, paired=True)
    assert (paired.low, paired.high) == (0.0, 0.0) and sign(paired) == 0


def test_three_seeds_give_the_range_of_the_per_seed_differences():
    # The percentile bootstrap of 3 samples: all three drawn equal has probability
    # 1/27 > 2.5 %, so the 95 % CI runs from the smallest to the largest difference.
    interval = difference([3.0, 1.0, 8.0], [1.0, 1.5, 2.0], SEEDS, paired=True)
    assert interval.estimate == pytest.approx(np.mean([2.0, -0.5, 6.0]))
    assert (interval.low, interval.high) == pytest.approx((-0.5, 6.0))
    assert sign(interval) == 0  # one seed of three went the other way
    held = difference([3.0, 2.0, 8.0], [1.0, 1.5, 2.0], SEEDS, paired=True)
    assert held.low == pytest.approx(0.5) and sign(held) == 1


def test_the_ci_of_a_mean_matches_normal_theory():
    x = np.random.default_rng(7).normal(0.0, 1.0, 400)
    interval = difference(x, np.zeros(400), EPISODES, paired=True)
    half_width = 1.96 * x.std() / np.sqrt(len(x))
    assert interval.low == pytest.approx(x.mean() - half_width, abs=0.2 * half_width)
    assert interval.high == pytest.approx(x.mean() + half_width, abs=0.2 * half_width)


def test_probability_of_improvement_known_answers():
    x, y = [5.0, 6.0, 7.0], [1.0, 2.0, 3.0]
    assert probability_of_improvement(x, y, SEEDS).estimate == 1.0
    assert probability_of_improvement(y, x, SEEDS).estimate == 0.0
    assert probability_of_improvement(x, x, SEEDS).estimate == 0.5
    half = probability_of_improvement([1.0, 3.0], [2.0, 2.0], SEEDS)
    assert half.estimate == 0.5 and half.low == 0.0 and half.high == 1.0


@pytest.mark.parametrize("n", [1, 2, 3, 5, 8, 100])
def test_iqm_and_improvement_are_rliables_metrics(n):
    from rliable import metrics

    rng = np.random.default_rng(n)
    x, y = rng.integers(0, 4, (n, 1)).astype(float), rng.normal(1.5, 1.0, (n + 3, 1))
    assert iqm(y) == pytest.approx(metrics.aggregate_iqm(y), abs=1e-12)
    assert improvement(x, y) == pytest.approx(metrics.probability_of_improvement(x, y))
    assert improvement(x, x) == 0.5 == metrics.probability_of_improvement(x, x)
    ties = rng.integers(0, 3, (n, 1)).astype(float)  # many ties: they count half
    assert improvement(x, ties) == pytest.approx(metrics.probability_of_improvement(x, ties))


def test_row_intervals_over_seeds_iqm_trims_a_quartile_each_side():
    values = {name: [[v] * 3 for v in (1.0, 2.0, 3.0, 4.0, 100.0)] for name in ("reward",)}
    values |= {name: [[1.0] * 3] * 5 for name in ("success", "steps", "collisions")}
    entry = row_intervals(values)
    assert (entry["ci_over"], entry["ci_n"]) == ("seeds", 5)
    assert entry["reward_iqm"] == pytest.approx(3.0)  # mean of 2, 3, 4
    low, high = entry["reward_ci"]
    assert low < 22.0 < high  # the mean, pulled up by the outlying seed
    assert entry["success_ci"] == [1.0, 1.0]


def test_one_seed_intervals_are_over_its_episodes():
    entry = _entry("C2.1", [[10.0, 12.0, 14.0, 16.0]])
    assert (entry["ci_over"], entry["ci_n"]) == ("episodes", 4)
    assert entry["reward_per_seed"] == [13.0]
    assert entry["reward_per_episode"] == [[10.0, 12.0, 14.0, 16.0]]
    assert entry["reward_ci"][0] < 13.0 < entry["reward_ci"][1]
    samples, over = unit_samples(entry)
    assert over == EPISODES and list(samples) == [10.0, 12.0, 14.0, 16.0]
    several = _entry("C2.1", _seeds([10.0, 12.0]))
    samples, over = unit_samples(several)
    assert over == SEEDS and list(samples) == pytest.approx([10.0, 12.0])


def test_intervals_are_reproducible_and_leave_numpys_global_rng_alone():
    np.random.seed(1234)
    expected = np.random.random()
    np.random.seed(1234)
    x, y = [1.0, 4.0, 2.0, 8.0, 5.0], [0.0, 1.0, 3.0, 2.0, 2.5]
    first = difference(x, y, SEEDS)
    assert np.random.random() == expected  # the bootstrap did not move the global stream
    assert difference(x, y, SEEDS) == first
    assert probability_of_improvement(x, y, SEEDS) == probability_of_improvement(x, y, SEEDS)


def test_the_one_seed_margin_counts_the_trained_rows():
    over_episodes = difference([1.0, 2.0], [0.0, 1.0], EPISODES)
    assert margin(over_episodes) == ONE_SEED_MARGIN == 7.0  # 2 × √2 × 2.46
    assert margin(over_episodes, trained=1) == 4.9
    assert margin(over_episodes, trained=0) == 0.0
    assert margin(difference([1.0, 2.0], [0.0, 1.0], SEEDS)) == 0.0


def test_the_training_spread_is_the_one_the_paper_reference_measured():
    import json

    from tolins.bench.reference import reference_path

    rows = json.loads(reference_path("paper").read_text())["rows"]
    row, spread = training_spread({row_id: rows[row_id] for row_id in PAPER})
    assert rows[row]["seeds"] >= 5
    assert round(spread, 2) == TRAINING_SPREAD, (row, spread)
    assert training_spread(
        {"A": {"reward_per_seed": [1.0, 3.0]}, "B": {"reward_per_seed": [0.0, 1.0]}}
    ) == ("A", 1.0)
    with pytest.raises(ValueError, match="≥ 2 training seeds"):
        training_spread({"A": {"reward_per_seed": [1.0]}})


def test_bad_samples_and_old_entries_are_refused():
    with pytest.raises(ValueError, match="allowed: ≥ 1 finite number"):
        difference([], [1.0], SEEDS)
    with pytest.raises(ValueError, match="allowed: equal lengths"):
        difference([1.0, 2.0], [1.0], SEEDS, paired=True)
    old = {"reward_mean": 1.0, "reward_std": 0.1, "episodes": 100, "seeds": 1}
    with pytest.raises(ValueError, match=r"tolins < 0\.3"):
        unit_samples(old)


# --- claims ---------------------------------------------------------------------------------


def _table(means: dict[str, list[float]], episodes: int = 4) -> dict[str, dict]:
    return {row_id: _entry(row_id, _seeds(m, episodes)) for row_id, m in means.items()}


def _paper_table(seeds: int = 5) -> dict[str, list[float]]:
    """Every row at the paper's mean, its seeds spread by ± the paper's std."""
    offsets = np.linspace(-1.0, 1.0, seeds)
    return {r: list(PAPER[r]["reward"][0] + PAPER[r]["reward"][1] * offsets) for r in PAPER}


def test_every_claim_holds_on_the_papers_own_table_with_five_seeds():
    checks = {c.claim.name: c for c in check_claims(_table(_paper_table()))}
    assert [checks[name].verdict for name in PAPER_CLAIMS] == [HELD] * 4
    polygon = checks["polygon_transfer"]
    (pair,) = polygon.comparisons
    assert pair.difference.over == SEEDS and pair.difference.n == 5
    assert pair.difference.estimate == pytest.approx(16.01 - 15.82)
    assert pair.improvement.estimate > 0.5
    assert polygon.basis == "5 training seeds; 95 % CIs over seeds"
    assert pair.describe().startswith("P2.2 16.01 vs P2.1 15.82: +0.19 [")
    assert polygon.to_json()["comparisons"][0]["verdict"] == HELD


def test_a_half_standard_error_difference_inside_delta_is_no_practical_difference():
    # P2.2 vs P2.1 at +0.23 ± 0.50 is not "held", but it bounds the effect well inside δ.
    means = _paper_table(3)
    means["P2.1"] = [21.0, 21.5, 21.8]
    means["P2.2"] = [21.9, 21.0, 22.1]  # per-seed differences +0.9, -0.5, +0.3
    check = {c.claim.name: c for c in check_claims(_table(means))}["polygon_transfer"]
    (pair,) = check.comparisons
    assert pair.difference.estimate == pytest.approx(0.7 / 3)
    assert -SMALLEST_EFFECT < pair.difference.low < 0 < pair.difference.high < SMALLEST_EFFECT
    assert check.verdict == pair.verdict == NO_DIFFERENCE
    assert pair.seeds_to_decide is None and check.to_json()["delta"] == SMALLEST_EFFECT


def test_an_undecided_pair_wider_than_delta_says_how_many_seeds_would_decide():
    means = _paper_table(3)
    means["P2.1"] = [21.0, 21.0, 21.0]
    means["P2.2"] = [25.0, 17.0, 22.0]  # per-seed differences +4, -4, +1: mean +1/3
    (pair,) = {c.claim.name: c for c in check_claims(_table(means))}["polygon_transfer"].comparisons
    assert pair.verdict == INCONCLUSIVE and pair.difference.high > SMALLEST_EFFECT
    spread = float(np.std([4.0, -4.0, 1.0], ddof=1))
    assert pair.spread == pytest.approx(spread)
    # Decided once 1.96 · spread / √n < δ − |mean| (the larger reach of the two):
    needed = math.ceil((1.959964 * spread / (SMALLEST_EFFECT - 1 / 3)) ** 2)
    assert pair.seeds_to_decide == needed == 14
    assert f"{needed} seeds would decide" in pair.describe()
    assert pair.to_json()["seeds_to_decide"] == needed


def test_a_claim_shows_no_practical_difference_when_a_pair_does_and_none_failed():
    means = _paper_table()
    means["C1.3"] = [m + 10 for m in means["C1.2"]]  # beats BC by far...
    means["C1.1"] = [m - 0.1 + 0.05 * i for i, m in enumerate(means["C1.3"])]  # ...ties the expert
    checks = {c.claim.name: c for c in check_claims(_table(means))}
    verdicts = [c.verdict for c in checks["rs_gail"].comparisons]
    assert verdicts[:2] == [NO_DIFFERENCE, HELD]
    assert checks["rs_gail"].verdict == NO_DIFFERENCE


def test_each_pair_states_its_head_room_to_the_ceiling_and_the_papers():
    pair = next(c for c in check_claims(_table(_paper_table())) if c.claim.name == "rs_gail")
    expert = pair.comparisons[0]  # C1.3 against the efficient expert C1.1
    assert expert.worse == "C1.1"
    assert expert.headroom == pytest.approx(CEILING - expert.worse_reward)
    assert expert.paper_headroom == pytest.approx(CEILING - PAPER["C1.1"]["reward"][0])
    assert f"head-room {expert.headroom:.2f} (paper's: {expert.paper_headroom:.2f})" in (
        expert.describe()
    )


@pytest.mark.parametrize(
    ("row_id", "claim"),
    [
        ("C1.2", "rs_gail"),
        ("C3.1", "tolerance_guided"),
        ("C4.1", "inference"),
        ("P2.1", "polygon_transfer"),
    ],
)
def test_a_claim_did_not_hold_when_its_baseline_wins_on_every_seed(row_id, claim):
    means = _paper_table()
    means[row_id] = [30.0 + i for i in range(5)]
    verdicts = {c.claim.name: c.verdict for c in check_claims(_table(means))}
    assert verdicts[claim] == NOT_HELD
    assert [verdicts[name] for name in PAPER_CLAIMS if name != claim] == [HELD] * 3


def test_a_claim_with_one_undecided_pair_is_inconclusive_and_a_missing_row_not_evaluated():
    means = _paper_table()
    means["C1.3"] = [m + 10 for m in means["C1.1"]]  # beats the expert and BC...
    for seed in (0, 1):  # ...except on two seeds of five, against the expert
        means["C1.3"][seed] = means["C1.1"][seed] - 5
    del means["P2.2"]
    checks = {c.claim.name: c for c in check_claims(_table(means))}
    assert [c.verdict for c in checks["rs_gail"].comparisons][:2] == [INCONCLUSIVE, HELD]
    assert checks["rs_gail"].verdict == INCONCLUSIVE
    assert checks["polygon_transfer"].verdict == NOT_EVALUATED
    assert checks["polygon_transfer"].to_json()["evidence"] == []


def test_one_training_seed_decides_only_beyond_the_training_noise():
    def verdict(better: float, worse: float, rows=("C3.2", "C3.1")) -> tuple[str, object]:
        # 40 episodes per row within ±1 of its mean: the episode-level CI is narrow
        claim = next(c for c in CLAIMS if rows in c.pairs)
        means = {r: _paper_table(1)[r] for pair in claim.pairs for r in pair}
        means[rows[0]], means[rows[1]] = [better], [worse]
        check = next(c for c in check_claims(_table(means, 40)) if c.claim == claim)
        pair = next(p for p in check.comparisons if (p.better, p.worse) == rows)
        return pair.verdict, check

    small, check = verdict(20.8, 20.0)  # +0.8 at many standard errors: not evidence
    assert small == INCONCLUSIVE  # nor equivalence: the training noise (±7.0) exceeds δ
    # The seeds that would decide it at the training noise of two rows, √2 × 2.46:
    spread = TRAINING_SPREAD * math.sqrt(2)
    assert check.comparisons[0].seeds_to_decide == math.ceil(
        (1.959964 * spread / (SMALLEST_EFFECT - 0.8)) ** 2
    )
    assert check.basis.startswith(ONE_SEED)
    assert check.comparisons[0].difference.over == EPISODES
    assert check.comparisons[0].margin == 7.0
    assert verdict(32.0, 20.0)[0] == HELD
    assert verdict(20.0, 32.0)[0] == NOT_HELD
    assert verdict(26.0, 20.0)[0] == INCONCLUSIVE  # +6: within two rows' training noise
    # π_n against an expert: one trained row, margin 4.9
    assert verdict(26.0, 20.0, ("C2.3", "C2.1"))[0] == HELD
    assert verdict(24.0, 20.0, ("C2.3", "C2.1"))[0] == INCONCLUSIVE


def test_claims_refuse_results_without_per_seed_figures():
    old = {r: {"reward_mean": 1.0, "reward_std": 0.1, "episodes": 100, "seeds": 1} for r in PAPER}
    with pytest.raises(ValueError, match="reward_per_seed"):
        check_claims(old)


def test_the_deep_rl_claim_is_not_evaluated_at_unequal_budgets():
    means = {row: [20.0, 21.0, 22.0] for row in ("C2.3", "P1.3")}
    means |= {row: [0.0, 0.5, 1.0] for row in ("R1.1", "R1.2", "R1.3", "R1.4")}
    table = _table(means)

    def deep_rl(**kwargs):
        return {c.claim.name: c for c in check_claims(table, **kwargs)}["rs_gail_vs_deep_rl"]

    unequal = deep_rl(budgets=(3_000, 28_800))
    assert unequal.verdict == "not evaluated" and "unequal budgets" in unequal.basis
    assert len(unequal.comparisons) == 4  # the pairs are still shown
    assert deep_rl(budgets=(288_000, 288_000)).verdict == "held"
    assert deep_rl().verdict == "held"


@pytest.mark.parametrize("n", [1, 3, 8, 20, 100])
def test_batched_intervals_are_rliables_bit_for_bit(n):
    """Row intervals, plain means and paired differences, computed on the whole batch of
    resamples at once, equal rliable's ``get_interval_estimates`` evaluating one resample
    at a time (the same seed, the same draws)."""
    from rliable import library

    from tolins.bench.table import statistics

    def rliable(scores, func):
        with statistics._seeded_global_rng():
            point, interval = library.get_interval_estimates(
                {"x": scores}, func, reps=statistics.REPS, confidence_interval_size=0.95
            )
        return point["x"], interval["x"]

    rng = np.random.default_rng(n)
    values = {
        "reward": [list(rng.normal(20.0, 6.0, n))],
        "success": [list(rng.integers(0, 2, n).astype(float))],
        "steps": [list(rng.integers(20, 41, n).astype(float))],
        "collisions": [list(rng.integers(0, 5, n).astype(float))],
    }
    entry = row_intervals(values)
    scores = np.array([values[name][0] for name in statistics.FIGURES]).T
    point, interval = rliable(scores, lambda x: np.concatenate([x.mean(0), [iqm(x[:, 0])]]))
    for i, name in enumerate(statistics.FIGURES):
        assert entry[f"{name}_ci"] == list(interval[:, i]), name
    assert (entry["reward_iqm"], entry["reward_iqm_ci"]) == (point[-1], list(interval[:, -1]))
    a, b = scores[:, 0], scores[:, 2]
    paired = difference(a, b, EPISODES, paired=True)
    point, interval = rliable((a - b)[:, None], lambda d: np.array([d.mean()]))
    assert (paired.estimate, paired.low, paired.high) == (point[0], *interval[:, 0])
    for c in (b, rng.normal(18.0, 6.0, n + 2)):  # resampled independently: any lengths
        unpaired = difference(a, c, EPISODES)
        pair = [a[:, None], c[:, None]]
        point, interval = rliable(pair, lambda p, q: np.array([p.mean() - q.mean()]))
        assert (unpaired.estimate, unpaired.low, unpaired.high) == (point[0], *interval[:, 0])
        better = probability_of_improvement(a, c, EPISODES)
        point, interval = rliable(pair, lambda p, q: np.array([improvement(p, q)]))
        assert (better.estimate, better.low, better.high) == (point[0], *interval[:, 0])
