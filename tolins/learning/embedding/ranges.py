"""The workpieces each embedding family is trained on: documented ranges, sampling, checks.

* **circle**: ``CircularSocket(2, cols)``, ``cols`` 1…20, pin radius 0.25–0.35 mm, hole
  radius 0.45–0.6 mm, row pitch 2.5–7.62 mm, column pitch 2.0–5.08 mm, nominal (no bent
  pins). Radial clearance 0.1–0.35 mm, inside the ±0.4 mm circle window.
* **polygon**: ``PolygonSocket(sides, pin, pin + gap)``, ``sides`` 3…6, peg circumradius
  1.2–1.8 mm, circumradius gap 0.06–0.2 mm (the presets: square and pentagon 1.5/1.65,
  hexagon 1.2/1.26, the paper's square 1.5/1.575). The largest region, a triangle with a
  0.2 mm gap, reaches 0.2 mm from the origin, inside the ±0.25 mm polygon window.

Every range is closed and sampled uniformly (integers inclusive).

The graded embedding (:data:`GRADED_RANGES`) widens both families to the tolerance grades:
circle radial clearance 0.015–0.35 mm (any pin radius 0.25–0.35 mm), polygon gap
0.02–0.2 mm, each clearance (gap) drawn log-uniformly.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec

FAMILIES = ("circle", "polygon")


@dataclass(frozen=True)
class CircleRanges:
    """Closed ranges ``(low, high)`` of the circle family's spec fields (mm)."""

    rows: tuple[int, int] = (2, 2)
    cols: tuple[int, int] = (1, 20)
    pin_radius: tuple[float, float] = (0.25, 0.35)
    hole_radius: tuple[float, float] = (0.45, 0.6)
    row_pitch: tuple[float, float] = (2.5, 7.62)
    col_pitch: tuple[float, float] = (2.0, 5.08)

    def sample(self, rng: np.random.Generator) -> CircularSocket:
        """One nominal socket drawn uniformly from the ranges."""
        return CircularSocket(
            rows=int(rng.integers(self.rows[0], self.rows[1] + 1)),
            cols=int(rng.integers(self.cols[0], self.cols[1] + 1)),
            pin_radius=float(rng.uniform(*self.pin_radius)),
            hole_radius=float(rng.uniform(*self.hole_radius)),
            row_pitch=float(rng.uniform(*self.row_pitch)),
            col_pitch=float(rng.uniform(*self.col_pitch)),
        )

    def violations(self, spec: SocketSpec) -> list[str]:
        """What puts ``spec`` outside the ranges (empty: inside)."""
        if not isinstance(spec, CircularSocket):
            return [f"{type(spec).__name__} is not a CircularSocket"]
        found = _outside(self, spec)
        if spec.is_defective:
            found.append("pin_offsets: bent pins (trained on nominal sockets only)")
        return found


@dataclass(frozen=True)
class PolygonRanges:
    """Closed ranges ``(low, high)`` of the polygon family (``gap`` = hole − peg circumradius)."""

    sides: tuple[int, int] = (3, 6)
    pin_circumradius: tuple[float, float] = (1.2, 1.8)
    gap: tuple[float, float] = (0.06, 0.2)

    def sample(self, rng: np.random.Generator) -> PolygonSocket:
        """One peg drawn uniformly from the ranges."""
        pin = float(rng.uniform(*self.pin_circumradius))
        return PolygonSocket(
            sides=int(rng.integers(self.sides[0], self.sides[1] + 1)),
            pin_circumradius=pin,
            hole_circumradius=pin + float(rng.uniform(*self.gap)),
        )

    def violations(self, spec: SocketSpec) -> list[str]:
        """What puts ``spec`` outside the ranges (empty: inside)."""
        if not isinstance(spec, PolygonSocket):
            return [f"{type(spec).__name__} is not a PolygonSocket"]
        return _outside(self, spec)


