"""What the bent-pin inference recovers of a grasp error on the Panda, from failed insertions.

Usage::

    python benchmarks/panda_grasp_inference.py [--episodes 30] [--std 0.5]

A grasp error moves every pin by the same offset from where the robot believes it: what
the bent-pin posterior (:mod:`tolins.inference.posterior`, a prior on each pin's offset)
can explain as a common offset of all pins. On ``tolins/Circle2x2Panda-v2`` with
``grasp_error=[std, std, 0.02]`` (x along the finger pads, where most of it stays; across
them the fingers centre the part), the safe expert runs ``--episodes`` episodes alone and
wrapped in inference (:class:`~tolins.inference.adaptive.InferenceGuidedPolicy`: each
blocked attempt re-plans the goal; no touch points, which the Panda does not report).
Printed: success, the blocked attempts, and, for the episodes that re-planned, the part's
true offset in the hand (``info["pose"] - info["sensed_pose"]`` at the reset) against the
goal inference chose last (inserting needs ``goal ≈ -offset``): the offset's size before
and the residual ``|goal + offset|`` after, and how many re-plans kept the goal because no
goal was likely enough (the search's discard threshold).
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.inference.adaptive import InferenceGuidedPolicy
from tolins.policies import SafeExpert

ENV = "tolins/Circle2x2Panda-v2"


def run(episodes: int, std: float, inference: bool) -> list[dict[str, float]]:
    env = gym.make(ENV, grasp_error=[std, std, 0.02]).unwrapped
    policy = InferenceGuidedPolicy(
        SafeExpert(), env, sigma=max(std, 0.05), contact=False, inference=inference
    )
    rows = []
    for seed in range(episodes):
        policy.reset(seed)
        observation, info = env.reset(seed=seed)
        offset = (info["pose"] - info["sensed_pose"])[:2]
        done, blocked = False, 0
        while not done:
            blocked += policy.blocked(observation) and policy._lifting == 0
            observation, _, terminated, truncated, info = env.step(policy(observation))
            done = terminated or truncated
        goal = policy.goals[-1][:2] if policy.goals else np.zeros(2)
        rows.append(
            {
                "success": float(info["success"]),
                "attempts": float(blocked),
                "offset": float(np.linalg.norm(offset)),
                "residual": float(np.linalg.norm(goal + offset)),
                "replanned": float(bool(policy.goals)),
                "discarded": float(sum(r.discard for r in policy.results)),
                "plans": float(len(policy.results)),
            }
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--std", type=float, default=0.5, help="grasp error std (mm)")
    args = parser.parse_args()
    print(
        "| policy | success | blocked attempts | episodes re-planned | offset in the hand "
        "(mm) | residual after the last goal (mm) | re-plans kept at the goal (too unlikely) "
        "|\n|---|--:|--:|--:|--:|--:|--:|"
    )
    for inference in (False, True):
        rows = run(args.episodes, args.std, inference)
        mean = {key: np.mean([r[key] for r in rows]) for key in rows[0]}
        planned = [r for r in rows if r["replanned"]]
        offset, residual = (
            f"{np.mean([r[key] for r in planned]):.3f}" if planned else "–"
            for key in ("offset", "residual")
        )
        name = "safe expert + inference" if inference else "safe expert, lift and retry"
        plans = sum(r["plans"] for r in rows)
        kept = f"{sum(r['discarded'] for r in rows):.0f} of {plans:.0f}" if plans else "–"
        print(
            f"| {name} | {mean['success']:.2f} | {mean['attempts']:.2f} | {len(planned)} "
            f"| {offset} | {residual} | {kept} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
