"""A socket's parts as closed triangle meshes, for CAD tools and slicers.

Built from the MJCF model's own geometry (:mod:`tolins.mjcf.model`), in mm, z up, the
board's top at z = 0:

* ``board``: the model's plate (its size and thickness) less its holes, each the polygon
  that models it (a round hole's 16-gon of face distance ``hole_radius``, a peg's hole
  polygon): one watertight body, a polygon with holes triangulated by GEOS's constrained
  Delaunay triangulation (shapely) and extruded (trimesh).
* ``plug{h}``: blocked hole ``h``. With ``plugs_apart`` its own body, the hole's polygon
  through the board (the model's square plug covers that polygon; the rest of the square
  lies in the wall), and the board keeps the hole; otherwise the board is solid there.
* ``pin{i}``: the pins where the model puts them: pitch error and bends in their centres,
  a burr in its pin's radius, a short pin lacking its tip. A round pin is a prism of
  :data:`PIN_SECTIONS` sides whose edges lie on the model's cylinder; a peg is its
  polygon prism.
* ``carrier``: the plate above the pins.

The workpiece (pins and carrier) is in its own frame, a full-length pin's tip at z = 0,
raised by ``lift`` mm; at the nominal pose over the board, the tips are ``lift`` above it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
import trimesh
from shapely.geometry import Polygon

from tolins.geometry.specs import CircularSocket, SocketSpec, polygon_vertices
from tolins.geometry.workspace import PIN_LENGTH
from tolins.mjcf.model import (
    BOARD_RGBA,
    BOARD_THICKNESS,
    CARRIER_RGBA,
    CARRIER_THICKNESS,
    PIN_RGBA,
    board_margin,
    carrier_half_size,
    cell_half_width,
    hole_shape,
)

#: Sides of the prism that stands in for a round pin (its edges on the cylinder).
PIN_SECTIONS = 64
#: Height (mm) of the pin tips over the board's top when board and workpiece share a file.
WORKPIECE_LIFT = 2.0
#: Colours (RGBA, 0–1) beside the model's board, pin and carrier ones: a burred, a short
#: pin and a plug as the recordings draw them.
BURR_RGBA = (0.86, 0.24, 0.2, 1.0)
SHORT_RGBA = (0.27, 0.51, 0.86, 1.0)
PLUG_RGBA = (0.78, 0.24, 0.63, 1.0)
#: What :func:`socket_parts` can build.
PART_CHOICES = ("all", "board", "workpiece")


@dataclass(frozen=True)
class Part:
    """One closed body of a socket: its name, its mesh (mm) and its colour."""

    name: str
    mesh: trimesh.Trimesh
    rgba: tuple[float, float, float, float]


def prism(outline: Polygon, z_bottom: float, z_top: float) -> trimesh.Trimesh:
    """The closed prism of ``outline`` (holes allowed) between ``z_bottom`` and ``z_top``."""
    if not z_bottom < z_top:
        raise ValueError(f"z_bottom={z_bottom!r} ≥ z_top={z_top!r}; allowed: z_bottom < z_top")
    index: dict[tuple[float, float], int] = {}
    faces = [
        [index.setdefault(corner, len(index)) for corner in triangle.exterior.coords[:3]]
        for triangle in shapely.constrained_delaunay_triangles(outline).geoms
    ]
    mesh = trimesh.creation.extrude_triangulation(
        np.array(list(index), dtype=float), np.array(faces), z_top - z_bottom
    )
    mesh.apply_translation([0.0, 0.0, z_bottom])
    return mesh


def hole_outlines(spec: SocketSpec) -> list[np.ndarray]:
    """The polygon ``(sides, 2)`` of every hole (mm), as the model's wall pieces bound it."""
    sides, circumradius = hole_shape(spec)
    outline = polygon_vertices(sides, circumradius)
    return [outline + center for center in spec.hole_centers]


def board_bounds(spec: SocketSpec) -> np.ndarray:
    """``[[x_lo, y_lo], [x_hi, y_hi]]`` (mm) of the board: the model's hole cells and the
    margin around them (:func:`tolins.mjcf.board.board_boxes`)."""
    reach = cell_half_width(spec) + board_margin(spec)
    centers = spec.hole_centers
    return np.array([centers.min(axis=0) - reach, centers.max(axis=0) + reach])


def blocked(spec: SocketSpec) -> tuple[int, ...]:
    """The blocked holes of ``spec`` (a peg's hole is never blocked)."""
    return spec.blocked_holes if isinstance(spec, CircularSocket) else ()


def board_parts(spec: SocketSpec, *, plugs_apart: bool = False) -> list[Part]:
    """The board, and with ``plugs_apart`` a plug per blocked hole (see the module)."""
    (x_lo, y_lo), (x_hi, y_hi) = board_bounds(spec)
    plugged = set(blocked(spec))
    outlines = hole_outlines(spec)
    holes = [o for h, o in enumerate(outlines) if plugs_apart or h not in plugged]
    plate = Polygon([(x_lo, y_lo), (x_hi, y_lo), (x_hi, y_hi), (x_lo, y_hi)], holes)
    parts = [Part("board", prism(plate, -BOARD_THICKNESS, 0.0), BOARD_RGBA)]
    if plugs_apart:
        parts += [
            Part(f"plug{h}", prism(Polygon(outlines[h]), -BOARD_THICKNESS, 0.0), PLUG_RGBA)
            for h in sorted(plugged)
        ]
    return parts


def workpiece_parts(spec: SocketSpec, *, lift: float = 0.0) -> list[Part]:
    """The pins and the carrier, a full-length pin's tip at z = ``lift``."""
    parts = []
    if isinstance(spec, CircularSocket):
        for i, (center, radius, short, burr) in enumerate(
            zip(spec.pin_centers, spec.pin_radii, spec.shortenings, spec.burrs, strict=True)
        ):
            outline = Polygon(polygon_vertices(PIN_SECTIONS, radius) + center)
            rgba = SHORT_RGBA if short > 0 else BURR_RGBA if burr > 0 else PIN_RGBA
            parts.append(Part(f"pin{i}", prism(outline, lift + short, lift + PIN_LENGTH), rgba))
    else:
        outline = Polygon(polygon_vertices(spec.sides, spec.pin_circumradius))
        parts.append(Part("pin0", prism(outline, lift, lift + PIN_LENGTH), PIN_RGBA))
    half_x, half_y = carrier_half_size(spec)
    plate = shapely.box(-half_x, -half_y, half_x, half_y)
    bottom = lift + PIN_LENGTH
    parts.append(Part("carrier", prism(plate, bottom, bottom + CARRIER_THICKNESS), CARRIER_RGBA))
    return parts


def socket_parts(spec: SocketSpec, part: str = "all", *, plugs_apart: bool = False) -> list[Part]:
    """The bodies of ``part`` of ``spec``: ``board`` (and its plugs), ``workpiece`` (in its
    frame) or ``all`` (the workpiece :data:`WORKPIECE_LIFT` over the board)."""
    if part not in PART_CHOICES:
        raise ValueError(f"part={part!r}; allowed: {', '.join(PART_CHOICES)}")
    parts = [] if part == "workpiece" else board_parts(spec, plugs_apart=plugs_apart)
    if part != "board":
        parts += workpiece_parts(spec, lift=WORKPIECE_LIFT if part == "all" else 0.0)
    return parts
