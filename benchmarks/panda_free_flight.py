"""Can the Panda take longer physics steps in free flight, as the free body's ``-v2`` does?

Usage::

    python benchmarks/panda_free_flight.py [--factors 1,2,4,5] [--steps 12] [--seed 0]

The part is lifted and swung in the air, far from the board (nothing but the fingers
touches it), then lowered, for ``--steps`` control steps of ``tolins/Circle2x2Panda-v3``,
with the physics step ``factor`` times the contact step (1 ms) and the law updated at the
same 500 Hz (every ``2 / factor`` steps, at least every step). Printed per factor: the
control step the episode ended at (a part lost from the hand is a fault), the part's slip
in the hand at the end (true pose against the robot's belief, mm and rad) and the largest
difference of the part's pose from the 1 ms run's over the steps both ran.
"""

from __future__ import annotations

import argparse
import copy

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.physics.panda import update_plan


def swing(factor: int, steps: int, seed: int) -> tuple[np.ndarray, np.ndarray, str | None]:
    """The part's true poses, its last slip in the hand and the fault, if any."""
    env = gym.make("tolins/Circle2x2Panda-v3", measurement_noise=0.0).unwrapped
    env.reset(seed=seed)
    sims = env.backend._batch.sims
    if factor > 1:
        model = copy.copy(sims.models[0])
        model.opt.timestep *= factor
        sims.models[0] = model
        sims.every = max(1, sims.every // factor)
        sims.plan = update_plan(sims.nstep // factor, sims.checks, sims.every)
        sims._span = sims.every * model.opt.timestep
    poses, slip, fault = [], np.zeros(4), None
    for k in range(steps):
        up = 2.0 if k < steps // 2 else -2.0
        action = np.array([2.0 * np.sin(k), 2.0 * np.cos(k), 0.05 * np.sin(2 * k), up])
        _, _, terminated, truncated, info = env.step(action)
        poses.append(info["pose"].copy())
        slip = np.abs(info["pose"] - info["sensed_pose"])
        if "error" in info or terminated or truncated:
            fault = info.get("error")
            break
    return np.array(poses), slip, fault


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--factors", default="1,2,4,5")
    parser.add_argument("--steps", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(
        "| physics step | control steps run | fault | slip at the end [x, y, θ, z] "
        "| largest pose difference from 1 ms [x, y, θ, z] |\n|--:|--:|---|---|---|"
    )
    reference = None
    for factor in (int(f) for f in args.factors.split(",")):
        poses, slip, fault = swing(factor, args.steps, args.seed)
        if reference is None:
            reference = poses
        n = min(len(poses), len(reference))
        differ = np.abs(poses[:n] - reference[:n]).max(axis=0) if n else np.full(4, np.nan)
        print(
            f"| {factor} ms | {len(poses)} | {fault or '–'} | {np.round(slip, 4).tolist()} "
            f"| {np.round(differ, 4).tolist()} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
