"""The board: a plate with n-gon holes, decomposed into convex pieces MuJoCo can collide.

Each hole sits in a square cell of half-width ``w``. The ring between the hole and the
square is split along the rays through the hole's vertices into one convex prism per
side (a wedge ∩ square ∩ the half-plane beyond that side), shared by all holes. The
rest of the board is covered by boxes: full-width strips between the rows of cells and
short boxes between the cells of a row.
"""

from __future__ import annotations

import math

import numpy as np

from tolins.geometry.specs import polygon_vertices

#: Width (mm) of board beyond the outermost hole cells.
BOARD_MARGIN = 3.0
#: Skip boxes thinner than this (mm): neighbouring cells that touch.
_MIN_BOX = 1e-9


def _square_hit(angle: float, half_width: float) -> np.ndarray:
    """Where the ray from the origin at ``angle`` leaves the square of half-width ``half_width``."""
    direction = np.array([math.cos(angle), math.sin(angle)])
    return direction * half_width / np.max(np.abs(direction))


def hole_wall_pieces(sides: int, circumradius: float, half_width: float) -> list[np.ndarray]:
    """Convex 2-D outlines, counter-clockwise, of the ``sides`` pieces around one hole.

    Piece ``k`` lies between the hole's face from vertex ``k`` to ``k + 1`` and the
    square cell of half-width ``half_width``.
    """
    if half_width <= circumradius:
        raise ValueError(
            f"half_width={half_width!r} does not enclose a hole of circumradius "
            f"{circumradius!r}; allowed: half_width > circumradius"
        )
    vertices = polygon_vertices(sides, circumradius)
    step = 2 * math.pi / sides
    pieces = []
    for k in range(sides):
        start = (2 * k + 1) * math.pi / sides
        end = start + step
        corners = [
            _square_hit(a, half_width)
            for a in (math.pi / 4 + j * math.pi / 2 for j in range(-4, 9))
            if start + 1e-12 < a < end - 1e-12
        ]
        outline = [
            vertices[k],
            _square_hit(start, half_width),
            *corners,
            _square_hit(end, half_width),
            vertices[(k + 1) % sides],
        ]
        pieces.append(np.array(outline))
    return pieces


def board_boxes(
    centers: np.ndarray, half_width: float, margin: float = BOARD_MARGIN
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Boxes ``(center_xy, half_size_xy)`` covering the board outside the hole cells.

    ``centers`` are the hole centres ``(n, 2)`` on a regular grid.
    """
    xs = np.unique(np.round(centers[:, 0], 9))
    ys = np.unique(np.round(centers[:, 1], 9))
    x_lo, x_hi = xs[0] - half_width - margin, xs[-1] + half_width + margin
    y_lo, y_hi = ys[0] - half_width - margin, ys[-1] + half_width + margin
    boxes = []

    def add(x0: float, x1: float, y0: float, y1: float) -> None:
        if x1 - x0 > _MIN_BOX and y1 - y0 > _MIN_BOX:
            boxes.append(
                (np.array([(x0 + x1) / 2, (y0 + y1) / 2]), np.array([(x1 - x0) / 2, (y1 - y0) / 2]))
            )

    row_edges = [y_lo, *[e for y in ys for e in (y - half_width, y + half_width)], y_hi]
    for y0, y1 in zip(row_edges[::2], row_edges[1::2], strict=True):
        add(x_lo, x_hi, y0, y1)
    col_edges = [x_lo, *[e for x in xs for e in (x - half_width, x + half_width)], x_hi]
    for y in ys:
        for x0, x1 in zip(col_edges[::2], col_edges[1::2], strict=True):
            add(x0, x1, y - half_width, y + half_width)
    return boxes
