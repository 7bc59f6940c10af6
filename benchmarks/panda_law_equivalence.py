"""The Panda's law compiled against the same law in numpy: the same outcomes, episode by episode.

Usage::

    python benchmarks/panda_law_equivalence.py [--episodes 100] [--version 3]
        [--envs Circle2x2,Circle2x2Fit50,Square,SquareFit50] [--workers 2]

The numpy law (:meth:`~tolins.physics.arm.Arm.batch_torques`) is the law the Panda ids ran
before the compiled one (:mod:`tolins.physics.compiled_law`), bit for bit. For each
workpiece, both experts, without and with the bench's grasp error
(:data:`~tolins.bench.table.robot.GRASP_ERROR`), ``--episodes`` episodes (seeds 0 …) run
with each law. Printed per row: episodes whose outcome differs (success, steps, faults),
episodes whose observations differ in any bit, the first step where they do (median), and
the largest difference of the final true pose (mm, rad).
"""

from __future__ import annotations

import argparse
import itertools
from concurrent.futures import ProcessPoolExecutor

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.bench.table.robot import GRASP_ERROR
from tolins.policies import EXPERTS


def episodes(env_id: str, expert: str, grasp: bool, compiled: bool, count: int) -> list[dict]:
    """Each episode's outcome, observations and final pose under one law."""
    kwargs = {"grasp_error": list(GRASP_ERROR)} if grasp else {}
    env = gym.make(env_id, **kwargs).unwrapped
    env.backend._batch.sims.compiled = compiled
    out = []
    for seed in range(count):
        policy = EXPERTS[expert]()
        observation, _ = env.reset(seed=seed)
        seen, done = [observation], False
        while not done:
            observation, _, terminated, truncated, info = env.step(policy(observation))
            seen.append(observation)
            done = terminated or truncated or "error" in info
        outcome = (bool(info["is_success"]), len(seen) - 1, info.get("error"))
        out.append({"outcome": outcome, "observations": np.array(seen), "pose": info["pose"]})
    return out


def compare(job: tuple[str, str, bool, int]) -> str:
    """One row: the two laws' episodes of a workpiece, expert and grasp side by side."""
    env_id, expert, grasp, count = job
    compiled = episodes(env_id, expert, grasp, True, count)
    reference = episodes(env_id, expert, grasp, False, count)
    outcomes = bits = 0
    first, pose = [], 0.0
    for a, b in zip(compiled, reference, strict=True):
        outcomes += a["outcome"] != b["outcome"]
        n = min(len(a["observations"]), len(b["observations"]))
        differ = np.flatnonzero(np.any(a["observations"][:n] != b["observations"][:n], axis=1))
        if len(differ) or len(a["observations"]) != len(b["observations"]):
            bits += 1
            first.append(int(differ[0]) if len(differ) else n)
        pose = max(pose, float(np.max(np.abs(a["pose"] - b["pose"]))))
    success = np.mean([a["outcome"][0] for a in compiled])
    median = f"{np.median(first):.0f}" if first else "–"
    return (
        f"| {env_id} | {expert} | {'yes' if grasp else 'no'} | {count} | {success:.2f} "
        f"| {outcomes} | {bits} | {median} | {pose:.2g} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--version", type=int, default=3)
    parser.add_argument("--envs", default="Circle2x2,Circle2x2Fit50,Square,SquareFit50")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    jobs = [
        (f"tolins/{name}Panda-v{args.version}", expert, grasp, args.episodes)
        for name, expert, grasp in itertools.product(
            args.envs.split(","), ("safe", "efficient"), (False, True)
        )
    ]
    print(
        "| env | expert | grasp error | episodes | success | outcomes differing "
        "| episodes with a bit differing | first differing step (median) "
        "| largest final pose difference |\n|---|---|---|--:|--:|--:|--:|--:|--:|",
        flush=True,
    )
    with ProcessPoolExecutor(args.workers) as pool:
        for row in pool.map(compare, jobs):
            print(row, flush=True)


if __name__ == "__main__":
    main()
