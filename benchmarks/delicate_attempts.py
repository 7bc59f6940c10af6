"""Inference on a part its own failed attempts may bend: π_e* on bent-pin 2*1 workpieces
with rigid pins and with pins that bend.

Usage::

    python benchmarks/delicate_attempts.py [--episodes 50] [--materials phosphor_bronze,alloy42]

The workpieces of Table 1's C4 rows (``tolins/Circle2x1Defective-v2``: every pin bent by
``N(0, 0.12² I)`` mm, drawn per episode from its seed) are attempted by each expert wrapped
in probabilistic inference (:class:`~tolins.inference.adaptive.InferenceGuidedPolicy`, as
π_φ* wraps π_φ in row C4.2: a blocked attempt lifts the part, updates the posterior and
moves the goal, up to 8 re-plans, so up to 9 attempts in the paper's 40 steps), on the
same seeds with rigid pins and with ``pins="elastic-plastic"`` in each ``--materials``.
With pins that bend, every attempt meets the part as the last one left it (its bends
stay for the episode). Printed per row: success, attempts (1 + re-plans) of the successes,
the share of parts damaged (a pin bent for good beyond half the clearance), successes
without damage, and the largest permanent bend.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.inference.adaptive import InferenceGuidedPolicy
from tolins.policies import EXPERTS
from tolins.rollouts.episodes import EpisodeRun

ENV_ID = "tolins/Circle2x1Defective-v2"


def attempts(expert: str, episodes: int, **pins: str) -> dict[str, float]:
    """The figures of ``episodes`` episodes (seeds 0 …) of ``expert`` with inference."""
    env = gym.make(ENV_ID, **pins).unwrapped
    policy = InferenceGuidedPolicy(EXPERTS[expert](), env)
    rows = []
    for seed in range(episodes):
        observation, info = env.reset(seed=seed)
        policy.reset(seed)
        run = EpisodeRun(policy, env.settings, observation, info)
        while not run.done:
            observation, reward, terminated, truncated, info = env.step(run.act(observation))
            run.observe(observation, reward, terminated, truncated, info)
        episode = run.episode()
        bend = info.get("pin_bend", np.zeros((1, 2)))
        rows.append(
            (
                episode.success,
                1 + policy.replans,
                bool(episode.damaged),
                float(np.max(np.hypot(bend[:, 0], bend[:, 1]))),
            )
        )
    success, tries, damaged, bends = (np.array(column) for column in zip(*rows, strict=True))
    return {
        "success": success.mean(),
        "attempts": tries[success].mean() if success.any() else float("nan"),
        "damaged": damaged.mean(),
        "undamaged_success": (success & ~damaged).mean(),
        "largest_bend_um": bends.max() * 1e3,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=50)
    parser.add_argument("--materials", default="phosphor_bronze,alloy42")
    args = parser.parse_args()
    print(
        "| expert | pins | success | attempts of the successes | damaged | success without "
        "damage | largest bend (µm) |\n|---|---|--:|--:|--:|--:|--:|"
    )
    for expert in ("safe", "efficient"):
        variants = [("rigid", {})] + [
            (m, {"pins": "elastic-plastic", "pin_material": m}) for m in args.materials.split(",")
        ]
        for label, pins in variants:
            f = attempts(expert, args.episodes, **pins)
            print(
                f"| {expert} | {label} | {f['success']:.2f} | {f['attempts']:.2f} "
                f"| {f['damaged']:.2f} | {f['undamaged_success']:.2f} "
                f"| {f['largest_bend_um']:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
