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

import math
from dataclasses import dataclass, field

import numpy as np

from tolins.geometry.validation import check_int, check_positive

#: Thinnest board wall (mm) allowed between two neighbouring holes.
MIN_WALL = 0.2
#: Number of sides of the polygon that stands in for a circular hole (face distance = radius).
CIRCLE_HOLE_SIDES = 16
#: Most pins of a circular socket (a 20*20 socket) and most sides of a polygon peg: the
#: model's size (and compile time) grows with both.
MAX_PINS = 400
MAX_SIDES = 64
#: Largest bend of a pin (mm) along an axis with a single hole (along an axis with more,
#: its cell bounds it): ten times the clearance of the paper's sockets.
MAX_PIN_OFFSET = 2.0


def polygon_vertices(sides: int, circumradius: float) -> np.ndarray:
    """Vertices ``(sides, 2)`` of a regular polygon with a face normal along +x."""
    angles = (2 * np.arange(sides) + 1) * np.pi / sides
    return circumradius * np.stack([np.cos(angles), np.sin(angles)], axis=1)


def inradius(sides: int, circumradius: float) -> float:
    """Distance from the centre of a regular polygon to its faces."""
    return circumradius * math.cos(math.pi / sides)


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
    """

    rows: int
    cols: int
    pin_radius: float = 0.3
    hole_radius: float = 0.5
    row_pitch: float = 7.62
    col_pitch: float = 2.54
    pin_offsets: tuple[tuple[float, float], ...] | None = field(default=None)

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
        set_(self, "pin_offsets", self._validated_offsets(self.pin_offsets))

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
        return self.pin_offsets is not None and any(dx or dy for dx, dy in self.pin_offsets)

    @property
    def pin_reach(self) -> float:
        """Radius of the smallest circle about a pin's centre that holds the pin (mm)."""
        return self.pin_radius

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
    def pin_centers(self) -> np.ndarray:
        """Actual pin centres ``(n_pins, 2)`` in the workpiece frame, offsets included."""
        return self.hole_centers + self.offsets

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
