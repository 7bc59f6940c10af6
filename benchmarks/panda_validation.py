"""The Panda ids against the free body: both experts, success, collisions, limits, slip, cost.

Usage::

    python benchmarks/panda_validation.py [--episodes 20] [--envs Circle2x2,Circle2x8,Square]

For each preset and its 50 µm grade, each expert runs ``--episodes`` episodes (seeds 0 …)
on ``tolins/{name}-v2`` (the free body on its servos) and on ``tolins/{name}Panda-v2`` (a
Franka Panda holding the part, :mod:`tolins.physics.panda`). Printed per row: success,
steps, collisions and reward (means), simulator faults (a part lost from the hand among
them); for the Panda also the largest slip of the part in the hand during an episode (its
true pose against the robot's belief, less the offset the grasp settled at), the share of
law updates with a motor at its torque limit, the closest approach of any joint to its
limit, and the wall time per control step against the free body's (goal ≤ 2×).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.physics import arm as arm_law
from tolins.policies import EXPERTS


class LimitWatch:
    """Counts the law's updates with a motor at its torque limit (wraps the law)."""

    def __init__(self) -> None:
        self.updates = self.saturated = 0
        self._law = arm_law.Arm.batch_torques
        watch = self

        def counted(arm, *args, **kwargs):
            tau = watch._law(arm, *args, **kwargs)
            watch.updates += len(tau)
            watch.saturated += int(np.any(np.abs(tau) >= arm.limit * (1 - 1e-9), axis=1).sum())
            return tau

        arm_law.Arm.batch_torques = counted

    def close(self) -> None:
        arm_law.Arm.batch_torques = self._law


def run(env_id: str, expert: str, episodes: int) -> dict[str, float]:
    env = gym.make(env_id).unwrapped
    panda = env.settings.robot == "panda"
    rows, slips, margins, steps_total, wall = [], [], [], 0, 0.0
    for seed in range(episodes):
        policy = EXPERTS[expert]()
        observation, info = env.reset(seed=seed)
        settled = None if not panda else info["sensed_pose"] - info["pose"]
        slip, margin, done, reward = 0.0, np.inf, False, 0.0
        while not done:
            action = policy(observation)
            began = time.perf_counter()
            observation, r, terminated, truncated, info = env.step(action)
            wall += time.perf_counter() - began
            steps_total += 1
            reward += r
            done = terminated or truncated or "error" in info
            if panda and "error" not in info:
                offset = info["sensed_pose"] - info["pose"] - settled
                slip = max(slip, float(np.max(np.abs(offset[[0, 1, 3]]))))
                arm = env.backend._batch.arm
                q = env.backend.data.qpos[arm.qpos]
                room = np.minimum(q - arm.range[:, 0], arm.range[:, 1] - q)
                margin = min(margin, float(room.min()))
        rows.append((info["success"], info["step"], info["n_collisions"], reward, "error" in info))
        slips.append(slip)
        margins.append(margin)
    columns = (np.array(c, dtype=float) for c in zip(*rows, strict=True))
    success, steps, collisions, reward, errors = columns
    return {
        "success": success.mean(),
        "steps": steps.mean(),
        "collisions": collisions.mean(),
        "reward": reward.mean(),
        "faults": int(errors.sum()),
        "slip_mm": max(slips),
        "joint_margin_rad": min(margins),
        "ms_per_step": wall / steps_total * 1e3,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--envs", default="Circle2x2,Circle2x8,Square")
    args = parser.parse_args()
    print(
        "| env | expert | robot | success | steps | collisions | reward | faults | "
        "largest slip (mm) | closest joint to its limit (rad) | torque-limited updates | "
        "ms per control step | ratio |\n|---|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
    )
    for name in args.envs.split(","):
        for preset in (name, f"{name}Fit50"):
            for expert in EXPERTS:
                free = run(f"tolins/{preset}-v2", expert, args.episodes)
                watch = LimitWatch()
                try:
                    panda = run(f"tolins/{preset}Panda-v2", expert, args.episodes)
                finally:
                    watch.close()
                share = watch.saturated / max(watch.updates, 1)
                for robot, r in (("free", free), ("panda", panda)):
                    extra = (
                        f"{r['slip_mm']:.3f} | {r['joint_margin_rad']:.2f} | {share:.2%}"
                        if robot == "panda"
                        else "– | – | –"
                    )
                    print(
                        f"| {preset} | {expert} | {robot} | {r['success']:.2f} | {r['steps']:.1f} "
                        f"| {r['collisions']:.2f} | {r['reward']:.2f} | {r['faults']} | {extra} "
                        f"| {r['ms_per_step']:.2f} "
                        f"| {r['ms_per_step'] / free['ms_per_step']:.1f} |",
                        flush=True,
                    )


if __name__ == "__main__":
    main()
