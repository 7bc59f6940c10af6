"""The next insertion goal: CMA-ES on the expected success under the posterior.

The paper's objective for attempt ``m + 1`` at goal ``s̄* = [x*, y*, θ*]``::

    g_{m+1}(s̄*) = E[I_{m+1} | I_1..m, s̄_1..m, s̄*]
                = ∫ 1[s̄* ∈ T(ε)] p(ε | I_1..m, s̄_1..m) dε  ≈  Σ_n w_n 1[s̄* ∈ T(ε_n)]

and with measured poses ``g′_{m+1} = ∫ g_{m+1} p(s̄_1..m | ŝ_1..m) ds̄_1..m``, which the
posterior's weights already integrate (:mod:`.posterior`). The search starts CMA-ES
(pycma) at the best of the nominal goal and the samples' centre goals
(:func:`centre_goals`) and keeps the best goal evaluated.
"""

from __future__ import annotations

import dataclasses
import threading
from dataclasses import dataclass

import numpy as np

from tolins.geometry.specs import CircularSocket
from tolins.inference.history import History
from tolins.inference.posterior import (
    DefectModel,
    Posterior,
    sample_defect_posterior,
    sample_posterior,
)

#: Below this best expected success the workpiece is recommended for discarding.
DISCARD_THRESHOLD = 0.02
_CANDIDATES = 128
#: Held while a goal search draws from numpy's global RNG (pycma's).
_GLOBAL_RNG = threading.Lock()


@dataclass(frozen=True)
class GoalResult:
    """The goal of the next attempt.

    Attributes:
        goal: ``[x*, y*, θ*]`` (mm, rad).
        expected_success: ``g_{m+1}`` at ``goal`` (0 when the history is unexplained).
        discard: ``expected_success < threshold`` (or the history is unexplained).
        evaluations: Goals whose ``g`` was evaluated.
        not_insertable: The defect model's verdict (:func:`next_goal` with ``model``): no
            goal is expected to insert (best ``g`` below ``not_insertable_below``, e.g. the
            posterior's mass on a blocked hole); the adaptive loop stops. Always False in
            the bent-pin model.
        blocked: Posterior probability of a blocked hole (0 in the bent-pin model).
    """

    goal: np.ndarray
    expected_success: float
    discard: bool
    evaluations: int
    not_insertable: bool = False
    blocked: float = 0.0


def expected_success(spec: CircularSocket, posterior: Posterior, goals: object) -> np.ndarray:
    """``g(s̄*) = Σ_n w_n 1[s̄* ∈ T(ε_n)]`` for goals ``(G, 3)``, vectorised over samples."""
    goals = np.asarray(goals, dtype=float).reshape(-1, 3)
    live = posterior.weights > 0
    if posterior.burrs is None:
        return posterior.weights[live] @ inside_matrix(spec, posterior.offsets[live], goals)
    inside = inside_matrix(spec, posterior.offsets[live], goals, posterior.burrs[live])
    return (1.0 - posterior.blocked) * (posterior.weights[live] @ inside)


def inside_matrix(
    spec: CircularSocket, offsets: np.ndarray, goals: np.ndarray, burrs: np.ndarray | None = None
) -> np.ndarray:
    """``1[goal_g ∈ T(ε_n)]`` ``(N, G)``, one pin at a time; equals ``pins_inside(...).all(-1)``.

    ``burrs`` ``(N, n_pins)``: each sample's own burrs (mm) on top of the spec's.

    Pin ``i``'s gap ``R(θ) p_i + (x, y) - h_i`` is ``[p_x, p_y, 1] @ [[cos, sin], [-sin, cos],
    [x - h_x, y - h_y]]`` per goal.
    """
    holes, pins = spec.hole_centers, spec.nominal_pin_centers  # pitch error in the pins
    cos, sin = np.cos(goals[:, 2]), np.sin(goals[:, 2])
    # Each pin's own squared clearance (burrs); a blocked or too-large pin never fits.
    clearances = spec.pin_clearances
    limits = np.where(clearances >= 0, clearances * clearances, -1.0)
    if burrs is not None:
        own = clearances[None, :] - burrs
        limits = np.where(own >= 0, own * own, -1.0)[:, :, None]
    inside = np.ones((len(offsets), len(goals)), dtype=bool)
    for i, (hx, hy) in enumerate(holes):
        px, py = pins[i, 0] + offsets[:, i, 0:1], pins[i, 1] + offsets[:, i, 1:2]
        dx = px * cos - py * sin + (goals[:, 0] - hx)
        dy = px * sin + py * cos + (goals[:, 1] - hy)
        inside &= dx * dx + dy * dy <= (limits[i] if burrs is None else limits[:, i])
    return inside


