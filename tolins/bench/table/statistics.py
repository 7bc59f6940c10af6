"""Interval estimates of the bench's figures, with training seeds as the unit (rliable).

Every policy of the bench is trained once per training seed, and training varies far more
than evaluation does (paper profile, 5 seeds: a row's per-seed mean reward spreads by up
to 2.38, while its 100 evaluation episodes put the mean within about ±0.5). So an
interval is over **training seeds** whenever there are two or more: the samples are the
per-seed means, resampled by rliable's stratified bootstrap
(:func:`rliable.library.get_interval_estimates`, percentile method, :data:`REPS`
replications, 95 %). With one training seed the samples are the evaluation episodes
(``over == "episodes"``), and the interval says nothing about training variance.

Decisions (:func:`sign`): an interval above 0 is positive, below 0 negative, one that
contains 0 undecided; :func:`equivalent` tells an undecided one inside a smallest effect of
interest (the claims' four-valued verdicts, :mod:`tolins.bench.table.claims`). **One-seed
rule**: an interval over episodes decides only when it clears ``±`` :func:`margin`
entirely, 7.0 reward (:data:`ONE_SEED_MARGIN`) for two trained rows. The margin is the
training noise a single seed cannot show: two rows whose per-seed means each spread by
:data:`TRAINING_SPREAD` (the largest std over seeds of a Table 1 row the paper profile
measured, ``reference:paper``: P2.2 2.46 over 6 seeds; P2.1 2.44, C1.2 2.38, C2.2 2.31,
P1.2 2.25) differ by training alone with a std of up to √2 × 2.46 = 3.48, and 2 × 3.48 is
its 95 % bound (one trained row against an expert: 2 × 2.46 = 4.9). The deep-RL rows are
not in it: their seeds learn or do not (R2.1, PPO on the dense reward, spreads by 9.47),
so one seed of them decides nothing; the paper profile trains them on five. So an
episode-level difference is called only when its whole episode-level CI lies beyond what
retraining could plausibly undo; anything smaller (e.g. +0.8 ± 0.6) is inconclusive,
however many standard errors it is.

The resamples are rliable's: those its ``get_interval_estimates`` draws from numpy's
global stream with ``StratifiedBootstrap`` (one table, each figure's runs drawn with
replacement) and ``StratifiedIndependentBootstrap`` (two samples, each drawn on its own),
in the same order, and the interval arch's percentile interval of them; rliable evaluates
a statistic one resample at a time in Python (2 s for a row), here every statistic is
computed on the whole batch of resamples at once (:func:`_batch_estimate`,
:func:`_independent_estimate`), giving rliable's intervals bit for bit (tests compare
them). rliable's metrics ``aggregate_iqm`` and ``probability_of_improvement`` are
:func:`iqm` and :func:`improvement` here (tested equal to rliable's).

Every estimate seeds the global stream with :data:`BOOTSTRAP_SEED` and restores it
afterwards (under a lock), so the same data give the same interval, in any order, and the
caller's global random stream is where it was. Another *thread* drawing from that RNG
meanwhile (pycma's ``ask`` does) would see the seeded stream, so the bench computes
intervals only after its stages have finished.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

CONFIDENCE = 0.95
REPS = 2000
BOOTSTRAP_SEED = 0
SEEDS, EPISODES = "seeds", "episodes"
#: Largest std of a Table 1 row's per-seed mean reward measured on the paper profile
#: (:func:`training_spread` of ``reference:paper``'s Table 1 rows; a test keeps the two equal).
TRAINING_SPREAD = 2.46


def one_seed_spread(trained: int) -> float:
    """The std of one training seed's difference between two rows of which ``trained``
    (0, 1 or 2) are trained: :data:`TRAINING_SPREAD` × √``trained`` reward, the training
    noise an interval over one seed's episodes cannot show."""
    return TRAINING_SPREAD * math.sqrt(trained)


def one_seed_margin(trained: int) -> float:
    """The one-seed rule's margin for a pair with ``trained`` trained rows (0, 1 or 2):
    twice :func:`one_seed_spread`, to one decimal."""
    return round(2 * one_seed_spread(trained), 1)


#: An interval over episodes (one training seed) of two trained rows decides only beyond
#: ± this (reward).
ONE_SEED_MARGIN = one_seed_margin(2)
#: The figures of a row, in the order of results.json.
FIGURES = ("reward", "success", "steps", "collisions")

