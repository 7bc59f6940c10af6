"""Socket specifications: frozen, validated dataclasses in millimetres and radians.

Conventions (shared by every part of tolins):

* The board's top surface is ``z = 0``; the target pose of a nominal socket is
  ``[x, y, theta] = [0, 0, 0]``.
* Pins are numbered row-major. Row ``r`` lies at ``y = (r - (rows - 1) / 2) * row_pitch``,
  column ``c`` at ``x = (c - (cols - 1) / 2) * col_pitch``.
* Regular polygons have their vertices at angles ``(2k + 1) * pi / sides``, so one
  face normal points along +x (a square is axis-aligned).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from tolins.geometry.validation import check_int, check_positive, checked_array

#: Thinnest board wall (mm) allowed between two neighbouring holes.
MIN_WALL = 0.2
#: Number of sides of the polygon that stands in for a circular hole (face distance = radius).
CIRCLE_HOLE_SIDES = 16
#: Most pins of a circular socket (a 20*20 socket) and most sides of a polygon peg: the
#: model's size (and compile time) grows with both.
MAX_PINS = 400
MAX_SIDES = 64
#: Largest extent (mm) of a socket: every hole, at its circumradius, within this of the
#: socket's centre along x and y (its pins stay in their holes' cells). The presets reach
#: 9.5 mm (the 2*8), a 20*20 socket at 10 mm pitch 95.5. The board, covering every place
#: a pin reaches in the servo range, then stays within 130 mm of the centre, clear of the
#: Panda's base 450 mm away, and every workpiece hangs from the same handle with the same
#: mass (:mod:`tolins.mjcf.panda`).
MAX_EXTENT = 100.0
#: Largest bend of a pin (mm) along an axis with a single hole (along an axis with more,
#: its cell bounds it): ten times the clearance of the paper's sockets.
MAX_PIN_OFFSET = 2.0
#: Largest relative pitch error of a workpiece: its pins' spacing is the holes' times a
#: scale in ``[1 - MAX_PITCH_ERROR, 1 + MAX_PITCH_ERROR]`` (and every pin in its cell).
MAX_PITCH_ERROR = 0.1
#: Largest burr (mm) of a pin: its radius grows by at most this (and it stays in its cell).
MAX_BURR = 0.5
#: Largest shortening (mm) of a pin: half the pins' length (``workspace.PIN_LENGTH``).
MAX_SHORTENING = 2.0


def polygon_vertices(sides: int, circumradius: float) -> np.ndarray:
    """Vertices ``(sides, 2)`` of a regular polygon with a face normal along +x."""
    angles = (2 * np.arange(sides) + 1) * np.pi / sides
    return circumradius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


def inradius(sides: int, circumradius: float) -> float:
    """Distance from the centre of a regular polygon to its faces."""
    return circumradius * math.cos(math.pi / sides)


def check_extent(fields: str, hole_centers: np.ndarray, hole_circumradius: float) -> None:
    """``ValueError`` naming ``fields`` unless every hole lies within :data:`MAX_EXTENT` of
    the centre."""
    extent = float(np.max(np.abs(hole_centers))) + hole_circumradius
    if extent > MAX_EXTENT:
        raise ValueError(
            f"{fields}: a hole reaches {extent:.6g} mm from the socket's centre; allowed: "
            f"every hole within {MAX_EXTENT:g} mm of it along x and y (centre plus "
            "circumradius)"
        )


@dataclass(frozen=True)
class CircularSocket:
    """An n×m grid of circular pins over a board with as many round holes.

    Args:
        rows: Number of pin rows (along y), ≥ 1.
        cols: Number of pins per row (along x), ≥ 1.
        pin_radius: Pin radius in mm, smaller than ``hole_radius``.
        hole_radius: Hole radius in mm.
        row_pitch: Distance between rows in mm.
        col_pitch: Distance between columns in mm.
        pin_offsets: Bent pins: an array ``(rows * cols, 2)`` of each pin's horizontal
            displacement in mm from its nominal place (the holes stay nominal).
            ``None`` means a nominal workpiece. Stored as a tuple of ``(dx, dy)`` pairs
            so that specs are hashable; use :attr:`offsets` for the array.
        pin_pitch_scale: Pitch error: ``(col_scale, row_scale)``, the pins' column and row
            spacing as a multiple of the holes' (each within ``1 ± MAX_PITCH_ERROR``): pin
            ``i`` sits at ``h_i * scale + offset_i``. ``None``: no pitch error.
        pin_burrs: Oversized (burred) pins: per pin, mm ``≥ 0`` added to its radius (at most
            :data:`MAX_BURR`); a pin whose radius reaches the hole's never goes in.
            ``None``: none.
        pin_shortenings: Short pins: per pin, mm ``≥ 0`` (at most :data:`MAX_SHORTENING`)
            missing at its tip, so it meets the board that much later (lower); the pose's
            ``z`` stays the height of a full-length pin's tip. ``None``: none.
        blocked_holes: Blocked holes: the sorted indices of holes with a plug in them; a
            workpiece with one is never insertable. ``()``: none.

    Every pin (pitch error and bend included, at its burred radius) must stay in its cell:
    ``|pin_i - h_i| ≤ pitch / 2 - (pin_radius + burr_i)`` along an axis with more than one
    hole, ``≤ MAX_PIN_OFFSET`` along one with a single hole.
    """

    rows: int
    cols: int
    pin_radius: float = 0.3
    hole_radius: float = 0.5
    row_pitch: float = 7.62
    col_pitch: float = 2.54
    pin_offsets: tuple[tuple[float, float], ...] | None = field(default=None)
    pin_pitch_scale: tuple[float, float] | None = None
    pin_burrs: tuple[float, ...] | None = None
    pin_shortenings: tuple[float, ...] | None = None
    blocked_holes: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "rows", check_int("rows", self.rows, minimum=1))
        set_(self, "cols", check_int("cols", self.cols, minimum=1))
        if self.rows * self.cols > MAX_PINS:
            raise ValueError(
                f"rows={self.rows!r} × cols={self.cols!r} = {self.rows * self.cols} pins; "
                f"allowed: at most {MAX_PINS} pins"
            )
        for name in ("pin_radius", "hole_radius", "row_pitch", "col_pitch"):
            set_(self, name, check_positive(name, getattr(self, name)))
        if self.pin_radius >= self.hole_radius:
            raise ValueError(
                f"pin_radius={self.pin_radius!r} is not smaller than hole_radius="
                f"{self.hole_radius!r}; allowed: pin_radius < hole_radius"
            )
        wall_span = 2 * self.hole_circumradius + MIN_WALL
        for name, count in (("row_pitch", self.rows), ("col_pitch", self.cols)):
            pitch = getattr(self, name)
            if count > 1 and pitch < wall_span:
                raise ValueError(
                    f"{name}={pitch!r} leaves no wall between holes of radius "
                    f"{self.hole_radius!r}; allowed: {name} ≥ {wall_span:.4g} mm "
                    f"(two hole circumradii plus a {MIN_WALL} mm wall)"
                )
        sizes = ", ".join(
            f"{name}={getattr(self, name)!r}"
            for name in ("rows", "cols", "hole_radius", "row_pitch", "col_pitch")
        )
        check_extent(sizes, self.hole_centers, self.hole_circumradius)
        set_(self, "pin_pitch_scale", self._validated_pitch(self.pin_pitch_scale))
        for name, limit in (("pin_burrs", MAX_BURR), ("pin_shortenings", MAX_SHORTENING)):
            set_(self, name, self._validated_per_pin(name, getattr(self, name), limit))
        set_(self, "blocked_holes", self._validated_blocked(self.blocked_holes))
        set_(self, "pin_offsets", self._validated_offsets(self.pin_offsets))
        self._check_cells()

    def _validated_pitch(self, scale: object) -> tuple[float, float] | None:
        if scale is None:
            return None
        allowed = (
            f"None or (col_scale, row_scale), each within 1 ± {MAX_PITCH_ERROR} "
            "(the pins' spacing over the holes')"
        )
        array = checked_array("pin_pitch_scale", scale, (2,), allowed)
        if np.any(np.abs(array - 1.0) > MAX_PITCH_ERROR + 1e-12):
            raise ValueError(
                f"pin_pitch_scale={array.tolist()!r} is out of range; allowed: {allowed}"
            )
        return (float(array[0]), float(array[1]))

    def _validated_per_pin(
        self, name: str, values: object, limit: float
    ) -> tuple[float, ...] | None:
        if values is None:
            return None
        allowed = f"None or {self.n_pins} values in [0, {limit}] mm, one per pin"
        array = checked_array(name, values, (self.n_pins,), allowed)
        if np.any(array < 0) or np.any(array > limit):
            raise ValueError(f"{name}={array.tolist()!r} is out of range; allowed: {allowed}")
        return tuple(float(v) for v in array)

    def _validated_blocked(self, holes: object) -> tuple[int, ...]:
        allowed = f"a tuple of distinct hole indices 0 … {self.n_pins - 1}"
        if not isinstance(holes, (tuple, list)):
            raise ValueError(f"blocked_holes={holes!r} is not a tuple; allowed: {allowed}")
        indices = [
            check_int("blocked_holes[]", h, minimum=0, maximum=self.n_pins - 1) for h in holes
        ]
        if len(set(indices)) != len(indices):
            raise ValueError(f"blocked_holes={holes!r} repeats a hole; allowed: {allowed}")
        return tuple(sorted(indices))

    def _check_cells(self) -> None:
        """Every pin, at its burred radius, where pitch error and bend put it, in its cell."""
        if self.pin_pitch_scale is None and self.pin_burrs is None:
            return  # _validated_offsets has checked the bends against offset_limit
        displacement = np.abs(self.pin_centers - self.hole_centers)
        burrs = self.burrs[:, None]
        limit = self.offset_limit
        multi = np.array([self.cols > 1, self.rows > 1])
        outside = np.any(displacement > limit - np.where(multi, burrs, 0.0) + 1e-12, axis=1)
        if np.any(outside):
            pin = int(np.argmax(outside))
            raise ValueError(
                f"pin {pin} (pitch scale {self.pin_pitch_scale!r}, offset "
                f"{self.offsets[pin].tolist()!r}, burr {float(self.burrs[pin])!r}) reaches out "
                "of its cell; allowed: |pin - hole| ≤ pitch / 2 - (pin_radius + burr) along "
                f"an axis with several holes, ≤ {MAX_PIN_OFFSET} mm along one with a single hole"
            )

    def _validated_offsets(self, offsets: object) -> tuple[tuple[float, float], ...] | None:
        if offsets is None:
            return None
        try:
            array = np.asarray(offsets, dtype=float)
        except (TypeError, ValueError) as error:
            raise ValueError(
                f"pin_offsets={offsets!r} is not numeric; allowed: an array of shape "
                f"({self.n_pins}, 2) in mm"
            ) from error
        if array.shape != (self.n_pins, 2):
            raise ValueError(
                f"pin_offsets has shape {array.shape}; allowed: ({self.n_pins}, 2) "
                f"for a {self.rows}*{self.cols} socket"
            )
        if not np.all(np.isfinite(array)):
            raise ValueError(
                f"pin_offsets={array.tolist()!r} contains NaN or inf; allowed: finite mm"
            )
        half_cell = self.offset_limit
        outside = np.any(np.abs(array) > half_cell, axis=1)
        if np.any(outside):
            pin = int(np.argmax(outside))
            raise ValueError(
                f"pin_offsets[{pin}]={array[pin].tolist()!r} moves pin {pin} out of its cell; "
                f"allowed: |dx| ≤ {half_cell[0]:.4g} mm and |dy| ≤ {half_cell[1]:.4g} mm"
            )
        return tuple((float(dx), float(dy)) for dx, dy in array)

    @property
    def n_pins(self) -> int:
        return self.rows * self.cols

    @property
    def family(self) -> str:
        return "circle"

    @property
    def is_defective(self) -> bool:
        bent = self.pin_offsets is not None and any(dx or dy for dx, dy in self.pin_offsets)
        pitch = self.pin_pitch_scale is not None and self.pin_pitch_scale != (1.0, 1.0)
        burred = self.pin_burrs is not None and any(self.pin_burrs)
        short = self.pin_shortenings is not None and any(self.pin_shortenings)
        return bent or pitch or burred or short or bool(self.blocked_holes)

    @property
    def pin_reach(self) -> float:
        """Radius of the smallest circle about a pin's centre that holds the pin (mm): the
        largest burred radius."""
        if self.pin_burrs is None:
            return self.pin_radius
        return self.pin_radius + max(self.pin_burrs)

    @property
    def burrs(self) -> np.ndarray:
        """Each pin's burr ``(n_pins,)`` in mm (zeros without)."""
        return np.zeros(self.n_pins) if self.pin_burrs is None else np.array(self.pin_burrs)

    @property
    def shortenings(self) -> np.ndarray:
        """Each pin's shortening ``(n_pins,)`` in mm (zeros without)."""
        if self.pin_shortenings is None:
            return np.zeros(self.n_pins)
        return np.array(self.pin_shortenings)

    @property
    def pin_radii(self) -> np.ndarray:
        """Each pin's radius ``(n_pins,)`` in mm, burrs included."""
        return self.pin_radius + self.burrs

    @property
    def pin_clearances(self) -> np.ndarray:
        """Each pin's radial clearance in its hole ``(n_pins,)`` (mm): ``hole_radius -
        pin_radius - burr``; ``-inf`` for a blocked hole. A pin fits only where it is ≥ 0."""
        clearances = self.hole_radius - self.pin_radii
        clearances[list(self.blocked_holes)] = -np.inf
        return clearances

    @property
    def offset_limit(self) -> np.ndarray:
        """Largest ``(|dx|, |dy|)`` (mm) of a pin offset, so that a pin stays in its cell:
        half the pitch less a pin radius (neighbours cannot touch); along an axis with a
        single hole, :data:`MAX_PIN_OFFSET`."""
        return np.array(
            [
                self.col_pitch / 2 - self.pin_radius if self.cols > 1 else MAX_PIN_OFFSET,
                self.row_pitch / 2 - self.pin_radius if self.rows > 1 else MAX_PIN_OFFSET,
            ]
        )

    @property
    def hole_circumradius(self) -> float:
        """Circumradius of the polygon that models each round hole."""
        return self.hole_radius / math.cos(math.pi / CIRCLE_HOLE_SIDES)

    @property
    def offsets(self) -> np.ndarray:
        """Pin offsets ``(n_pins, 2)`` in mm (zeros for a nominal workpiece)."""
        if self.pin_offsets is None:
            return np.zeros((self.n_pins, 2))
        return np.array(self.pin_offsets, dtype=float)

    @property
    def hole_centers(self) -> np.ndarray:
        """Nominal hole (and pin) centres ``(n_pins, 2)`` in mm, row-major."""
        r, c = np.meshgrid(np.arange(self.rows), np.arange(self.cols), indexing="ij")
        x = (c.ravel() - (self.cols - 1) / 2) * self.col_pitch
        y = (r.ravel() - (self.rows - 1) / 2) * self.row_pitch
        return np.stack([x, y], axis=1).astype(float)

    @property
    def nominal_pin_centers(self) -> np.ndarray:
        """Pin centres ``(n_pins, 2)`` before bends: the hole centres, pitch error included."""
        if self.pin_pitch_scale is None:
            return self.hole_centers
        return self.hole_centers * np.array(self.pin_pitch_scale)

    @property
    def pin_centers(self) -> np.ndarray:
        """Actual pin centres ``(n_pins, 2)`` in the workpiece frame, pitch error and
        offsets included."""
        return self.nominal_pin_centers + self.offsets

    @property
    def clearance(self) -> float:
        """Radial clearance of a nominal pin in its hole (mm)."""
        return self.hole_radius - self.pin_radius

    def nominal(self) -> CircularSocket:
        """The same socket without defects."""
        return CircularSocket(
            self.rows, self.cols, self.pin_radius, self.hole_radius, self.row_pitch, self.col_pitch
        )


