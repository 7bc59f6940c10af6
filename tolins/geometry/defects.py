"""Random defects of a workpiece: bent pins."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from tolins.geometry.specs import CircularSocket
from tolins.geometry.validation import check_positive

#: A bent-pin std is allowed when at least this share of its draws keep every pin in its
#: cell (:attr:`~tolins.geometry.specs.CircularSocket.offset_limit`).
MIN_VALID_SHARE = 0.5
#: Draws before :func:`sample_defects` gives up: at a valid share ≥ 1/2 all of them fail
#: with a probability ≤ 2⁻¹⁰⁰.
MAX_DRAWS = 100


def valid_share(spec: CircularSocket, sigma: float) -> float:
    """Probability that one draw of offsets ~ N(0, sigma² I) keeps every pin of ``spec`` in
    its cell: ``(erf(hx / (sigma √2)) · erf(hy / (sigma √2))) ** n_pins``."""
    hx, hy = spec.offset_limit / (sigma * math.sqrt(2.0))
    return (math.erf(hx) * math.erf(hy)) ** spec.n_pins


def max_defect_sigma(spec: CircularSocket) -> float:
    """The largest bent-pin std (mm) whose :func:`valid_share` is :data:`MIN_VALID_SHARE`."""
    low, high = 0.0, float(np.max(spec.offset_limit))
    while valid_share(spec, high) >= MIN_VALID_SHARE:
        high *= 2.0
    for _ in range(60):
        middle = 0.5 * (low + high)
        low, high = (
            (middle, high) if valid_share(spec, middle) >= MIN_VALID_SHARE else (low, middle)
        )
    return low


def check_defect_sigma(spec: CircularSocket, sigma: object, field: str = "sigma") -> float:
    """``sigma`` as a float if it is a bent-pin std (mm) that ``spec`` allows: finite, > 0,
    and at least half of its draws valid (:func:`max_defect_sigma`)."""
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"{field} is set but only a CircularSocket has bent pins, not {spec!r}")
    sigma = check_positive(field, sigma)
    if valid_share(spec, sigma) < MIN_VALID_SHARE:
        raise ValueError(
            f"{field}={sigma!r} is too large for a {spec.rows}*{spec.cols} socket: fewer than "
            f"half of its draws keep every pin in its cell; allowed: 0 < {field} ≤ "
            f"{max_defect_sigma(spec):.4g} mm"
        )
    return sigma


def sample_defects(
    spec: CircularSocket, sigma: float, rng: np.random.Generator | int | None = None
) -> CircularSocket:
    """Return a copy of ``spec`` whose pins are displaced by offsets drawn from N(0, sigma² I),
    re-drawn until every pin is in its cell.

    A draw is the offsets of all pins, ``rng.normal(0, sigma, (n_pins, 2))``; one with a pin
    beyond :attr:`~tolins.geometry.specs.CircularSocket.offset_limit` is dropped as a whole
    and the next one drawn (the offsets are N(0, sigma² I) conditioned on every pin in its
    cell). A first draw that is valid is the result, so the same ``rng`` gives the same
    workpiece as a single draw did. ``sigma`` (mm) must pass :func:`check_defect_sigma`;
    any offsets ``spec`` already had are replaced; ``rng`` is a ``numpy.random.Generator``
    or a seed for one.
    """
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"spec={spec!r} cannot have bent pins; allowed: a CircularSocket")
    sigma = check_defect_sigma(spec, sigma)
    rng = np.random.default_rng(rng)
    limit = spec.offset_limit
    for _ in range(MAX_DRAWS):
        offsets = rng.normal(0.0, sigma, size=(spec.n_pins, 2))
        if not np.any(np.abs(offsets) > limit):
            return dataclasses.replace(spec, pin_offsets=offsets)
    raise RuntimeError(f"{MAX_DRAWS} draws of sigma={sigma!r} all moved a pin out of its cell")
