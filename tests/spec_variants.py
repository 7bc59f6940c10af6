"""Specs that differ from each other in exactly one field each (shared by several tests)."""

from __future__ import annotations

from tolins import CircularSocket, PolygonSocket, sample_defects


def one_field_variants() -> list[CircularSocket | PolygonSocket]:
    """13 distinct specs: a 2*2 socket and a square peg, each field changed in turn."""
    return [
        CircularSocket(2, 2),
        CircularSocket(2, 3),
        CircularSocket(3, 2),
        CircularSocket(2, 2, pin_radius=0.25),
        CircularSocket(2, 2, hole_radius=0.55),
        CircularSocket(2, 2, row_pitch=8.0),
        CircularSocket(2, 2, col_pitch=3.0),
        sample_defects(CircularSocket(2, 2), 0.1, rng=0),
        sample_defects(CircularSocket(2, 2), 0.1, rng=1),
        PolygonSocket(4, 1.5, 1.65),
        PolygonSocket(5, 1.5, 1.65),
        PolygonSocket(4, 1.4, 1.65),
        PolygonSocket(4, 1.5, 1.7),
    ]
