"""Which board pieces each pin can touch, as explicit MJCF ``<pair>``s.

Pins and board pieces are vertical prisms (the workpiece only turns about z), and
contacts have no margin, so a pin can touch a piece only where their horizontal
outlines overlap. Over the servo range of :mod:`tolins.geometry.workspace` (every
``|x|, |y| ≤ XY_RANGE``, ``|theta| ≤ THETA_RANGE``) and every bend a spec of the family
allows (``offset_limit``), pin ``i`` stays inside a box about the origin; the pieces
whose bounding boxes meet it are its pairs. A wall piece's top face is part of the
board's top, so a pin a pitch away from its hole still has its neighbour's pieces.

With these pairs the pins need no automatic collision: MuJoCo tests each pair with its
bounding spheres and runs the narrowphase, instead of walking two bounding-volume trees.
The pairs are emitted in the order in which the tree walk sorts its contacts (by geom
id, lower geom type first; board geom first between equal types), with the contact
parameters the geoms' defaults mix to, so the contacts, their order and the whole
trajectory are bit for bit those of the automatic collision
(``tests/test_contact_filtering.py``).

It is not the default: explicit pairs skip the broadphase and are all tested in every
step, by bounding spheres alone (a pin's has a radius of 2 mm: it is 4 mm long), so
away from the board and inside the holes the narrowphase runs on many more pairs than
the tree walk's oriented boxes let through; only while pins press on the board do the
pairs save time (``benchmarks/README.md``, "A cheaper contact step").
"""

from __future__ import annotations

import math

import numpy as np

from tolins.geometry.specs import CircularSocket, SocketSpec
from tolins.geometry.workspace import THETA_RANGE, XY_RANGE

#: MuJoCo's geom type numbers (``mjtGeom``): the pair order depends on them.
GEOM_TYPE = {"box": 6, "cylinder": 5, "mesh": 7}
#: Slack (mm) added to every reach box against rounding.
_SLACK = 1e-6


def _arc_range(a: float, b: float) -> tuple[float, float]:
    """Range of ``a cos(t) + b sin(t)`` over ``|t| ≤ THETA_RANGE``."""
    candidates = [-THETA_RANGE, THETA_RANGE]
    stationary = math.atan2(b, a)
    candidates += [
        t for t in (stationary - math.pi, stationary, stationary + math.pi) if abs(t) <= THETA_RANGE
    ]
    values = [a * math.cos(t) + b * math.sin(t) for t in candidates]
    return min(values), max(values)


def _swept(center: np.ndarray, grow: np.ndarray) -> np.ndarray:
    """``[[x_lo, y_lo], [x_hi, y_hi]]`` of ``center`` turned over ``|theta| ≤ THETA_RANGE``,
    grown by ``grow`` ``(2,)``."""
    (x_lo, x_hi), (y_lo, y_hi) = _arc_range(center[0], -center[1]), _arc_range(*center[::-1])
    return np.array([[x_lo - grow[0], y_lo - grow[1]], [x_hi + grow[0], y_hi + grow[1]]])


def pin_reach_boxes(spec: SocketSpec) -> np.ndarray:
    """``(n_pins, 2, 2)``: per pin, ``[[x_lo, y_lo], [x_hi, y_hi]]`` (mm) of a box that holds
    the pin's outline over the whole servo range, for any bend of the spec's family (the
    box of the nominal pin grown by ``offset_limit``) and for the spec's own pins (other
    defects: pitch errors, burrs)."""
    circle = isinstance(spec, CircularSocket)
    limit = spec.offset_limit if circle else np.zeros(2)
    radii = spec.pin_radii if circle else np.full(1, spec.pin_reach)
    sin = math.sin(THETA_RANGE)
    # |R(theta) d|_x ≤ |d_x| + |d_y| sin(theta) for |theta| ≤ THETA_RANGE, and alike in y.
    bend = limit + limit[::-1] * sin
    boxes = []
    for hole, pin, radius in zip(spec.hole_centers, spec.pin_centers, radii, strict=True):
        grow = XY_RANGE + max(radius, spec.pin_reach) + _SLACK
        nominal, own = _swept(hole, grow + bend), _swept(pin, np.full(2, grow))
        boxes.append([np.minimum(nominal[0], own[0]), np.maximum(nominal[1], own[1])])
    return np.array(boxes)


def reachable(reach: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """``(n_pins, n_pieces)`` bools: whether pin ``i``'s reach box meets piece ``j``'s box
    (``pieces``: ``(n_pieces, 2, 2)`` as :func:`pin_reach_boxes`)."""
    lo_ok = np.all(pieces[None, :, 0] <= reach[:, None, 1], axis=-1)
    hi_ok = np.all(pieces[None, :, 1] >= reach[:, None, 0], axis=-1)
    return lo_ok & hi_ok


def pair_order(
    pins: list[tuple[str, str]],
    pieces: list[tuple[str, str]],
    mask: np.ndarray,
    first_pin_id: int,
) -> list[tuple[str, str]]:
    """``(board geom, pin geom)`` names of the pairs in ``mask``, in the tree walk's order.

    ``pins`` and ``pieces`` are ``(name, geom type)`` in model order; the pieces' geom ids
    are ``0, 1, ...`` and the pins' ``first_pin_id, first_pin_id + 1, ...``.
    """
    keys = []
    for i, j in zip(*np.nonzero(mask), strict=True):
        pin_id, piece_id = first_pin_id + int(i), int(j)
        pin_first = GEOM_TYPE[pins[i][1]] < GEOM_TYPE[pieces[j][1]]
        keys.append(((pin_id, piece_id) if pin_first else (piece_id, pin_id), int(j), int(i)))
    keys.sort()
    return [(pieces[j][0], pins[i][0]) for _, j, i in keys]
