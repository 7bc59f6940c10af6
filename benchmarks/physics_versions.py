"""Control steps per CPU-second of ``-v1`` against ``-v2``, side by side in one run.

Run through ``python benchmarks/env_throughput.py --versions`` (or this file directly).

Per preset and policy (the safe and efficient experts, a uniformly random policy), whole
episodes from the same seeds run on ``-v1`` and on ``-v2`` in alternating blocks; each
block's thread CPU time (``time.thread_time``, steps only, resets excluded) is divided by
its control steps, and each version's fastest block is kept, so a busy spell of a shared
machine hits both alike. Each block also checks that both versions' episodes ended alike
(steps, successes and rewards). Then the vector env of ``--envs`` simulations on both cores,
wall clock, same alternation.
"""

from __future__ import annotations

import argparse
import sys
import time

import gymnasium as gym
import numpy as np

import tolins
from tolins.paper import A_MAX
from tolins.policies import EXPERTS

PRESETS = ("Circle2x2", "Circle2x8", "Circle2x20", "Square", "Hexagon", "Circle2x2Fit20")
POLICIES = ("safe", "efficient", "random")


def _env(name: str, version: int) -> gym.Env:
    if name == "Circle2x20":  # not a preset: the generic id with a 2*20 socket
        return gym.make(f"tolins/Insert-v{version}", socket=tolins.CircularSocket(rows=2, cols=20))
    return gym.make(f"tolins/{name}-v{version}")


def _policy(name: str, seed: int):
    if name == "random":
        rng = np.random.default_rng(seed)
        return lambda _obs: rng.uniform(-A_MAX, A_MAX)
    return EXPERTS[name]()


def run_block(env: gym.Env, policy: str, seeds: range) -> tuple[float, int, list]:
    """Thread CPU seconds of the steps, control steps, and each episode's outcome."""
    cpu, steps, outcomes = 0.0, 0, []
    for seed in seeds:
        act = _policy(policy, seed)
        obs, _ = env.reset(seed=seed)
        total, done, n = 0.0, False, 0
        while not done:
            action = act(obs)
            start = time.thread_time()
            obs, reward, terminated, truncated, _ = env.step(action)
            cpu += time.thread_time() - start
            total, n, done = total + reward, n + 1, terminated or truncated
        steps += n
        outcomes.append((n, terminated, total))
    return cpu, steps, outcomes


def measure(name: str, policy: str, episodes: int, blocks: int) -> dict:
    """The fastest block of each version (ms per control step) and whether they agree."""
    envs = {v: _env(name, v) for v in (1, 2)}
    best = {1: np.inf, 2: np.inf}
    same = True
    for block in range(blocks):
        seeds = range(block * episodes, (block + 1) * episodes)
        outcomes = {}
        for v in (1, 2) if block % 2 == 0 else (2, 1):
            cpu, steps, outcomes[v] = run_block(envs[v], policy, seeds)
            best[v] = min(best[v], 1e3 * cpu / steps)
        same &= outcomes[1] == outcomes[2]
    return {"v1_ms": best[1], "v2_ms": best[2], "speedup": best[1] / best[2], "same": same}


def measure_vector(num_envs: int, steps: int, blocks: int) -> dict:
    """Wall seconds per control step of the vector env of the 2*2 (random actions)."""
    best = {1: np.inf, 2: np.inf}
    for block in range(blocks):
        for v in (1, 2) if block % 2 == 0 else (2, 1):
            envs = tolins.make_vec(f"tolins/Circle2x2-v{v}", num_envs)
            rng = np.random.default_rng(block)
            envs.reset(seed=block)
            start = time.perf_counter()
            for _ in range(steps):
                envs.step(rng.uniform(-A_MAX, A_MAX, (num_envs, 4)))
            best[v] = min(best[v], (time.perf_counter() - start) / steps)
            envs.close()
    return {"v1_ms": 1e3 * best[1], "v2_ms": 1e3 * best[2], "speedup": best[1] / best[2]}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=5, help="episodes per block")
    parser.add_argument("--blocks", type=int, default=4, help="blocks per version")
    parser.add_argument("--only", nargs="+", choices=PRESETS, default=list(PRESETS))
    parser.add_argument("--envs", type=int, default=8, help="simulations of the vector env")
    parser.add_argument("--vector-steps", type=int, default=40)
    args = parser.parse_args(argv)
    if min(args.episodes, args.blocks, args.envs, args.vector_steps) < 1:
        parser.error("--episodes, --blocks, --envs and --vector-steps must be ≥ 1")
    print("| preset | policy | -v1 ms/step | -v2 ms/step | speed-up | same outcomes |")
    print("|---|---|--:|--:|--:|---|")
    for name in args.only:
        for policy in POLICIES:
            r = measure(name, policy, args.episodes, args.blocks)
            print(
                f"| {name} | {policy} | {r['v1_ms']:.3f} | {r['v2_ms']:.3f} | "
                f"{r['speedup']:.2f} | {'yes' if r['same'] else 'NO'} |",
                flush=True,
            )
    v = measure_vector(args.envs, args.vector_steps, args.blocks)
    print(
        f"\nVector env, {args.envs} envs of the 2*2 on every core, random actions, wall clock: "
        f"-v1 {v['v1_ms']:.2f} ms, -v2 {v['v2_ms']:.2f} ms per control step "
        f"({v['speedup']:.2f}×)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
