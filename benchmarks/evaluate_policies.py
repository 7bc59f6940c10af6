"""Evaluate policies side by side on one environment: Table 1's figures (mean ± std).

Usage::

    python benchmarks/evaluate_policies.py --env tolins/Circle2x2-v1 --episodes 100 \\
        safe pi_bc=runs/bc/policy.pt pi_n=runs/pi_n/policy.pt

Each policy is an expert name (``safe``, ``efficient``) or ``NAME=PATH`` of a policy saved
by ``tolins train``. Every policy sees the same seeds (10000, 10001, ...; those of
``tolins bench``), which no training run uses; policies run on 2 threads (results do not
depend on it). A tolerance-guided policy gets the embedding of the environment's socket.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ThreadPoolExecutor

import torch

from tolins.bench.jobs.policy_episodes import evaluate
from tolins.bench.table.seeds import FIRST_SEED, eval_seeds
from tolins.rollouts.summary import Summary, summarise


def figures(entry: str, env_id: str, episodes: int, backend: str) -> Summary:
    """Table 1's figures of ``entry`` over ``episodes`` episodes from the fixed seeds."""
    return summarise(evaluate(entry, env_id, backend, eval_seeds(0, episodes)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("policies", nargs="+", help="expert name or NAME=PATH")
    parser.add_argument("--env", required=True)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--backend", default="mujoco", choices=["mujoco", "kinematic"])
    args = parser.parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    with ThreadPoolExecutor(2) as pool:
        summaries = pool.map(
            lambda e: figures(e, args.env, args.episodes, args.backend), args.policies
        )
        print("| policy | eval env | reward | success rate | steps | collisions |")
        print("|---|---|---|---|---|---|")
        for entry, s in zip(args.policies, summaries, strict=True):
            print(
                f"| {entry.split('=')[0]} | {args.env} | {s.reward_mean:.2f} ± {s.reward_std:.2f} "
                f"| {s.success_mean:.2f} ± {s.success_std:.2f} "
                f"| {s.steps_mean:.2f} ± {s.steps_std:.2f} "
                f"| {s.collisions_mean:.2f} ± {s.collisions_std:.2f} |"
            )
    print(
        f"\n{args.episodes} episodes per policy, seeds {FIRST_SEED}…, backend {args.backend}, "
        f"{time.perf_counter() - start:.0f} s"
    )


if __name__ == "__main__":
    main()
