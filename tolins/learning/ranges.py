"""The workpieces each embedding family is trained on: documented ranges, sampling, checks.

* **circle**: ``CircularSocket(2, cols)``, ``cols`` 1…20, pin radius 0.25–0.35 mm, hole
  radius 0.45–0.6 mm, row pitch 2.5–7.62 mm, column pitch 2.0–5.08 mm, nominal (no bent
  pins). Radial clearance 0.1–0.35 mm, inside the ±0.4 mm circle window.
* **polygon**: ``PolygonSocket(sides, pin, pin + gap)``, ``sides`` 3…6, peg circumradius
  1.2–1.8 mm, circumradius gap 0.06–0.2 mm (the presets: square and pentagon 1.5/1.65,
  hexagon 1.2/1.26, the paper's square 1.5/1.575). The largest region, a triangle with a
  0.2 mm gap, reaches 0.2 mm from the origin, inside the ±0.25 mm polygon window.

Every range is closed and sampled uniformly (integers inclusive).
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


FamilyRanges = CircleRanges | PolygonRanges

#: The ranges of each family, as trained for the shipped checkpoints.
RANGES: dict[str, FamilyRanges] = {"circle": CircleRanges(), "polygon": PolygonRanges()}

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


def ranges_from_dict(family: str, values: dict[str, object]) -> FamilyRanges:
    """Ranges of ``family`` from their stored form (a checkpoint's ``ranges``)."""
    cls = CircleRanges if family == "circle" else PolygonRanges
    return cls(**{key: tuple(value) for key, value in values.items()})
