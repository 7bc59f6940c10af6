"""Time one goal query (posterior + CMA-ES) for the study's 2*1 socket (issue 6, item 5).

Histories of 1..9 failed attempts from the study's own method; each query is
``next_goal(SOCKET, history, SIGMA, rng, n_samples=...)``: sample the posterior, pick the
best candidate, refine with CMA-ES. Prints the median and the 95th percentile.

    python benchmarks/inference_speed.py            # 1000 particles (the study's), 60 queries
    python benchmarks/inference_speed.py --quick    # 10 queries
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from tolins.geometry.tolerance import pins_inside
from tolins.inference import History, next_goal
from tolins.inference.study import SIGMA, SOCKET, draw_workpieces


def histories(count: int, contact: bool, particles: int) -> list[History]:
    """Failed-attempt histories met in the study (workpieces the nominal goal misses)."""
    out: list[History] = []
    rng = np.random.default_rng(0)
    for eps in draw_workpieces(400, seed=7):
        history = History.empty()
        for _ in range(9):
            goal = next_goal(SOCKET, history, SIGMA, rng, n_samples=particles).goal
            inside = pins_inside(SOCKET, eps, goal)
            if inside.all():
                break
            history = history.append(goal, False, ~inside if contact else None)
            out.append(history)
            if len(out) == count:
                return out
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=int, default=1000)
    parser.add_argument("--queries", type=int, default=60)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    queries = 10 if args.quick else args.queries
    for contact in (False, True):
        cases = histories(queries, contact, args.particles)
        times = []
        for k, history in enumerate(cases):
            rng = np.random.default_rng(k)
            start = time.perf_counter()
            next_goal(SOCKET, history, SIGMA, rng, n_samples=args.particles)
            times.append(time.perf_counter() - start)
        ms = 1e3 * np.array(times)
        label = "inference_contact" if contact else "inference"
        print(
            f"{label:<18} {len(ms)} queries, {args.particles} particles, history 1-9: "
            f"median {np.median(ms):.1f} ms, p95 {np.percentile(ms, 95):.1f} ms, "
            f"max {ms.max():.1f} ms (target ≤ 50 ms)"
        )


if __name__ == "__main__":
    main()
