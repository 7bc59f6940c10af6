"""Random defects of a workpiece: bent pins."""

from __future__ import annotations

import dataclasses

import numpy as np

from tolins.geometry.specs import CircularSocket
from tolins.geometry.validation import check_positive


def sample_defects(
    spec: CircularSocket, sigma: float, rng: np.random.Generator | int | None = None
) -> CircularSocket:
    """Return a copy of ``spec`` whose pins are displaced by offsets drawn from N(0, sigma² I).

    Any offsets ``spec`` already had are replaced. ``sigma`` is in mm; ``rng`` is a
    ``numpy.random.Generator`` or a seed for one.
    """
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"spec={spec!r} cannot have bent pins; allowed: a CircularSocket")
    sigma = check_positive("sigma", sigma)
    rng = np.random.default_rng(rng)
    offsets = rng.normal(0.0, sigma, size=(spec.n_pins, 2))
    return dataclasses.replace(spec, pin_offsets=offsets)