_LOCK = threading.Lock()
#: The sample pairs :func:`improvement_of_batch` compares at once (a few MB of booleans).
_PAIRS_AT_ONCE = 2**22


@dataclass(frozen=True)
class Interval:
    """A point estimate and its 95 % bootstrap CI over ``n`` samples of kind ``over``."""

    estimate: float
    low: float
    high: float
    over: str
    n: int

    def to_json(self) -> dict[str, Any]:
        return {
            "estimate": self.estimate,
            "ci": [self.low, self.high],
            "over": self.over,
            "n": self.n,
        }

    def format(self, digits: int = 2, signed: bool = False) -> str:
        """``estimate [low, high]``, e.g. ``+1.20 [+0.31, +2.05]``."""
        spec = f"{'+' if signed else ''}.{digits}f"
        return f"{self.estimate:{spec}} [{self.low:{spec}}, {self.high:{spec}}]"


@contextmanager
def _seeded_global_rng() -> Iterator[None]:
    with _LOCK:
        state = np.random.get_state()
        np.random.seed(BOOTSTRAP_SEED)
        try:
            yield
        finally:
            np.random.set_state(state)


def iqm(x: np.ndarray) -> float:
    """The interquartile mean of ``x`` (all its entries): rliable's ``aggregate_iqm``
    (``scipy.stats.trim_mean(x, 0.25)``: sort, drop ⌊n/4⌋ values at each end, average)."""
    return float(iqm_of_batch(np.ravel(np.asarray(x, dtype=float))[None])[0])


def improvement(x: np.ndarray, y: np.ndarray) -> float:
    """P(X > Y) of two samples (ties count half): rliable's ``probability_of_improvement``
    for one task (its Mann-Whitney U / (n_x n_y))."""
    return float(improvement_of_batch(np.ravel(x)[None], np.ravel(y)[None])[0])


