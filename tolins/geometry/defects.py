"""Random defects of a workpiece: bent pins, pitch error, burred, short pins, a blocked hole.

:func:`sample_defects` draws one kind (:data:`DEFECT_KINDS`) at a scale ``sigma``:

* ``bent`` (the default; the paper's): offsets ``~ N(0, sigma² I)`` mm per pin, re-drawn
  until every pin is in its cell (``pin_offsets``).
* ``pitch``: the pins' column and row spacing scaled by ``1 + N(0, sigma²)`` each
  (``sigma`` relative, e.g. 0.01 = 1 %), re-drawn until within ``MAX_PITCH_ERROR`` and
  every pin in its cell (``pin_pitch_scale``).
* ``burr``: each pin's radius grows by ``|N(0, sigma²)|`` mm, re-drawn until within
  ``MAX_BURR`` and in its cell (``pin_burrs``).
* ``short``: each pin is shortened by ``|N(0, sigma²)|`` mm, re-drawn until within
  ``MAX_SHORTENING`` (``pin_shortenings``).
* ``blocked``: one hole, drawn uniformly, is plugged (``blocked_holes``); ``sigma`` must
  be ``None``.

Each kind replaces its own field and keeps the others, so kinds compose.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from tolins.geometry.specs import MAX_BURR, MAX_PITCH_ERROR, MAX_SHORTENING, CircularSocket
from tolins.geometry.validation import check_positive, is_seed

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


#: The kinds of defect :func:`sample_defects` draws.
DEFECT_KINDS = ("bent", "pitch", "burr", "short", "blocked")


def check_rng(rng: object, field: str = "rng") -> np.random.Generator:
    """``rng`` as a ``numpy.random.Generator``: itself, or one made by
    ``numpy.random.default_rng`` from ``None`` (fresh entropy), an integer seed ≥ 0 (or a
    list of them), a ``SeedSequence`` or a ``BitGenerator``; ``ValueError`` naming ``field``
    otherwise."""
    allowed = "None, a numpy.random.Generator, or an integer seed ≥ 0 (or a list of them)"
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, (np.random.SeedSequence, np.random.BitGenerator)) or rng is None:
        return np.random.default_rng(rng)
    if isinstance(rng, (list, tuple)) and rng and all(is_seed(seed) for seed in rng):
        return np.random.default_rng([int(seed) for seed in rng])
    if is_seed(rng):
        return np.random.default_rng(int(rng))
    raise ValueError(f"{field}={rng!r} is not a random generator or seed; allowed: {allowed}")


def _check_sigma_given(sigma: object, kind: str) -> None:
    """``ValueError`` for ``sigma=None`` with a kind that needs a scale (all but blocked)."""
    if sigma is None and kind != "blocked":
        raise ValueError(
            f"sigma=None is for kind='blocked' only; allowed for kind={kind!r}: a finite number > 0"
        )


def sample_defects(
    spec: CircularSocket,
    sigma: float | None,
    rng: np.random.Generator | int | None = None,
    *,
    kind: str = "bent",
) -> CircularSocket:
    """Return a copy of ``spec`` whose pins are displaced by offsets drawn from N(0, sigma² I),
    re-drawn until every pin is in its cell.

    A draw is the offsets of all pins, ``rng.normal(0, sigma, (n_pins, 2))``; one with a pin
    beyond :attr:`~tolins.geometry.specs.CircularSocket.offset_limit` is dropped as a whole
    and the next one drawn (the offsets are N(0, sigma² I) conditioned on every pin in its
    cell). A first draw that is valid is the result, so the same ``rng`` gives the same
    workpiece as a single draw did. ``sigma`` (mm) must pass :func:`check_defect_sigma`;
    any offsets ``spec`` already had are replaced; ``rng`` is a ``numpy.random.Generator``
    or a seed for one (:func:`check_rng`). ``kind`` (:data:`DEFECT_KINDS`, module docstring)
    draws another kind of defect at the scale ``sigma`` instead. ``sigma`` has no default:
    every kind needs one but ``blocked``, which needs ``None``.
    """
    if kind != "bent":
        return _sample_kind(spec, sigma, rng, kind)
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"spec={spec!r} cannot have bent pins; allowed: a CircularSocket")
    _check_sigma_given(sigma, kind)
    sigma = check_defect_sigma(spec, sigma)
    rng = check_rng(rng)
    limit = spec.offset_limit
    for _ in range(MAX_DRAWS):
        offsets = rng.normal(0.0, sigma, size=(spec.n_pins, 2))
        if not np.any(np.abs(offsets) > limit):
            return dataclasses.replace(spec, pin_offsets=offsets)
    raise RuntimeError(f"{MAX_DRAWS} draws of sigma={sigma!r} all moved a pin out of its cell")


def check_defects(
    spec: object, defects: object, field: str = "defects"
) -> tuple[str, float | None]:
    """``defects`` as ``(kind, sigma)`` if :func:`sample_defects` can draw that kind at that
    scale from ``spec``: a kind of :data:`DEFECT_KINDS` and its ``sigma`` (``None`` for
    ``blocked``), checked by one trial draw."""
    allowed = f"(kind, sigma) with kind one of {', '.join(DEFECT_KINDS)} (sigma None for blocked)"
    if not isinstance(defects, (tuple, list)) or len(defects) != 2:
        raise ValueError(f"{field}={defects!r}; allowed: {allowed}")
    kind, sigma = defects
    if kind not in DEFECT_KINDS:
        raise ValueError(f"{field} kind={kind!r} is unknown; allowed: {allowed}")
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"{field} is set but only a CircularSocket has defects, not {spec!r}")
    if kind == "bent":
        return kind, check_defect_sigma(spec, sigma, field)
    try:
        sample_defects(spec, sigma, 0, kind=kind)
    except RuntimeError as error:
        raise ValueError(f"{field}={defects!r}: {error}") from None
    return kind, None if sigma is None else float(sigma)


#: Per kind: the spec field it sets and the largest ``sigma`` (its field's own bound).
_KIND_LIMITS = {"pitch": MAX_PITCH_ERROR, "burr": MAX_BURR, "short": MAX_SHORTENING}


def _sample_kind(
    spec: CircularSocket, sigma: object, rng: np.random.Generator | int | None, kind: str
) -> CircularSocket:
    """:func:`sample_defects` of a kind other than ``bent``."""
    if kind not in DEFECT_KINDS:
        raise ValueError(f"kind={kind!r} is unknown; allowed: {', '.join(DEFECT_KINDS)}")
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"spec={spec!r} cannot have {kind} defects; allowed: a CircularSocket")
    rng = check_rng(rng)
    if kind == "blocked":
        if sigma is not None:
            raise ValueError(f"sigma={sigma!r} is set for kind='blocked'; allowed: None")
        hole = int(rng.integers(spec.n_pins))
        return dataclasses.replace(spec, blocked_holes=(hole,))
    _check_sigma_given(sigma, kind)
    sigma = check_positive("sigma", sigma, "mm" if kind != "pitch" else "(relative)")
    limit = _KIND_LIMITS[kind]
    if sigma > limit:
        raise ValueError(f"sigma={sigma!r} is too large for kind={kind!r}; allowed: ≤ {limit}")
    for _ in range(MAX_DRAWS):
        if kind == "pitch":
            scale = 1.0 + rng.normal(0.0, sigma, size=2)
            values = {"pin_pitch_scale": tuple(scale)} if np.all(abs(scale - 1) <= limit) else None
        else:
            draw = np.abs(rng.normal(0.0, sigma, size=spec.n_pins))
            field = "pin_burrs" if kind == "burr" else "pin_shortenings"
            values = {field: tuple(draw)} if np.all(draw <= limit) else None
        if values is None:
            continue
        try:
            return dataclasses.replace(spec, **values)
        except ValueError:
            continue  # a pin out of its cell: draw again
    raise RuntimeError(
        f"{MAX_DRAWS} draws of kind={kind!r}, sigma={sigma!r} all left the allowed range or "
        "moved a pin out of its cell; choose a smaller sigma"
    )
