"""Socket geometry: specs, defects (numpy and shapely only; nothing else of tolins)."""

from tolins.geometry.defects import sample_defects
from tolins.geometry.specs import (
    CIRCLE_HOLE_SIDES,
    MIN_WALL,
    CircularSocket,
    PolygonSocket,
    SocketSpec,
    inradius,
    polygon_vertices,
)

__all__ = [
    "CIRCLE_HOLE_SIDES",
    "MIN_WALL",
    "CircularSocket",
    "PolygonSocket",
    "SocketSpec",
    "inradius",
    "polygon_vertices",
    "sample_defects",
]