@dataclass(frozen=True)
class PolygonSocket:
    """A single regular-polygon peg in a same-shaped hole, both centred at the origin.

    Args:
        sides: Number of sides, ≥ 3.
        pin_circumradius: Circumradius of the peg in mm.
        hole_circumradius: Circumradius of the hole in mm, larger than the peg's.
    """

    sides: int
    pin_circumradius: float
    hole_circumradius: float

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "sides", check_int("sides", self.sides, minimum=3, maximum=MAX_SIDES)
        )
        for name in ("pin_circumradius", "hole_circumradius"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        if self.pin_circumradius >= self.hole_circumradius:
            raise ValueError(
                f"pin_circumradius={self.pin_circumradius!r} is not smaller than "
                f"hole_circumradius={self.hole_circumradius!r}; allowed: pin < hole"
            )
        check_extent(
            f"hole_circumradius={self.hole_circumradius!r}",
            self.hole_centers,
            self.hole_circumradius,
        )

    @property
    def n_pins(self) -> int:
        return 1

    @property
    def family(self) -> str:
        return "polygon"

    @property
    def is_defective(self) -> bool:
        return False

    @property
    def pin_reach(self) -> float:
        """Radius of the smallest circle about the peg's centre that holds the peg (mm)."""
        return self.pin_circumradius

    @property
    def hole_centers(self) -> np.ndarray:
        return np.zeros((1, 2))

    @property
    def pin_centers(self) -> np.ndarray:
        return np.zeros((1, 2))

    @property
    def clearance(self) -> float:
        """Face-to-face clearance of the centred peg (mm)."""
        return inradius(self.sides, self.hole_circumradius) - inradius(
            self.sides, self.pin_circumradius
        )


SocketSpec = CircularSocket | PolygonSocket


#: The tolerance grades of the presets: radial (face-to-face) clearances in µm.
GRADES_UM = (200, 100, 50, 20)


def with_clearance(spec: SocketSpec, clearance: float) -> SocketSpec:
    """``spec`` (nominal) with its holes resized to a radial clearance of ``clearance`` mm,
    pins unchanged: a round hole of radius ``pin_radius + clearance``, a polygon hole whose
    faces lie ``clearance`` beyond the peg's (``spec.clearance == clearance``)."""
    clearance = check_positive("clearance", clearance)
    if isinstance(spec, CircularSocket):
        return dataclasses.replace(spec.nominal(), hole_radius=spec.pin_radius + clearance)
    if isinstance(spec, PolygonSocket):
        grow = clearance / math.cos(math.pi / spec.sides)
        return dataclasses.replace(spec, hole_circumradius=spec.pin_circumradius + grow)
    raise ValueError(f"spec={spec!r}; allowed: a CircularSocket or PolygonSocket")


def workpiece_dict(spec: SocketSpec) -> dict[str, object]:
    """``spec`` as JSON-ready data, the ground truth of an episode's workpiece:
    ``{"type": "CircularSocket", "rows": 2, ..., "pin_offsets": [[dx, dy], ...] or None,
    "pin_pitch_scale": ..., "pin_burrs": ..., "pin_shortenings": ..., "blocked_holes":
    [...], "defective": bool}`` (tuples as lists; ``type(spec)(**fields)`` of every key but
    ``type`` and ``defective`` rebuilds it)."""
    fields: dict[str, object] = {"type": type(spec).__name__}
    for item in dataclasses.fields(spec):
        value = getattr(spec, item.name)
        if isinstance(value, tuple):
            value = [list(v) if isinstance(v, tuple) else v for v in value]
        fields[item.name] = value
    fields["defective"] = spec.is_defective
    return fields
