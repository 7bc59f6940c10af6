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
    """

    poses: np.ndarray
    inserted: np.ndarray
    blocked: np.ndarray | None = None
    measurement_noise: np.ndarray | None = None

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

    @classmethod
    def empty(cls, measurement_noise: object = None) -> History:
        """No attempt yet."""
        return cls(np.zeros((0, 3)), np.zeros(0, dtype=bool), None, measurement_noise)

    def __len__(self) -> int:
        return len(self.poses)

    def append(self, pose: object, inserted: bool, blocked: object = None) -> History:
        """A new history with one more attempt (``blocked`` only if the history has them)."""
        if len(self) and (blocked is None) != (self.blocked is None):
            raise ValueError("blocked must be given for every attempt or for none")
        rows = None
        if blocked is not None:
            row = np.asarray(blocked, dtype=bool)[None]
            rows = row if self.blocked is None else np.concatenate([self.blocked, row])
        return History(
            np.concatenate([self.poses, np.asarray(pose, dtype=float).reshape(1, 3)]),
            np.append(self.inserted, bool(inserted)),
            rows,
            self.measurement_noise,
        )


def _finite(name: str, value: object) -> np.ndarray:
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name}={value!r} is not numeric") from error
    if not np.isfinite(array).all():
        raise ValueError(f"{name} contains NaN or inf; allowed: finite values")
    return array