def centre_goals(spec: CircularSocket, offsets: np.ndarray) -> np.ndarray:
    """The pose ``(N, 3)`` that best aligns each sample's pins with the holes.

    Least squares (2-D Kabsch) of ``R(θ) p_i + t ≈ h_i`` with ``p_i = h_i + eps_i``: for two
    pins this is the deepest pose of the tolerance, and the workpiece can be inserted at
    all iff it is inside.
    """
    holes = spec.hole_centers
    pins = holes + offsets
    p = pins - pins.mean(axis=-2, keepdims=True)
    h = holes - holes.mean(axis=0)
    cross = np.sum(p[..., 0] * h[:, 1] - p[..., 1] * h[:, 0], axis=-1)
    dot = np.sum(p[..., 0] * h[:, 0] + p[..., 1] * h[:, 1], axis=-1)
    theta = np.arctan2(cross, dot)
    c, s = np.cos(theta), np.sin(theta)
    centre = pins.mean(axis=-2)
    x = holes[:, 0].mean() - (c * centre[..., 0] - s * centre[..., 1])
    y = holes[:, 1].mean() - (s * centre[..., 0] + c * centre[..., 1])
    return np.stack([x, y, theta], axis=-1)


def find_goal(
    spec: CircularSocket,
    posterior: Posterior,
    rng: np.random.Generator,
    *,
    threshold: float = DISCARD_THRESHOLD,
    iterations: int = 12,
    popsize: int = 8,
) -> GoalResult:
    """Maximise ``g_{m+1}`` over ``[x*, y*, θ*]`` with CMA-ES from the best candidate.

    An unexplained posterior gives the nominal goal, ``expected_success = 0`` and
    ``discard = True``. ``rng`` seeds CMA-ES (pycma reseeds numpy's global RNG).
    """
    nominal = np.zeros(3)
    if not posterior.explained:
        return GoalResult(nominal, 0.0, True, 0)
    order = np.argsort(-posterior.weights, kind="stable")[:_CANDIDATES]
    candidates = np.concatenate([nominal[None], centre_goals(spec, posterior.offsets[order])])
    scores = expected_success(spec, posterior, candidates)
    best = int(np.argmax(scores))
    goal, score, evaluations = candidates[best], float(scores[best]), len(candidates)
    if iterations > 0 and score < 1.0:
        goal, score, evaluations = _refine(spec, posterior, goal, score, rng, iterations, popsize)
        evaluations += len(candidates)
    return GoalResult(goal, score, score < threshold, evaluations)


def _refine(
    spec: CircularSocket,
    posterior: Posterior,
    start: np.ndarray,
    start_score: float,
    rng: np.random.Generator,
    iterations: int,
    popsize: int,
) -> tuple[np.ndarray, float, int]:
    """CMA-ES in mm-scaled coordinates ``[x, y, θ·L]`` (L: the farthest hole's distance)."""
    import cma  # 0.8 s (it loads scipy.stats and matplotlib): only where a goal is searched

    scale = np.array([1.0, 1.0, max(float(np.max(np.hypot(*spec.hole_centers.T))), 1.0)])
    options = {
        "seed": int(rng.integers(1, 2**31 - 1)),
        "popsize": popsize,
        "maxiter": iterations,
        "verbose": -9,
        "verb_log": 0,
        "verb_disp": 0,
        "tolflatfitness": iterations,
    }
    best, best_score, evaluations = start, start_score, 0
    # pycma seeds numpy's global RNG and ask() draws from it: hold it for the whole search,
    # or two searches in threads (π_φ* evaluations run two at a time) interleave their
    # draws and neither is reproducible.
    with _GLOBAL_RNG:
        es = cma.CMAEvolutionStrategy(start * scale, 0.25 * spec.clearance, options)
        while not es.stop():
            population = np.array(es.ask())
            goals = population / scale
            scores = expected_success(spec, posterior, goals)
            evaluations += len(goals)
            top = int(np.argmax(scores))
            if scores[top] > best_score:
                best, best_score = goals[top], float(scores[top])
            es.tell(list(population), list(-scores))
    return best, best_score, evaluations


def next_goal(
    spec: CircularSocket,
    history: History,
    sigma: float,
    rng: np.random.Generator,
    *,
    n_samples: int = 1000,
    threshold: float = DISCARD_THRESHOLD,
    model: DefectModel | None = None,
    not_insertable_below: float = DISCARD_THRESHOLD,
) -> GoalResult:
    """The goal of the next attempt given ``history``: the nominal goal when it is empty.

    ``model``: infer with the defect model (:class:`~.posterior.DefectModel`: bends, pitch
    error, burrs, a blocked hole) instead of the bent-pin prior ``N(0, sigma²)``; then the
    result is ``not_insertable`` when its best ``g`` (times ``1 - P(blocked)``) is below
    ``not_insertable_below``.
    """
    if model is not None:
        return _defect_goal(spec, history, model, rng, n_samples, threshold, not_insertable_below)
    posterior = sample_posterior(spec, history, sigma, n_samples, rng)
    if len(history) == 0:
        score = float(expected_success(spec, posterior, np.zeros(3))[0])
        return GoalResult(np.zeros(3), score, score < threshold, 1)
    return find_goal(spec, posterior, rng, threshold=threshold)


def _defect_goal(spec, history, model, rng, n_samples, threshold, not_insertable_below):
    """:func:`next_goal` with the defect model."""
    posterior = sample_defect_posterior(spec, history, model, n_samples, rng)
    if len(history) == 0:
        score = float(expected_success(spec, posterior, np.zeros(3))[0])
        found = GoalResult(np.zeros(3), score, score < threshold, 1)
    else:
        found = find_goal(spec, posterior, rng, threshold=threshold)
    verdict = len(history) > 0 and found.expected_success < not_insertable_below
    return dataclasses.replace(found, not_insertable=verdict, blocked=posterior.blocked)