@dataclass(frozen=True)
class GradedCircleRanges(CircleRanges):
    """The circle family of the graded embedding: radial clearance ``hole - pin``
    0.015–0.35 mm (the grades' 20, 50 and 100 µm and the paper's 0.2 mm), drawn
    log-uniformly so that the fine fits are as frequent as the loose ones."""

    hole_radius: tuple[float, float] = (0.265, 0.7)
    clearance: tuple[float, float] = (0.015, 0.35)

    def sample(self, rng: np.random.Generator) -> CircularSocket:
        """One nominal socket: pin radius, log-uniform clearance, then the other fields."""
        rows = int(rng.integers(self.rows[0], self.rows[1] + 1))
        cols = int(rng.integers(self.cols[0], self.cols[1] + 1))
        pin = float(rng.uniform(*self.pin_radius))
        clearance = _log_uniform(rng, self.clearance)
        return CircularSocket(
            rows=rows,
            cols=cols,
            pin_radius=pin,
            hole_radius=pin + clearance,
            row_pitch=float(rng.uniform(*self.row_pitch)),
            col_pitch=float(rng.uniform(*self.col_pitch)),
        )


@dataclass(frozen=True)
class GradedPolygonRanges(PolygonRanges):
    """The polygon family of the graded embedding: circumradius gap 0.02–0.2 mm (the
    grades' 20 µm square and hexagon: 0.028 and 0.023 mm), drawn log-uniformly."""

    gap: tuple[float, float] = (0.02, 0.2)

    def sample(self, rng: np.random.Generator) -> PolygonSocket:
        """One peg: sides, circumradius, then a log-uniform gap."""
        sides = int(rng.integers(self.sides[0], self.sides[1] + 1))
        pin = float(rng.uniform(*self.pin_circumradius))
        return PolygonSocket(
            sides=sides, pin_circumradius=pin, hole_circumradius=pin + _log_uniform(rng, self.gap)
        )


def _log_uniform(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    low, high = bounds
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


FamilyRanges = CircleRanges | PolygonRanges

#: The ranges of each family, as trained for the shipped checkpoints.
RANGES: dict[str, FamilyRanges] = {"circle": CircleRanges(), "polygon": PolygonRanges()}
#: The ranges of the graded checkpoints (``tolins/assets/embedding_<family>_graded.pt``).
GRADED_RANGES: dict[str, FamilyRanges] = {
    "circle": GradedCircleRanges(),
    "polygon": GradedPolygonRanges(),
}
#: The embedding models: the paper's (default) and the graded one.
MODELS = ("paper", "graded")


def model_ranges(family: str, model: str = "paper") -> FamilyRanges:
    """The ranges of ``family`` ("circle" or "polygon") for ``model`` ("paper", "graded")."""
    if family not in RANGES:
        raise ValueError(f"family={family!r}; allowed: {', '.join(RANGES)}")
    if model not in MODELS:
        raise ValueError(f"model={model!r}; allowed: {', '.join(map(repr, MODELS))}")
    return (RANGES if model == "paper" else GRADED_RANGES)[family]


# Specs on a range's edge must pass despite float rounding (e.g. pin + gap).
_SLACK = 1e-9


def _outside(ranges: FamilyRanges, spec: SocketSpec) -> list[str]:
    found = []
    for item in fields(ranges):
        low, high = getattr(ranges, item.name)
        if item.name == "gap":
            value = spec.hole_circumradius - spec.pin_circumradius
        else:
            value = getattr(spec, item.name)
        if not low - _SLACK <= value <= high + _SLACK:
            found.append(f"{item.name}={value:.6g} outside [{low}, {high}]")
    return found


def ranges_from_dict(family: str, values: dict[str, object], model: str = "paper") -> FamilyRanges:
    """Ranges of ``family`` from their stored form (a checkpoint's ``ranges``)."""
    cls = type(model_ranges(family, model))
    return cls(**{key: tuple(value) for key, value in values.items()})