def improvement_of_batch(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """:func:`improvement` of each pair of rows of ``x`` and ``y`` (batch × samples), a few
    rows at a time (each compares every sample of x with every one of y)."""
    rows = max(1, _PAIRS_AT_ONCE // (x.shape[1] * y.shape[1]))
    parts = []
    for first in range(0, len(x), rows):
        a, b = x[first : first + rows, :, None], y[first : first + rows, None, :]
        parts.append(np.mean(a > b, axis=(1, 2)) + 0.5 * np.mean(a == b, axis=(1, 2)))
    return np.concatenate(parts)


def iqm_of_batch(x: np.ndarray) -> np.ndarray:
    """:func:`iqm` of each row of ``x`` (batch × samples)."""
    values = np.sort(x, axis=1)
    cut = int(0.25 * x.shape[1])
    return values[:, cut : x.shape[1] - cut].mean(axis=1)


def _batch_estimate(
    scores: np.ndarray, func: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """rliable's point estimate and (2, p) percentile CI of a statistic on ``scores`` (runs
    × figures) as ``get_interval_estimates`` computes them with its ``StratifiedBootstrap``:
    ``func`` maps a batch of tables (batch × runs × figures) to the statistic's p values of
    each (batch × p); the resamples are rliable's (the same draws from the global stream,
    in one call)."""
    with _seeded_global_rng():
        runs = np.random.choice(len(scores), (REPS, *scores.shape), replace=True)
    return func(scores[None])[0], _percentiles(func(scores[runs, np.arange(scores.shape[1])]))


def _independent_estimate(
    samples: Sequence[np.ndarray], func: Callable[..., np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """rliable's point estimate and (2, p) percentile CI of a statistic of independently
    resampled 1-D ``samples``, as ``get_interval_estimates`` computes them with its
    ``StratifiedIndependentBootstrap``: ``func`` maps one batch of resamples per sample
    (batch × its length) to the statistic's p values of each (batch × p); the resamples
    are rliable's (per replication, one draw per sample from the global stream)."""
    sizes = [len(sample) for sample in samples]
    with _seeded_global_rng():
        if len(set(sizes)) == 1:  # draws of one bound: the stream's order in one call
            picks = list(np.random.choice(sizes[0], (REPS, len(sizes), sizes[0])).swapaxes(0, 1))
        else:
            draws = [[np.random.choice(n, n) for n in sizes] for _ in range(REPS)]
            picks = [np.array(column) for column in zip(*draws, strict=True)]
    point = func(*(sample[None] for sample in samples))[0]
    resamples = [sample[pick] for sample, pick in zip(samples, picks, strict=True)]
    return point, _percentiles(func(*resamples))


def _percentiles(values: np.ndarray) -> np.ndarray:
    """The (2, p) 95 % percentile interval of each column of ``values`` (replications ×
    p), as arch's ``conf_int(method="percentile")`` computes it."""
    alpha = (1.0 - CONFIDENCE) / 2
    percentiles = [100 * alpha, 100 * (1.0 - alpha)]
    return np.array([np.percentile(column, percentiles) for column in values.T]).T


def _samples(values: Sequence[float], what: str) -> np.ndarray:
    array = np.asarray(values, dtype=float)
    if array.ndim != 1 or len(array) == 0 or not np.all(np.isfinite(array)):
        raise ValueError(f"{what}: {len(array)} values; allowed: ≥ 1 finite number")
    return array


def row_intervals(values: dict[str, list[list[float]]]) -> dict[str, Any]:
    """The interval keys of a ``results.json`` entry from its episodes' ``values`` (figure →
    one list of episode values per training seed): ``{figure}_ci`` (95 % CI of the mean),
    ``reward_iqm`` and ``reward_iqm_ci`` (IQM of the per-seed means), ``ci_over`` and
    ``ci_n`` (seeds when ≥ 2, else the one seed's episodes)."""
    seeds = values["reward"]
    if not seeds or not all(seeds):
        raise ValueError("no episodes; allowed: ≥ 1 episode per training seed")
    over = SEEDS if len(seeds) > 1 else EPISODES
    if over == SEEDS:
        columns = [[float(np.mean(s)) for s in values[name]] for name in FIGURES]
    else:
        columns = [list(values[name][0]) for name in FIGURES]
    scores = np.asarray(columns, dtype=float).T

    def means_and_iqm(x: np.ndarray) -> np.ndarray:
        return np.concatenate([x.mean(axis=1), iqm_of_batch(x[:, :, 0])[:, None]], axis=1)

    point, interval = _batch_estimate(scores, means_and_iqm)
    entry: dict[str, Any] = {
        f"{name}_ci": [float(interval[0, i]), float(interval[1, i])]
        for i, name in enumerate(FIGURES)
    }
    entry["reward_iqm"] = float(point[-1])
    entry["reward_iqm_ci"] = [float(interval[0, -1]), float(interval[1, -1])]
    entry["ci_over"] = over
    entry["ci_n"] = len(scores)
    return entry


def mean_intervals(values: dict[str, list[list[float]]]) -> dict[str, list[float]]:
    """``{figure}_ci``: the 95 % CI of each figure's mean from its episodes' ``values``
    (figure → one list of episode values per training seed), over the per-seed means with
    ≥ 2 seeds, else over the one seed's episodes (as :func:`row_intervals`)."""
    names = list(values)
    seeds = values[names[0]]
    if len(seeds) > 1:
        columns = [[float(np.mean(s)) for s in values[name]] for name in names]
    else:
        columns = [list(values[name][0]) for name in names]
    _, interval = _batch_estimate(np.asarray(columns, dtype=float).T, lambda x: x.mean(axis=1))
    return {
        f"{name}_ci": [float(interval[0, i]), float(interval[1, i])] for i, name in enumerate(names)
    }


def difference(
    x: Sequence[float], y: Sequence[float], over: str, *, paired: bool = False
) -> Interval:
    """mean(x) − mean(y) with its CI. ``paired`` (equal lengths, sample i of both shares a
    training seed or an evaluation episode's seed): the bootstrap resamples the pairs'
    differences; otherwise x and y are resampled independently (rliable's
    ``StratifiedIndependentBootstrap``)."""
    a, b = _samples(x, "x"), _samples(y, "y")
    if paired:
        if len(a) != len(b):
            raise ValueError(f"paired samples of {len(a)} and {len(b)}; allowed: equal lengths")
        point, interval = _batch_estimate((a - b)[:, None], lambda d: d.mean(axis=1))
    else:
        point, interval = _independent_estimate(
            [a, b], lambda p, q: (p.mean(axis=1) - q.mean(axis=1))[:, None]
        )
    n = len(a) if paired else min(len(a), len(b))
    return Interval(float(point[0]), float(interval[0, 0]), float(interval[1, 0]), over, n)


def probability_of_improvement(x: Sequence[float], y: Sequence[float], over: str) -> Interval:
    """P(X > Y) (:func:`improvement`: a random sample of x beats one of y, ties half) with
    its CI, x and y resampled independently."""
    a, b = _samples(x, "x"), _samples(y, "y")
    point, interval = _independent_estimate(
        [a, b], lambda p, q: improvement_of_batch(p, q)[:, None]
    )
    return Interval(
        float(point[0]), float(interval[0, 0]), float(interval[1, 0]), over, min(len(a), len(b))
    )


def margin(interval: Interval, trained: int = 2) -> float:
    """How far from 0 a difference's ``interval`` must lie to decide: 0 over seeds; over
    episodes (one training seed) :func:`one_seed_margin` of ``trained``, the number of the
    two compared rows that were trained (an expert row has no training variance)."""
    return 0.0 if interval.over == SEEDS else one_seed_margin(trained)


def training_spread(rows: Mapping[str, Mapping[str, Any]]) -> tuple[str, float]:
    """The row of ``rows`` (row id → ``results.json`` entry) whose per-seed mean reward
    spreads most over training seeds, and that std (over seeds, the ± of results.md): on
    ``reference:paper``'s Table 1 rows, :data:`TRAINING_SPREAD`. ``ValueError`` without a
    row of ≥ 2 seeds."""
    spreads = {
        row: float(np.std(entry["reward_per_seed"]))
        for row, entry in rows.items()
        if len(entry.get("reward_per_seed") or ()) > 1
    }
    if not spreads:
        raise ValueError("no row with ≥ 2 training seeds; allowed: results of a multi-seed run")
    row = max(spreads, key=spreads.__getitem__)
    return row, spreads[row]


def sign(interval: Interval, margin_: float = 0.0) -> int:
    """+1 if the CI lies above ``margin_``, −1 below ``-margin_``, 0 if undecided."""
    if interval.low > margin_:
        return 1
    if interval.high < -margin_:
        return -1
    return 0


def equivalent(interval: Interval, delta: float, margin_: float = 0.0) -> bool:
    """Whether the CI lies inside ``[-delta + margin_, delta - margin_]``: the difference is
    smaller than ``delta`` either way (two one-sided tests, each at 2.5 % — the 95 % CI
    inside the bounds; stricter than TOST's usual 90 % CI). With one training seed the
    bounds shrink by the training noise ``margin_``, so no one-seed CI is inside ``±delta``
    when ``margin_ ≥ delta``."""
    bound = delta - margin_
    return bound > 0 and -bound <= interval.low and interval.high <= bound


def seeds_to_decide(estimate: float, spread: float, delta: float) -> int:
    """The training seeds at which a difference of ``estimate`` with a std ``spread`` over
    seeds (of a seed's difference) would be decided: its 95 % CI (normal approximation of
    the bootstrap's, ``± 1.96 · spread / √n``) narrower than ``|estimate|`` (held or did
    not hold) or than ``delta − |estimate|`` (no practical difference); at least 2."""
    reach = max(abs(estimate), delta - abs(estimate))
    if spread <= 0:
        return 2
    return max(2, math.ceil((_Z * spread / reach) ** 2))


#: The 97.5 % quantile of the normal distribution (a 95 % two-sided interval).
_Z = 1.959963984540054


def unit_samples(entry: dict[str, Any], figure: str = "reward") -> tuple[np.ndarray, str]:
    """The samples of a ``results.json`` entry's ``figure`` on the unit, and which unit:
    the per-seed means (``{figure}_per_seed``) with ≥ 2 training seeds, else the one seed's
    episodes (``reward_per_episode``, reward only)."""
    per_seed = entry.get(f"{figure}_per_seed")
    if per_seed is None:
        raise ValueError(
            f"no {figure}_per_seed in the entry (a results.json of tolins < 0.3); "
            "allowed: entries written by tolins bench ≥ 0.3 (re-run it to re-report)"
        )
    if len(per_seed) > 1:
        return _samples(per_seed, f"{figure}_per_seed"), SEEDS
    if figure != "reward":
        raise ValueError(f"{figure}: one training seed and no episodes; allowed: reward")
    episodes = entry.get("reward_per_episode") or [[]]
    return _samples(episodes[0], "reward_per_episode"), EPISODES
