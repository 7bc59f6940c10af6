"""The socket's parts as plain arrays for logging: pure functions of a spec, in mm.

Built with the MJCF generator's own geometry code (``tolins.mjcf``), so the recording
shows the pieces the simulator collides: the board's wall prisms and boxes, the
polygons that model the holes, the pins and the carrier plate above them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tolins.geometry.specs import CircularSocket, SocketSpec, inradius, polygon_vertices
from tolins.mjcf.board import hole_wall_pieces
from tolins.mjcf.model import (
    BOARD_THICKNESS,
    PIN_LENGTH,
    board_filler_boxes,
    carrier_half_size,
    cell_half_width,
    hole_shape,
)


@dataclass(frozen=True)
class TriangleMesh:
    """Vertices ``(n, 3)`` and counter-clockwise triangles ``(m, 3)`` (vertex indices)."""

    vertices: np.ndarray
    triangles: np.ndarray


@dataclass(frozen=True)
class BoxSet:
    """Axis-aligned boxes: centres ``(n, 3)`` and half-sizes ``(n, 3)``."""

    centers: np.ndarray
    half_sizes: np.ndarray


@dataclass(frozen=True)
class BoardGeometry:
    """The static board: wall prisms around the holes, filler boxes, hole outlines at z = 0."""

    walls: TriangleMesh
    boxes: BoxSet
    hole_outlines: list[np.ndarray]


@dataclass(frozen=True)
class PinGeometry:
    """The pins in the workpiece frame (a full-length pin's tip at z = 0): exactly one of
    ``cylinders``, ``box``, ``mesh`` is set.

    ``cylinders`` is ``(centers (n, 3), radii (n,), lengths (n,))`` as the MJCF model
    places them: pitch error and bends in the centres, a burr in its pin's radius, a short
    pin lacking its tip (shorter, centred higher); ``box`` a single square peg; ``mesh`` a
    polygon peg prism. ``burred`` and ``short`` flag each pin ``(n,)`` (circles only).
    """

    cylinders: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    box: BoxSet | None = None
    mesh: TriangleMesh | None = None
    burred: np.ndarray | None = None
    short: np.ndarray | None = None


def prism_mesh(outline: np.ndarray, z_bottom: float, z_top: float) -> TriangleMesh:
    """A closed prism over a convex counter-clockwise ``outline`` ``(k, 2)``."""
    outline = np.asarray(outline, dtype=float)
    if outline.ndim != 2 or outline.shape[1] != 2 or len(outline) < 3:
        raise ValueError(f"outline has shape {outline.shape}; allowed: (k ≥ 3, 2)")
    if not z_bottom < z_top:
        raise ValueError(f"z_bottom={z_bottom!r} ≥ z_top={z_top!r}; allowed: z_bottom < z_top")
    k = len(outline)
    top = np.column_stack([outline, np.full(k, z_top)])
    bottom = np.column_stack([outline, np.full(k, z_bottom)])
    fan = np.arange(1, k - 1)
    triangles = [np.column_stack([np.zeros_like(fan), fan, fan + 1])]  # top, facing up
    triangles.append(np.column_stack([np.full_like(fan, k), k + fan + 1, k + fan]))  # bottom
    i = np.arange(k)
    j = (i + 1) % k
    triangles += [np.column_stack([i, k + i, k + j]), np.column_stack([i, k + j, j])]  # sides
    return TriangleMesh(np.concatenate([top, bottom]), np.concatenate(triangles))


def flat_shaded(mesh: TriangleMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(vertices, triangles, normals)`` with each triangle's own vertices and face
    normals, so a viewer shades every face flat (shared vertices would smooth the edges)."""
    vertices = mesh.vertices[mesh.triangles].reshape(-1, 3)
    corners = mesh.vertices[mesh.triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    triangles = np.arange(len(vertices)).reshape(-1, 3)
    return vertices, triangles, np.repeat(normals, 3, axis=0)


def merge_meshes(meshes: list[TriangleMesh]) -> TriangleMesh:
    """One mesh holding all of ``meshes``."""
    if not meshes:
        raise ValueError("no meshes to merge; allowed: at least one")
    offsets = np.cumsum([0, *(len(m.vertices) for m in meshes[:-1])])
    return TriangleMesh(
        np.concatenate([m.vertices for m in meshes]),
        np.concatenate([m.triangles + o for m, o in zip(meshes, offsets, strict=True)]),
    )


def board_geometry(spec: SocketSpec) -> BoardGeometry:
    """The board of ``spec`` as the MJCF generator builds it (top at z = 0)."""
    sides, circumradius = hole_shape(spec)
    half_width = cell_half_width(spec)
    pieces = hole_wall_pieces(sides, circumradius, half_width)
    outline = polygon_vertices(sides, circumradius)
    walls, holes = [], []
    for center in spec.hole_centers:
        walls += [prism_mesh(piece + center, -BOARD_THICKNESS, 0.0) for piece in pieces]
        ring = np.vstack([outline, outline[:1]]) + center
        holes.append(np.column_stack([ring, np.zeros(len(ring))]))
    boxes = board_filler_boxes(spec)
    box_set = BoxSet(
        np.array([[*c, -BOARD_THICKNESS / 2] for c, _ in boxes]),
        np.array([[*h, BOARD_THICKNESS / 2] for _, h in boxes]),
    )
    return BoardGeometry(merge_meshes(walls), box_set, holes)


def pin_geometry(spec: SocketSpec) -> PinGeometry:
    """The pins of ``spec`` (its defects included) in the workpiece frame."""
    half = PIN_LENGTH / 2
    if isinstance(spec, CircularSocket):
        levels = spec.shortenings
        centers = np.column_stack([spec.pin_centers, half + levels / 2])
        return PinGeometry(
            cylinders=(centers, spec.pin_radii, PIN_LENGTH - levels),
            burred=spec.burrs > 0,
            short=levels > 0,
        )
    if spec.sides == 4:
        side_half = inradius(4, spec.pin_circumradius)
        return PinGeometry(
            box=BoxSet(np.array([[0.0, 0.0, half]]), np.array([[side_half] * 2 + [half]]))
        )
    outline = polygon_vertices(spec.sides, spec.pin_circumradius)
    return PinGeometry(mesh=prism_mesh(outline, 0.0, PIN_LENGTH))


def plug_boxes(spec: SocketSpec) -> BoxSet | None:
    """The plugs of ``spec``'s blocked holes (``None``: none), in the world frame: the MJCF
    model's ``plug{h}`` boxes, a square of half-width ``hole_radius`` through the board."""
    if not isinstance(spec, CircularSocket) or not spec.blocked_holes:
        return None
    holes = spec.hole_centers[list(spec.blocked_holes)]
    n = len(holes)
    return BoxSet(
        np.column_stack([holes, np.full(n, -BOARD_THICKNESS / 2)]),
        np.tile([spec.hole_radius, spec.hole_radius, BOARD_THICKNESS / 2], (n, 1)),
    )


def carrier_box(spec: SocketSpec) -> BoxSet:
    """The carrier plate above the pins, in the workpiece frame."""
    half = carrier_half_size(spec)
    return BoxSet(np.array([[0.0, 0.0, PIN_LENGTH + 1.0]]), np.array([[*half, 1.0]]))
