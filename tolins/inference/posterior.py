"""The posterior over bent-pin offsets given a history, as weighted samples.

Prior: every pin's offset ``eps_i ~ N(0, sigma² I)``. Likelihood of attempt ``j`` at the
true pose ``s̄_j`` (perfect measurement, the paper's eq. for ``p(ε | I_1..m, s̄_1..m)``)::

    p(I_j | s̄_j, ε) = 1[s̄_j ∈ T(ε)]  if I_j = 1,   1 - 1[s̄_j ∈ T(ε)]  if I_j = 0
    p(ε | history) ∝ p(ε) Π_j p(I_j | s̄_j, ε)

With contact evidence ``b_j`` (which pins the board blocked) a failed attempt's factor is
``Π_i 1[pin i in its hole at s̄_j] = 1 - b_ji``; with touch bearings ``φ_ji`` of the blocked
pins it is multiplied by ``Π_i exp(κ (cos(φ_ji − ∠gap_ji(ε)) − 1))``, ``κ = 1 / noise²``
(a von Mises density around the direction of the pin's gap to its hole). With measured
poses ``ŝ_j = s̄_j + ν``, ``ν ~ N(0, diag(noise²))``, each factor is integrated over the
noise (the paper's ``g′``)::

    p(I_j | ŝ_j, ε) = ∫ p(I_j | s̄, ε) N(s̄; ŝ_j, diag(noise²)) ds̄ ≈ 1/K Σ_k p(I_j | ŝ_j + ν_k, ε)

``OVERSAMPLE × n`` samples are drawn from the prior and importance-weighted, then ``n`` of
them resampled and moved by Metropolis steps on ``p(ε) Π_j p(I_j | ·, ε)`` (sequential
Monte Carlo's resample-move). When no prior sample explains the history, they are moved
through tempered targets ``p(ε) Π_j max(p_j, e^{-λ})``, λ = 1…16 (a narrow posterior, e.g.
after contacts); failing that, the prior is widened (×2, ×4, importance-corrected) before
giving up with ``explained=False``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tolins.geometry.specs import CircularSocket
from tolins.geometry.tolerance import gaps_inside, pin_gaps
from tolins.inference.history import History

#: Noise draws per measured attempt (``K`` above).
NOISE_DRAWS = 32
#: Prior draws per returned sample: the importance step draws ``OVERSAMPLE × n_samples``,
#: then resamples ``n_samples`` of them and moves them. The likelihood is cheap next to the
#: goal search, which sees only ``n_samples``.
OVERSAMPLE = 16
_WIDENINGS = (2.0, 4.0)
_MOVES = 4
#: Tempering levels λ when no prior sample explains the history.
_TEMPERS = (1.0, 2.0, 4.0, 8.0, 16.0)


@dataclass(frozen=True)
class Posterior:
    """Weighted samples of the pin offsets.

    Attributes:
        offsets: ``(N, n_pins, 2)`` sampled offsets ``eps`` (mm).
        weights: ``(N,)`` normalised weights (sum 1, never NaN).
        explained: False when no sample, even from a widened prior, explains the history
            (then ``weights`` are uniform over prior samples).
        widening: Factor applied to ``sigma`` to explain the history (1: none).
        burrs: See below (defect model only).
        blocked: See below (defect model only).
    """

    offsets: np.ndarray
    weights: np.ndarray
    explained: bool = True
    widening: float = 1.0
    #: ``(N, n_pins)`` each sample's burrs (mm, shrinking the pin's clearance); None: the
    #: bent-pin model (no burrs). Set by :func:`sample_defect_posterior`.
    burrs: np.ndarray | None = None
    #: Posterior probability that a hole is blocked (no goal inserts); 0 in the bent model.
    blocked: float = 0.0

    @property
    def ess(self) -> float:
        """Effective sample size ``1 / Σ w²``."""
        return float(1.0 / np.sum(self.weights**2))


def log_likelihood(
    spec: CircularSocket,
    offsets: np.ndarray,
    history: History,
    noise_draws: np.ndarray | None,
    temper: float = np.inf,
) -> np.ndarray:
    """``log Π_j p(I_j | s̄_j, ε)`` for each sample ``(N,)``; ``-inf`` where impossible.

    ``noise_draws`` ``(m, K, 3)``: the ``ν_k`` added to measured poses (None: exact poses).
    A finite ``temper`` λ floors every factor at ``e^{-λ}`` (``-λ`` per violated attempt).
    """
    if len(history) == 0:
        return np.zeros(len(offsets))
    poses = history.poses[:, None, :]
    if noise_draws is not None:
        poses = poses + noise_draws
    # gaps: (N, m, K, n_pins, 2); inside: (N, m, K, n_pins)
    gaps = pin_gaps(spec, offsets[:, None, None], poses[None])
    inside = gaps_inside(spec, gaps)
    if history.blocked is None:
        fits = inside.all(-1) == history.inserted[None, :, None]
    else:
        fits = np.all(inside == ~history.blocked[None, :, None, :], axis=-1)
    factor = fits.astype(float)
    if history.bearings is not None:
        factor *= np.exp(_log_bearing_factor(gaps, history))
    with np.errstate(divide="ignore"):
        return np.maximum(np.log(factor.mean(-1)), -temper).sum(-1)


def _log_bearing_factor(gaps: np.ndarray, history: History) -> np.ndarray:
    """``Σ_i κ (cos(φ_ji − ∠gap_ji) − 1)`` over the measured bearings, ``κ = 1 / noise²``.

    A von Mises density in the measured bearing ``φ_ji`` around the gap's direction,
    normalised to 1 at its peak.
    """
    predicted = np.arctan2(gaps[..., 1], gaps[..., 0])
    measured = history.bearings[None, :, None, :]
    known = np.isfinite(measured)
    kappa = 1.0 / history.bearing_noise**2
    log_f = kappa * (np.cos(np.where(known, measured, 0.0) - predicted) - 1.0)
    return np.where(known, log_f, 0.0).sum(-1)


def sample_posterior(
    spec: CircularSocket,
    history: History,
    sigma: float,
    n_samples: int,
    rng: np.random.Generator,
) -> Posterior:
    """Weighted samples of ``p(ε | history)`` under the prior ``N(0, sigma² I)`` per pin."""
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"spec={spec!r}; allowed: a CircularSocket (bent pins)")
    if not sigma > 0 or n_samples < 2:
        raise ValueError(f"sigma={sigma!r}, n_samples={n_samples!r}; allowed: > 0 and ≥ 2")
    draws = _noise_draws(history, rng)
    shape = (n_samples, spec.n_pins, 2)
    if len(history) == 0:
        return Posterior(rng.normal(0.0, sigma, size=shape), np.full(n_samples, 1 / n_samples))
    offsets = rng.normal(0.0, sigma, size=(n_samples * OVERSAMPLE, *shape[1:]))
    log_w = log_likelihood(spec, offsets, history, draws)
    if not np.isfinite(log_w).any():
        offsets = _tempered(spec, history, sigma, offsets[:n_samples], draws, rng)
        log_w = log_likelihood(spec, offsets, history, draws)
    if np.isfinite(log_w).any():
        weighted = _normalised(offsets, log_w, 1.0)
        return _resample_move(spec, history, sigma, weighted, draws, rng, n_out=n_samples)
    for widening in _WIDENINGS:
        offsets = rng.normal(0.0, sigma * widening, size=shape)
        log_w = log_likelihood(spec, offsets, history, draws)
        # Importance correction of the widened proposal back to the prior.
        log_w += 0.5 * (1 - widening**-2) * -np.sum(offsets**2, axis=(1, 2)) / sigma**2
        if np.isfinite(log_w).any():
            posterior = _normalised(offsets, log_w, widening)
            if posterior.ess < n_samples / 4:
                posterior = _resample_move(spec, history, sigma, posterior, draws, rng)
            return posterior
    uniform = np.full(n_samples, 1.0 / n_samples)
    return Posterior(rng.normal(0.0, sigma, size=shape), uniform, False, _WIDENINGS[-1])


def _noise_draws(history: History, rng: np.random.Generator) -> np.ndarray | None:
    noise = history.measurement_noise
    if noise is None or not np.any(noise > 0) or len(history) == 0:
        return None
    return rng.normal(0.0, 1.0, size=(len(history), NOISE_DRAWS, 3)) * noise


def _normalised(offsets: np.ndarray, log_w: np.ndarray, widening: float) -> Posterior:
    weights = np.exp(log_w - np.max(log_w))
    return Posterior(offsets, weights / weights.sum(), True, widening)


def _resample_move(
    spec: CircularSocket,
    history: History,
    sigma: float,
    posterior: Posterior,
    draws: np.ndarray | None,
    rng: np.random.Generator,
    temper: float = np.inf,
    n_out: int | None = None,
) -> Posterior:
    """Systematic resampling to ``n_out`` samples (default: as many as given), then
    Metropolis random-walk moves on prior × likelihood."""
    n = len(posterior.weights) if n_out is None else n_out
    positions = (rng.random() + np.arange(n)) / n
    cumulative = np.cumsum(posterior.weights)
    index = np.minimum(np.searchsorted(cumulative, positions), len(cumulative) - 1)
    offsets = posterior.offsets[index]
    log_p = _log_target(spec, history, sigma, offsets, draws, temper)
    step = 0.5 * np.maximum(offsets.std(axis=0), 1e-3 * sigma)
    for _ in range(_MOVES):
        proposal = offsets + rng.normal(size=offsets.shape) * step
        log_q = _log_target(spec, history, sigma, proposal, draws, temper)
        accept = np.log(rng.random(n)) < log_q - log_p
        offsets = np.where(accept[:, None, None], proposal, offsets)
        log_p = np.where(accept, log_q, log_p)
    return Posterior(offsets, np.full(n, 1.0 / n), True, posterior.widening)


def _tempered(
    spec: CircularSocket,
    history: History,
    sigma: float,
    offsets: np.ndarray,
    draws: np.ndarray | None,
    rng: np.random.Generator,
) -> np.ndarray:
    """Prior samples moved through tempered targets ``p(ε) Π_j max(p_j, e^{-λ})``."""
    previous = np.zeros(len(offsets))
    for temper in _TEMPERS:
        current = log_likelihood(spec, offsets, history, draws, temper)
        weights = _normalised(offsets, current - previous, 1.0)
        moved = _resample_move(spec, history, sigma, weights, draws, rng, temper)
        offsets = moved.offsets
        previous = log_likelihood(spec, offsets, history, draws, temper)
    return offsets


def _log_target(
    spec: CircularSocket,
    history: History,
    sigma: float,
    offsets: np.ndarray,
    draws: np.ndarray | None,
    temper: float = np.inf,
) -> np.ndarray:
    prior = -0.5 * np.sum(offsets**2, axis=(1, 2)) / sigma**2
    return prior + log_likelihood(spec, offsets, history, draws, temper)


@dataclass(frozen=True)
class DefectModel:
    """The prior of :func:`sample_defect_posterior`: bent pins, pitch error, burrs, a
    blocked hole and a grasp error together (the defect kinds of
    :mod:`tolins.geometry.defects`, and a part held off in a robot's hand).

    A workpiece's latent ``z = (bend (n_pins, 2), δ (2,), u (n_pins,)[, g (3,)])`` is
    Gaussian: ``bend ~ N(0, sigma²)``, the pitch error ``δ = (col, row) scale - 1 ~ N(0,
    pitch_sigma²)``, ``u ~ N(0, burr_sigma²)`` with burr ``|u|``, and, only when
    ``grasp_sigma`` is not all zero, the grasp error ``g = (dx, dy, dψ) ~ N(0,
    diag(grasp_sigma²))``: the part that far off (in its own frame) from where the robot
    believes it, which moves every pin alike. Pin ``i`` (nominally at ``h_i``) sits at
    ``R(dψ) h_i (1 + δ) + (dx, dy) + bend_i``, with clearance ``c - |u_i|``. Besides, with
    prior probability ``blocked_prior`` one hole (uniform) is plugged: its pin never goes
    in, every attempt fails and it is blocked at every contact.

    Attributes:
        sigma: Bend std per pin and axis (mm; 0: straight pins).
        pitch_sigma: Relative pitch error std per axis (0: none).
        burr_sigma: Burr std (mm; 0: none).
        blocked_prior: Prior probability of a blocked hole (0: never).
        grasp_sigma: Grasp error std ``(x, y, yaw)`` (mm, mm, rad; the part's frame, as an
            env's ``grasp_error``); all zero: none (no grasp coordinates in ``z``).
    """

    sigma: float
    pitch_sigma: float = 0.0
    burr_sigma: float = 0.0
    blocked_prior: float = 0.0
    grasp_sigma: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("sigma", "pitch_sigma", "burr_sigma"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"{name}={getattr(self, name)!r}; allowed: ≥ 0")
        if not 0.0 <= self.blocked_prior < 1.0:
            raise ValueError(f"blocked_prior={self.blocked_prior!r}; allowed: 0 ≤ value < 1")
        grasp = np.asarray(self.grasp_sigma, dtype=float)
        if grasp.shape != (3,) or not np.all(grasp >= 0):
            raise ValueError(
                f"grasp_sigma={self.grasp_sigma!r}; allowed: three stds (x, y, yaw) ≥ 0"
            )
        object.__setattr__(self, "grasp_sigma", tuple(float(v) for v in grasp))
        if not (self.sigma > 0 or self.grasps):
            raise ValueError(
                f"sigma={self.sigma!r} with grasp_sigma={self.grasp_sigma!r}; allowed: "
                "sigma > 0, or a grasp_sigma above 0 (something must move the pins)"
            )

    @property
    def grasps(self) -> bool:
        """Whether the latent holds a grasp error (``grasp_sigma`` not all zero)."""
        return any(v > 0 for v in self.grasp_sigma)

    def scales(self, n_pins: int) -> np.ndarray:
        """Prior std of each latent coordinate ``(D,)``, ``D = 3 n_pins + 2`` (``+ 3`` with a
        grasp error; 0: fixed)."""
        parts = [
            np.full(2 * n_pins, self.sigma),
            np.full(2, self.pitch_sigma),
            np.full(n_pins, self.burr_sigma),
        ]
        if self.grasps:
            parts.append(np.asarray(self.grasp_sigma))
        return np.concatenate(parts)


def defect_parts(spec: CircularSocket, latent: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Effective offsets ``(N, n_pins, 2)`` (bend, pitch error and any grasp error) and
    burrs ``(N, n_pins)`` of latent samples ``(N, 3 n_pins + 2)``, or ``(N, 3 n_pins + 5)``
    with a grasp error (:class:`DefectModel`)."""
    n = spec.n_pins
    bend = latent[:, : 2 * n].reshape(-1, n, 2)
    pitch = latent[:, 2 * n : 2 * n + 2]
    offsets = bend + spec.hole_centers * pitch[:, None, :]
    if latent.shape[1] == 3 * n + 5:
        dx, dy, turn = (latent[:, 3 * n + 2 + k, None] for k in range(3))
        pins = spec.hole_centers[None] + spec.hole_centers * pitch[:, None, :]
        c, s = np.cos(turn) - 1.0, np.sin(turn)
        offsets = offsets + np.stack(
            [c * pins[..., 0] - s * pins[..., 1] + dx, s * pins[..., 0] + c * pins[..., 1] + dy],
            axis=-1,
        )
    return offsets, np.abs(latent[:, 2 * n + 2 : 3 * n + 2])


def defect_log_likelihood(
    spec: CircularSocket,
    latent: np.ndarray,
    history: History,
    noise_draws: np.ndarray | None,
    temper: float = np.inf,
    plugged: int | None = None,
    bearings: bool = True,
) -> np.ndarray:
    """:func:`log_likelihood` of latent samples of the defect model; ``plugged``: under the
    hypothesis that this hole is blocked (its pin never in); ``bearings=False``: without
    the touch bearings' factors (outcomes and blocked pins only)."""
    if len(history) == 0:
        return np.zeros(len(latent))
    offsets, burrs = defect_parts(spec, latent)
    poses = history.poses[:, None, :]
    if noise_draws is not None:
        poses = poses + noise_draws
    gaps = pin_gaps(spec, offsets[:, None, None], poses[None])
    clear = spec.clearance - burrs
    limits = np.where(clear >= 0, clear * clear, -1.0)
    if plugged is not None:
        limits[:, plugged] = -1.0
    inside = np.sum(gaps * gaps, axis=-1) <= limits[:, None, None, :]
    if history.blocked is None:
        fits = inside.all(-1) == history.inserted[None, :, None]
    else:
        fits = np.all(inside == ~history.blocked[None, :, None, :], axis=-1)
    factor = fits.astype(float)
    if bearings and history.bearings is not None:
        factor *= np.exp(_log_bearing_factor(gaps, history))
    with np.errstate(divide="ignore"):
        return np.maximum(np.log(factor.mean(-1)), -temper).sum(-1)


def sample_defect_posterior(
    spec: CircularSocket,
    history: History,
    model: DefectModel,
    n_samples: int,
    rng: np.random.Generator,
) -> Posterior:
    """Weighted samples of the defect model's posterior (:class:`DefectModel`), and the
    posterior probability of a blocked hole.

    The same resample-move scheme as :func:`sample_posterior` on the latent ``z``. The
    blocked hypothesis's evidence ``Z_b = 1/n Σ_k E[p(history | z, hole k plugged)]`` and
    the others' ``Z_0 = E[p(history | z)]`` are Monte Carlo estimates over the
    ``OVERSAMPLE × n_samples`` prior draws of the outcomes and blocked pins (the bearings
    left out: both are then shares of the draws); when no draw explains the history ``Z_0``
    is taken as ``1 / draws`` (its upper bound), so a blocked hole is never over-stated.
    """
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"spec={spec!r}; allowed: a CircularSocket")
    if n_samples < 2:
        raise ValueError(f"n_samples={n_samples!r}; allowed: ≥ 2")
    scales = model.scales(spec.n_pins)
    draws = _noise_draws(history, rng)

    def target(z: np.ndarray, temper: float = np.inf) -> np.ndarray:
        prior = -0.5 * np.sum((z[:, scales > 0] / scales[scales > 0]) ** 2, axis=1)
        return prior + defect_log_likelihood(spec, z, history, draws, temper)

    def prior_draws(count: int) -> np.ndarray:
        return rng.normal(0.0, 1.0, size=(count, len(scales))) * scales

    def finish(z: np.ndarray, blocked: float, explained: bool = True) -> Posterior:
        offsets, burrs = defect_parts(spec, z)
        weights = np.full(len(z), 1.0 / len(z))
        return Posterior(offsets, weights, explained, 1.0, burrs, blocked)

    if len(history) == 0:
        return finish(prior_draws(n_samples), model.blocked_prior)
    z = prior_draws(n_samples * OVERSAMPLE)
    log_w = defect_log_likelihood(spec, z, history, draws)
    blocked = _blocked_probability(spec, z, history, draws, model.blocked_prior)
    if not np.isfinite(log_w).any():
        z = z[:n_samples]
        previous = np.zeros(n_samples)
        for temper in _TEMPERS:
            current = defect_log_likelihood(spec, z, history, draws, temper)
            z = _latent_move(z, current - previous, lambda q, t=temper: target(q, t), rng, scales)
            previous = defect_log_likelihood(spec, z, history, draws, temper)
        log_w = defect_log_likelihood(spec, z, history, draws)
        if not np.isfinite(log_w).any():
            # Nothing but a blocked hole explains the history (or nothing at all).
            return finish(z, blocked, explained=blocked > 0)
    z = _latent_move(z, log_w, target, rng, scales, n_out=n_samples)
    return finish(z, blocked)


def _blocked_probability(
    spec: CircularSocket,
    z: np.ndarray,
    history: History,
    draws: np.ndarray | None,
    prior: float,
) -> float:
    """``P(blocked | history)`` from the evidences of :func:`sample_defect_posterior`."""
    if prior <= 0:
        return 0.0
    log_w = defect_log_likelihood(spec, z, history, draws, bearings=False)
    z_free = max(float(np.mean(np.exp(log_w))), 1.0 / len(z))
    z_blocked = np.mean(
        [
            np.mean(np.exp(defect_log_likelihood(spec, z, history, draws, k, bearings=False)))
            for k in range(spec.n_pins)
        ]
    )
    return float(prior * z_blocked / (prior * z_blocked + (1 - prior) * z_free))


def _latent_move(
    z: np.ndarray,
    log_w: np.ndarray,
    target: Callable[[np.ndarray], np.ndarray],
    rng: np.random.Generator,
    scales: np.ndarray,
    n_out: int | None = None,
) -> np.ndarray:
    """Systematic resampling of ``z`` by ``exp(log_w)`` to ``n_out`` samples, then
    Metropolis random-walk moves on ``target`` (fixed coordinates stay)."""
    n = len(z) if n_out is None else n_out
    weights = np.exp(log_w - np.max(log_w))
    cumulative = np.cumsum(weights / weights.sum())
    positions = (rng.random() + np.arange(n)) / n
    z = z[np.minimum(np.searchsorted(cumulative, positions), len(cumulative) - 1)]
    log_p = target(z)
    step = 0.5 * np.maximum(z.std(axis=0), 1e-3 * scales) * (scales > 0)
    for _ in range(_MOVES):
        proposal = z + rng.normal(size=z.shape) * step
        log_q = target(proposal)
        accept = np.log(rng.random(n)) < log_q - log_p
        z = np.where(accept[:, None], proposal, z)
        log_p = np.where(accept, log_q, log_p)
    return z
