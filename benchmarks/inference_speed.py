"""Time one goal query (posterior + CMA-ES) for the study's 2*1 socket.

Histories of 1..9 failed attempts from the study's own methods (binary outcomes, blocked
pins, blocked pins and touch bearings); each query is
``next_goal(SOCKET, history, SIGMA, rng, n_samples=...)``: sample the posterior, pick the
best candidate, refine with CMA-ES. Prints the median and the 95th percentile.

    python benchmarks/inference_speed.py            # 1000 particles (the study's), 60 queries
    python benchmarks/inference_speed.py --quick    # 10 queries
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from tolins.inference import History, next_goal
from tolins.inference.study import EVIDENCE, SIGMA, SOCKET, draw_workpieces, geometry_outcome


def histories(count: int, method: str, particles: int) -> list[History]:
    """Failed-attempt histories met in the study (workpieces the nominal goal misses)."""
    with_blocked, with_bearings = EVIDENCE[method]
    out: list[History] = []
    rng = np.random.default_rng(0)
    for eps in draw_workpieces(400, seed=7):
        attempt = geometry_outcome(eps)
        history = History.empty()
        for _ in range(9):
            goal = next_goal(SOCKET, history, SIGMA, rng, n_samples=particles).goal
            inside, bearings = attempt(goal)
            if inside.all():
                break
            history = history.append(
                goal,
                False,
                ~inside if with_blocked else None,
                bearings if with_bearings else None,
            )
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
    for method in EVIDENCE:
        cases = histories(queries, method, args.particles)
        times = []
        for k, history in enumerate(cases):
            rng = np.random.default_rng(k)
            start = time.perf_counter()
            next_goal(SOCKET, history, SIGMA, rng, n_samples=args.particles)
            times.append(time.perf_counter() - start)
        ms = 1e3 * np.array(times)
        print(
            f"{method:<18} {len(ms)} queries, {args.particles} particles, history 1-9: "
            f"median {np.median(ms):.1f} ms, p95 {np.percentile(ms, 95):.1f} ms, "
            f"max {ms.max():.1f} ms (target ≤ 50 ms)"
        )


if __name__ == "__main__":
    main()
