"""How the part settles in the Panda's hand after a reset: its offset over time, held still.

Usage::

    python benchmarks/panda_grasp_settling.py [--env tolins/Circle2x2Fit50Panda-v2]
        [--seconds 10] [--height 5]

A reset closes the fingers on the part with gravity off, then turns gravity on
(:mod:`tolins.physics.panda`). This resets ``--env`` (no measurement noise) with the part
``--height`` mm over the board, so that nothing touches it, commands zero velocity for
``--seconds`` and prints, per control step chosen, where the robot believes the part (its
forward kinematics and the nominal grasp) less where the part truly is: x, y in µm, θ in
mrad, z in µm.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.paper import CONTROL_DT


def offsets(env_id: str, seconds: float, height: float) -> list[tuple[float, np.ndarray]]:
    """(time after the reset in s, believed − true pose ``[x, y, θ, z]`` in µm and mrad)."""
    env = gym.make(env_id, measurement_noise=0.0)
    _, info = env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, height]})
    rows = [(0.0, (info["sensed_pose"] - info["pose"]) * 1e3)]
    steps = round(seconds / CONTROL_DT)
    shown = {1, 2, 4, 8, 12, 20, steps // 2, steps}
    for step in range(1, steps + 1):
        _, _, terminated, truncated, info = env.step(np.zeros(4))
        if step in shown:
            rows.append((step * CONTROL_DT, (info["sensed_pose"] - info["pose"]) * 1e3))
        if terminated or truncated:
            break
    env.close()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="tolins/Circle2x2Fit50Panda-v2")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--height", type=float, default=5.0, help="mm over the board")
    args = parser.parse_args()
    print(f"{args.env}, held still {args.height:g} mm over the board: believed − true")
    print("| t after the reset (s) | x (µm) | y (µm) | θ (mrad) | z (µm) |\n|--:|--:|--:|--:|--:|")
    for t, (x, y, theta, z) in offsets(args.env, args.seconds, args.height):
        print(f"| {t:.2f} | {x:+.1f} | {y:+.1f} | {theta:+.2f} | {z:+.1f} |")


if __name__ == "__main__":
    main()
