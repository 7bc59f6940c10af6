"""π_φ against π_φ* (the same policy with inference in the loop) on bent-pin workpieces.

Usage::

    python benchmarks/evaluate_adaptive.py --episodes 100 \\
        safe pi_phi=/tmp/acc/pi_phi/policy.pt

Table 1's C4.1 / C4.2 figures (mean ± std): every policy bare, wrapped in
:class:`tolins.inference.adaptive.InferenceGuidedPolicy` with binary outcomes
(``+inference``, the paper's π_φ*) and with the per-pin touch sensors and touch bearings
(``+inference_contact``). Every variant sees the same seeds (10000, 10001, ...) and so the
same bent workpieces and initial poses; a tolerance-guided policy gets the embedding
of the env's *nominal* socket. Variants run on 2 threads (results do not depend on it).
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ThreadPoolExecutor

import gymnasium as gym
import numpy as np
import torch

from tolins.inference.adaptive import InferenceGuidedPolicy
from tolins.learning.agents.actors import make_actor
from tolins.rollouts.episodes import run_episode
from tolins.rollouts.summary import Summary, summarise

FIRST_SEED = 10_000
VARIANTS = ("", "+lift", "+inference", "+inference_contact")


def evaluate(entry: str, variant: str, env_id: str, episodes: int) -> tuple[Summary, float]:
    """Table 1's figures of ``entry`` (+ ``variant``) and the mean re-plans per episode."""
    env = gym.make(env_id).unwrapped
    policy = make_actor(entry, env.nominal_socket)
    wrapper = None
    if variant:
        wrapper = InferenceGuidedPolicy(
            policy,
            env,
            inference=variant != "+lift",
            contact=variant == "+inference_contact",
        )
        policy = wrapper
    results, replans = [], []
    for i in range(episodes):
        if wrapper is not None:
            wrapper.reset(FIRST_SEED + i)
        results.append(run_episode(env, policy, seed=FIRST_SEED + i))
        replans.append(0 if wrapper is None else wrapper.replans)
    return summarise(results), float(np.mean(replans))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("policies", nargs="+", help="expert name or NAME=PATH")
    parser.add_argument("--env", default="tolins/Circle2x1Defective-v1")
    parser.add_argument("--episodes", type=int, default=100)
    args = parser.parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    jobs = [(entry, variant) for entry in args.policies for variant in VARIANTS]
    with ThreadPoolExecutor(2) as pool:
        summaries = pool.map(lambda j: evaluate(*j, args.env, args.episodes), jobs)
        print("| policy | eval env | reward | success rate | steps | collisions | re-plans |")
        print("|---|---|---|---|---|---|---|")
        for (entry, variant), (s, replans) in zip(jobs, summaries, strict=True):
            print(
                f"| {entry.split('=')[0]}{variant} | {args.env} "
                f"| {s.reward_mean:.2f} ± {s.reward_std:.2f} "
                f"| {s.success_mean:.2f} ± {s.success_std:.2f} "
                f"| {s.steps_mean:.2f} ± {s.steps_std:.2f} "
                f"| {s.collisions_mean:.2f} ± {s.collisions_std:.2f} | {replans:.2f} |"
            )
    print(
        f"\n{args.episodes} episodes per policy, seeds {FIRST_SEED}…, MuJoCo, "
        f"{time.perf_counter() - start:.0f} s"
    )


if __name__ == "__main__":
    main()
