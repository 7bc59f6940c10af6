"""How much of a commanded motion the MuJoCo servos cover per control step, by control_dt.

The servos are re-anchored at the start of every control step (``ServoStepper.advance``),
so a short control step loses the servo's rise time: this measures the share of
``u_z · control_dt`` the workpiece moves in free air, in the first step from rest and
after 0.5 s of steady commands. Run: ``.venv/bin/python benchmarks/servo_tracking.py``.
"""

from __future__ import annotations

import numpy as np

from tolins import CircularSocket
from tolins.physics.mujoco import MujocoBackend

CONTROL_DTS = (0.002, 0.003, 0.005, 0.01, 0.02, 0.05, 0.1, 0.25, 1.0)
DOWN = np.array([0.0, 0.0, 0.0, -2.5])


def covered(control_dt: float) -> tuple[float, float]:
    """Share of the commanded z motion covered in the first and in a steady control step."""
    backend = MujocoBackend(CircularSocket(2, 2), control_dt)
    heights = [backend.reset([0.0, 0.0, 0.0, 30.0]).pose[3]]
    for _ in range(max(3, round(0.5 / control_dt))):
        heights.append(backend.step(DOWN).pose[3])
    commanded = 2.5 * control_dt
    return (heights[0] - heights[1]) / commanded, (heights[-2] - heights[-1]) / commanded


def main() -> None:
    print("| control_dt (s) | first step | steady |")
    print("|---|---|---|")
    for control_dt in CONTROL_DTS:
        first, steady = covered(control_dt)
        print(f"| {control_dt:g} | {first:.3f} | {steady:.3f} |")


if __name__ == "__main__":
    main()
