"""The tolerance model: the poses ``[x, y, theta]`` that put every pin inside its hole.

A pose moves each pin rigidly: rotation by ``theta`` about the board origin, then
translation by ``(x, y)`` (mm, rad). Holes are nominal; pins carry the spec's
``pin_offsets``. The tolerance is a closed set: a pin touching its hole's wall is inside.

* Circles: pin ``i`` (centre ``p_i``, pitch error and offsets included) is inside hole
  ``h_i`` iff ``|R(theta) p_i + (x, y) - h_i| <= c_i``, ``c_i = hole_radius - pin_radius
  - burr_i`` (exact circles, not the 16-gons of the MuJoCo model); a pin with ``c_i < 0``
  (burred beyond its hole) or in a blocked hole is never inside
  (:attr:`~tolins.geometry.specs.CircularSocket.pin_clearances`). Short pins do not
  change the tolerance (a short pin must still be in its hole): they change only the
  height at which a pin meets the board (:func:`pin_levels`).
* Polygons: the peg is inside iff each of its vertices is behind each face of the hole.
  For two regular n-gons with a face normal along +x this reads
  ``max_k n_k·(x, y) <= r_hole - R_pin cos((theta mod 2π/n) - π/n)``, with face normals
  ``n_k`` at angles ``2πk/n``, ``r_hole`` the hole's inradius and ``R_pin`` the peg's
  circumradius (the right-hand side's second term is the rotated peg's reach along
  any face normal).

Every constraint has the form ``a cos(theta + beta) <= b``, which gives the largest
rotation of a pose in closed form (:func:`_arc_reach`); :func:`image` and :func:`extents`
use it, :func:`contains` evaluates the geometry directly.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec, inradius
from tolins.geometry.validation import check_int

#: Image value of a cell ``(x, y)`` whose pose ``[x, y, 0]`` is outside the tolerance.
#: Finite (no NaN in a loss) and below every valid theta (≥ 0), so the region is
#: ``image >= 0``.
NO_TOLERANCE = -1.0
_TWO_PI = 2 * math.pi


@dataclass(frozen=True)
class ImageWindow:
    """The square of ``(x, y)`` an image samples and the largest theta it stores.

    Attributes:
        half_width: The samples span ``[-half_width, half_width]`` mm in x and in y.
        theta_cap: Larger rotations (up to free turning) are stored as ``theta_cap`` rad.
        warp: Exponent ``p`` of the grid: the sample at ``u`` ∈ [-1, 1] (evenly spaced)
            lies at ``half_width · sign(u) · |u|^p``. 1 (the default): the linear grid;
            2: cells fine near the origin and coarse at the edge (the graded embedding).
    """

    half_width: float
    theta_cap: float
    warp: float = 1.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.warp) and self.warp > 0):
            raise ValueError(f"warp={self.warp!r}; allowed: a finite number > 0")

    def axis(self, resolution: int) -> np.ndarray:
        """The ``resolution`` sample coordinates along x (and y), both edges included."""
        steps = np.arange(resolution) * (2.0 / (resolution - 1)) - 1.0
        if self.warp != 1.0:
            steps = np.sign(steps) * np.abs(steps) ** self.warp
        return self.half_width * steps


#: One window per family, so that images of different workpieces are comparable. The
#: circle window holds clearances up to 0.4 mm (pins 0.25–0.35 mm in holes 0.45–0.6 mm,
#: bent pins shifting the region); the polygon window holds pegs up to 0.25 mm smaller
#: than their hole in circumradius (e.g. 1.2–1.65 mm pegs with a 0.06–0.15 mm gap).
WINDOWS = {
    "circle": ImageWindow(half_width=0.4, theta_cap=0.5),
    "polygon": ImageWindow(half_width=0.25, theta_cap=0.5),
}
#: The windows of the graded embedding (``tolins.embedding.encode(spec, model="graded")``):
#: the same squares, sampled on a warped grid (``warp=2``) so that the 20 µm regions of the
#: tolerance grades span ~14 cells at 64² (a linear grid: 12.7 µm per cell on circles).
GRADED_WINDOWS = {
    "circle": ImageWindow(half_width=0.4, theta_cap=0.5, warp=2.0),
    "polygon": ImageWindow(half_width=0.25, theta_cap=0.5, warp=2.0),
}


@dataclass(frozen=True)
class Extents:
    """The tolerance along each axis through the nominal pose (mm, mm, rad).

    ``x`` is the closed interval of x with ``y = theta = 0`` (and ``y`` likewise):
    exact, ``(nan, nan)`` when empty (a bent pin may exclude the nominal pose yet leave
    an interval). ``theta`` is the interval of rotations about ``x = y = 0`` that
    reaches ``theta = 0`` (``(-inf, inf)``: the peg turns freely; ``(nan, nan)``: the
    nominal pose is outside the tolerance).
    """

    x: tuple[float, float]
    y: tuple[float, float]
    theta: tuple[float, float]


def contains(spec: SocketSpec, poses: object) -> np.ndarray:
    """Whether each pose ``[..., 3]`` = ``[x, y, theta]`` puts every pin in its hole.

    Returns a bool array of shape ``poses.shape[:-1]``. Boundaries are inside.
    """
    _check_spec(spec)
    array = _checked_poses(poses)
    x, y, theta = array[..., 0], array[..., 1], array[..., 2]
    if isinstance(spec, CircularSocket):
        return _circle_contains(spec, x, y, theta)
    normals, hole_inradius = _polygon_geometry(spec)
    gauge = np.max(x[..., None] * normals[:, 0] + y[..., None] * normals[:, 1], axis=-1)
    period = _TWO_PI / spec.sides
    support = spec.pin_circumradius * np.cos(np.mod(theta, period) - period / 2)
    return gauge + support <= hole_inradius


def _circle_contains(
    spec: CircularSocket, x: np.ndarray, y: np.ndarray, theta: np.ndarray
) -> np.ndarray:
    """``|R(theta) p_i + (x, y) - h_i| <= clearance`` for all pins, as one matrix product."""
    _, _, clearance2 = _circle_geometry(spec)
    basis, offset = _circle_basis(spec)
    terms = np.empty((*x.shape, 4))
    terms[..., 0], terms[..., 1], terms[..., 2], terms[..., 3] = np.cos(theta), np.sin(theta), x, y
    # Columns: the moved pins' x - hole x for every pin, then their y - hole y.
    gap = terms @ basis
    gap += offset
    gap *= gap
    n = spec.n_pins
    return np.all(gap[..., :n] + gap[..., n:] <= clearance2, axis=-1)


def image(
    spec: SocketSpec, resolution: int = 64, *, window: ImageWindow | None = None
) -> np.ndarray:
    """The paper's flattened tolerance: the largest theta of each ``(x, y)`` cell.

    ``image[i, j]`` is at ``x = axis[j]``, ``y = axis[i]`` with ``axis =
    window.axis(resolution)`` (default window: ``WINDOWS[spec.family]``). Its value is the
    largest ``theta`` such that every pose ``[x, y, t]`` with ``0 <= t <= theta`` is in
    the tolerance, capped at ``window.theta_cap``, or :data:`NO_TOLERANCE` where
    ``[x, y, 0]`` is outside it. Only the upper part (theta ≥ 0) is stored, as in the paper.
    """
    _check_spec(spec)
    resolution = check_int("resolution", resolution, minimum=2)
    window = window or WINDOWS[spec.family]
    axis = window.axis(resolution)
    x, y = np.meshgrid(axis, axis)
    reach = _theta_reach(spec, x.ravel(), y.ravel(), sign=1.0)
    values = np.where(np.isnan(reach), NO_TOLERANCE, np.minimum(reach, window.theta_cap))
    return values.reshape(resolution, resolution)


def extents(spec: SocketSpec) -> Extents:
    """The x, y and theta extents of the tolerance through the nominal pose (:class:`Extents`)."""
    _check_spec(spec)
    zero = np.zeros(1)
    up, down = (float(_theta_reach(spec, zero, zero, sign=s)[0]) for s in (1.0, -1.0))
    theta = (math.nan, math.nan) if math.isnan(up) else (-down, up)
    return Extents(x=_line_extent(spec, axis=0), y=_line_extent(spec, axis=1), theta=theta)


def _line_extent(spec: SocketSpec, axis: int) -> tuple[float, float]:
    """Interval of the coordinate ``axis`` (0: x, 1: y) with the other two at 0."""
    if isinstance(spec, CircularSocket):
        pins, holes, clearance2 = _circle_geometry(spec)
        along, across = (pins - holes)[:, axis], (pins - holes)[:, 1 - axis]
        if np.any(across * across > clearance2):
            return (math.nan, math.nan)
        half = np.sqrt(clearance2 - across * across)
        low, high = float(np.max(-along - half)), float(np.min(-along + half))
        return (low, high) if low <= high else (math.nan, math.nan)
    normals, hole_inradius = _polygon_geometry(spec)
    # max_k n_k[axis] * s <= gap, where the largest n_k[axis] is > 0 and the smallest < 0.
    gap = hole_inradius - inradius(spec.sides, spec.pin_circumradius)
    return (float(gap / np.min(normals[:, axis])), float(gap / np.max(normals[:, axis])))


def _theta_reach(spec: SocketSpec, x: np.ndarray, y: np.ndarray, sign: float) -> np.ndarray:
    """Largest rotation ``t ≥ 0`` with ``[x, y, sign·t']`` inside for all ``t' ≤ t``.

    ``inf`` where it never leaves the tolerance, NaN where ``[x, y, 0]`` is outside.
    """
    if isinstance(spec, CircularSocket):
        pins, holes, clearance2 = _circle_geometry(spec)
        qx, qy = x[:, None] - holes[:, 0], y[:, None] - holes[:, 1]
        pin_norm = np.hypot(pins[:, 0], pins[:, 1])
        q_norm2 = qx * qx + qy * qy
        # |R p + q|² = |p|² + |q|² + 2 |p| |q| cos(theta + angle(p) - angle(q)) <= c²
        a = 2 * pin_norm * np.sqrt(q_norm2)
        beta = np.arctan2(pins[:, 1], pins[:, 0]) - np.arctan2(qy, qx)
        b = clearance2 - pin_norm * pin_norm - q_norm2
        # np.min propagates NaN: one pin outside its hole puts the pose outside.
        return np.min(_arc_reach(a, sign * beta, b), axis=1)
    normals, hole_inradius = _polygon_geometry(spec)
    gauge = np.max(x[:, None] * normals[:, 0] + y[:, None] * normals[:, 1], axis=1)
    # Symmetric in theta: the vertex at -π/n meets the faces first.
    return _arc_reach(spec.pin_circumradius, -math.pi / spec.sides, hole_inradius - gauge)


def _arc_reach(a: np.ndarray | float, beta: np.ndarray | float, b: np.ndarray) -> np.ndarray:
    """Largest ``t ≥ 0`` with ``a cos(t' + beta) <= b`` for all ``0 <= t' <= t`` (``a ≥ 0``).

    ``inf`` where the constraint always holds, NaN where it fails at ``t = 0``.
    """
    a, beta, b = np.broadcast_arrays(a, beta, b)
    unbounded = b >= a
    ratio = np.clip(b / np.where(a > 0, a, 1.0), -1.0, 1.0)
    # The constraint holds for (t + beta) mod 2π in [arccos(ratio), 2π - arccos(ratio)].
    reach = np.maximum(_TWO_PI - np.arccos(ratio) - np.mod(beta, _TWO_PI), 0.0)
    reach = np.where(unbounded, np.inf, reach)
    return np.where(a * np.cos(beta) <= b, reach, np.nan)


def pins_inside(spec: CircularSocket, offsets: object, poses: object) -> np.ndarray:
    """Whether each pin is in its hole, for every workpiece in ``offsets`` and pose in ``poses``.

    ``offsets`` ``[..., n_pins, 2]`` replaces the spec's own pin offsets (mm); ``poses``
    ``[..., 3]`` are ``[x, y, theta]``; the two leading shapes broadcast. Pin ``i`` is in
    iff ``|R(theta) (n_i + eps_i) + (x, y) - h_i| <= c_i`` (``n_i``: the pin's place
    before bends, pitch error included; ``c_i``: its clearance, burrs and blocked holes
    included, as :func:`contains`). Returns a
    bool array ``broadcast(offsets.shape[:-2], poses.shape[:-1]) + (n_pins,)``;
    ``pins_inside(...).all(-1)`` is :func:`contains` of each offset workpiece.
    """
    return gaps_inside(spec, pin_gaps(spec, offsets, poses))


def pin_gaps(spec: CircularSocket, offsets: object, poses: object) -> np.ndarray:
    """Each pin's centre minus its hole's centre ``(..., n_pins, 2)`` (mm), as :func:`pins_inside`.

    The gap of pin ``i`` is ``R(theta) (n_i + eps_i) + (x, y) - h_i`` (``n_i``: the hole
    centre, scaled by any pitch error); the pin is in its hole iff the gap's length is at
    most its clearance (:func:`gaps_inside`), and a blocked pin rests on the board on the
    side the gap points to.
    """
    if not isinstance(spec, CircularSocket):
        raise ValueError(f"spec={spec!r}; allowed: a CircularSocket")
    array = _checked_poses(poses)
    eps = _checked_offsets(spec, offsets)
    if spec.pin_pitch_scale is None:
        return _pin_gaps(spec.hole_centers, eps, array)
    return moved_pins(spec.nominal_pin_centers + eps, array) - spec.hole_centers


def gaps_inside(spec: CircularSocket, gaps: np.ndarray) -> np.ndarray:
    """Whether each pin with gap ``gaps`` ``(..., n_pins, 2)`` (:func:`pin_gaps`) is in its
    hole (within its own clearance; never in a blocked hole)."""
    if spec.pin_burrs is None and not spec.blocked_holes:
        return np.sum(gaps * gaps, axis=-1) <= spec.clearance * spec.clearance
    return np.sum(gaps * gaps, axis=-1) <= _circle_geometry(spec)[2]


def pin_levels(spec: SocketSpec) -> np.ndarray:
    """Height ``(n_pins,)`` (mm) of each pin's tip over a full-length pin's tip: its
    shortening (zeros for a polygon peg). Pin ``i`` meets the board's top when the pose's
    ``z = -level_i``."""
    if isinstance(spec, CircularSocket):
        return spec.shortenings
    return np.zeros(1)


def pins_inside_pose(spec: SocketSpec, poses: object) -> np.ndarray:
    """Whether each pin is in its hole at each pose ``[..., 3]``: ``(..., n_pins)`` bools;
    ``.all(-1)`` is :func:`contains`."""
    _check_spec(spec)
    array = _checked_poses(poses)
    if isinstance(spec, CircularSocket):
        return gaps_inside(spec, pin_gaps(spec, spec.offsets, array))
    return contains(spec, array)[..., None]


def moved_pins(pins: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """World ``(x, y)`` ``(..., n_pins, 2)`` of pin centres ``pins`` ``[..., n_pins, 2]``
    (workpiece frame) at poses ``[..., >= 3]``: ``R(theta) p + (x, y)``."""
    cos, sin = np.cos(poses[..., 2])[..., None], np.sin(poses[..., 2])[..., None]
    x = cos * pins[..., 0] - sin * pins[..., 1] + poses[..., 0, None]
    y = sin * pins[..., 0] + cos * pins[..., 1] + poses[..., 1, None]
    return np.stack([x, y], axis=-1)


def _pin_gaps(holes: np.ndarray, eps: np.ndarray, poses: np.ndarray) -> np.ndarray:
    return moved_pins(holes + eps, poses) - holes


def _checked_offsets(spec: CircularSocket, offsets: object) -> np.ndarray:
    eps = np.asarray(offsets, dtype=float)
    if eps.ndim < 2 or eps.shape[-2:] != (spec.n_pins, 2) or not np.isfinite(eps).all():
        raise ValueError(
            f"offsets has shape {eps.shape} or non-finite values; allowed: finite "
            f"[..., {spec.n_pins}, 2] in mm"
        )
    return eps


@functools.lru_cache(maxsize=256)
def _circle_geometry(spec: CircularSocket) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pin centres (offsets included), hole centres and each pin's squared radial clearance
    ``(n_pins,)``, ``-1`` where the pin never fits (burred beyond its hole, or blocked);
    read-only."""
    pins, holes = spec.pin_centers, spec.hole_centers
    clearances = spec.pin_clearances
    clearance2 = np.where(clearances >= 0, clearances * clearances, -1.0)
    for array in (pins, holes, clearance2):
        array.setflags(write=False)
    return pins, holes, clearance2


@functools.lru_cache(maxsize=256)
def _circle_basis(spec: CircularSocket) -> tuple[np.ndarray, np.ndarray]:
    """``basis`` ``(4, 2n)`` and ``offset`` ``(2n,)`` with ``[cos, sin, x, y] @ basis + offset``
    the moved pins' x then y coordinates relative to their holes."""
    pins, holes, _ = _circle_geometry(spec)
    px, py = pins[:, 0], pins[:, 1]
    zero, one = np.zeros(spec.n_pins), np.ones(spec.n_pins)
    basis = np.array(
        [np.append(px, py), np.append(-py, px), np.append(one, zero), np.append(zero, one)]
    )
    offset = -np.append(holes[:, 0], holes[:, 1])
    basis.setflags(write=False)
    offset.setflags(write=False)
    return basis, offset


@functools.lru_cache(maxsize=256)
def _polygon_geometry(spec: PolygonSocket) -> tuple[np.ndarray, float]:
    """Face normals ``(sides, 2)`` of the hole (angles ``2πk/n``) and its inradius."""
    angles = np.arange(spec.sides) * (_TWO_PI / spec.sides)
    normals = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    normals.setflags(write=False)
    return normals, inradius(spec.sides, spec.hole_circumradius)


def _check_spec(spec: object) -> None:
    if not isinstance(spec, (CircularSocket, PolygonSocket)):
        raise ValueError(f"spec={spec!r}; allowed: a CircularSocket or PolygonSocket")


def _checked_poses(poses: object) -> np.ndarray:
    allowed = "allowed: an array [..., 3] of [x, y, theta] in mm and rad"
    try:
        array = np.asarray(poses, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f"poses={poses!r} is not numeric; {allowed}") from error
    if array.ndim == 0 or array.shape[-1] != 3:
        raise ValueError(f"poses has shape {array.shape}; {allowed}")
    if not np.isfinite(array).all():
        bad = np.argwhere(~np.isfinite(array))[0].tolist()
        raise ValueError(f"poses{bad} = {float(array[tuple(bad)])} is not finite; {allowed}")
    return array
