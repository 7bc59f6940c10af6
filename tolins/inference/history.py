"""The insertion attempts made on one workpiece so far."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class History:
    """Attempts ``j = 1..m`` on one workpiece: truncated pose, outcome and optional contacts.

    Attributes:
        poses: ``(m, 3)`` poses ``[x, y, theta]`` (mm, rad) of the attempts: the true ones,
            or the measured ones ``ŝ_j`` when ``measurement_noise`` is given.
        inserted: ``(m,)`` outcomes ``I_j`` (True: inserted).
        blocked: ``(m, n_pins)`` contact evidence, or None: which pins the board blocked
            (the pin is outside its hole). Must be all False where ``inserted``.
        measurement_noise: Standard deviations ``(3,)`` of ``ŝ_j - s̄_j`` (mm, mm, rad),
            or None for exactly known poses.
        bearings: ``(m, n_pins)`` where each blocked pin touched the board: the angle (rad,
            board frame) of its touch point seen from its hole's centre; NaN for the pins
            not blocked or not measured. None: none measured. Needs ``blocked``.
        bearing_noise: Standard deviation (rad) of a measured bearing.
    """

    poses: np.ndarray
    inserted: np.ndarray
    blocked: np.ndarray | None = None
    measurement_noise: np.ndarray | None = None
    bearings: np.ndarray | None = None
    bearing_noise: float = 0.1

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        poses = _finite("poses", self.poses)
        if poses.ndim != 2 or poses.shape[1] != 3:
            raise ValueError(f"poses has shape {poses.shape}; allowed: (m, 3) of [x, y, theta]")
        inserted = np.asarray(self.inserted)
        if inserted.shape != (len(poses),) or inserted.dtype != bool:
            raise ValueError(
                f"inserted has shape {inserted.shape} and dtype {inserted.dtype}; "
                f"allowed: ({len(poses)},) bool"
            )
        set_(self, "poses", poses)
        set_(self, "inserted", inserted.copy())
        if self.blocked is not None:
            blocked = np.asarray(self.blocked)
            if blocked.ndim != 2 or len(blocked) != len(poses) or blocked.dtype != bool:
                raise ValueError(
                    f"blocked has shape {blocked.shape} and dtype {blocked.dtype}; "
                    f"allowed: ({len(poses)}, n_pins) bool"
                )
            if np.any(blocked[inserted]):
                raise ValueError("blocked marks a pin of an inserted attempt; allowed: none")
            set_(self, "blocked", blocked.copy())
        if self.measurement_noise is not None:
            noise = _finite("measurement_noise", self.measurement_noise)
            if noise.shape != (3,) or np.any(noise < 0):
                raise ValueError(f"measurement_noise={noise.tolist()}; allowed: 3 stds ≥ 0")
            set_(self, "measurement_noise", noise)
        if self.bearings is not None:
            set_(self, "bearings", self._checked_bearings())
        if not (np.isfinite(self.bearing_noise) and self.bearing_noise > 0):
            raise ValueError(f"bearing_noise={self.bearing_noise!r}; allowed: finite > 0 (rad)")

    def _checked_bearings(self) -> np.ndarray:
        if self.blocked is None:
            raise ValueError("bearings given without blocked; allowed: bearings with blocked")
        try:
            bearings = np.array(self.bearings, dtype=float)
        except (TypeError, ValueError) as error:
            raise ValueError(f"bearings={self.bearings!r} is not numeric") from error
        if bearings.shape != self.blocked.shape:
            raise ValueError(
                f"bearings has shape {bearings.shape}; allowed: {self.blocked.shape} like blocked"
            )
        if np.isinf(bearings).any() or np.any(np.isfinite(bearings) & ~self.blocked):
            raise ValueError(
                "bearings has inf or a bearing for a pin not blocked; allowed: finite "
                "values for blocked pins, NaN elsewhere"
            )
        return bearings

    @classmethod
    def empty(cls, measurement_noise: object = None, bearing_noise: float = 0.1) -> History:
        """No attempt yet."""
        return cls(
            np.zeros((0, 3)), np.zeros(0, dtype=bool), None, measurement_noise, None, bearing_noise
        )

    def __len__(self) -> int:
        return len(self.poses)

    def append(
        self, pose: object, inserted: bool, blocked: object = None, bearings: object = None
    ) -> History:
        """A new history with one more attempt.

        ``blocked`` and ``bearings`` are given for every attempt or for none.
        """
        if len(self) and (blocked is None) != (self.blocked is None):
            raise ValueError("blocked must be given for every attempt or for none")
        if len(self) and (bearings is None) != (self.bearings is None):
            raise ValueError("bearings must be given for every attempt or for none")
        return History(
            np.concatenate([self.poses, np.asarray(pose, dtype=float).reshape(1, 3)]),
            np.append(self.inserted, bool(inserted)),
            _rows(self.blocked, blocked, bool),
            self.measurement_noise,
            _rows(self.bearings, bearings, float),
            self.bearing_noise,
        )


def _rows(rows: np.ndarray | None, row: object, dtype: type) -> np.ndarray | None:
    """``rows`` with ``row`` appended (None when no row is given)."""
    if row is None:
        return None
    new = np.asarray(row, dtype=dtype)[None]
    return new if rows is None else np.concatenate([rows, new])


def _finite(name: str, value: object) -> np.ndarray:
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}={value!r} is not numeric") from error
    if not np.isfinite(array).all():
        raise ValueError(f"{name} contains NaN or inf; allowed: finite values")
    return array
