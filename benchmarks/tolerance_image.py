"""Time of one tolerance image, ``tolins.tolerance.image(spec, resolution)``, on one core.

Usage::

    python benchmarks/tolerance_image.py             # full run, a few seconds
    python benchmarks/tolerance_image.py --quick     # a smoke test

For each socket the image is computed ``--repeats`` times (after one warm-up call that
fills the geometry cache); the table gives the fastest and the median call. The process
is pinned to one core (``os.sched_setaffinity``) and BLAS to one thread. Also shown: the
share of cells in the tolerance and the largest theta. Target: a 64×64 image of a 2*20
socket in ≤ 50 ms.
"""

from __future__ import annotations

import os

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from tolins import CircularSocket, PolygonSocket  # noqa: E402
from tolins.tolerance import image  # noqa: E402

SOCKETS = {
    "2*1": CircularSocket(2, 1),
    "2*2": CircularSocket(2, 2),
    "2*20": CircularSocket(2, 20),
    "2*20 bent": CircularSocket(2, 20, pin_offsets=np.full((40, 2), 0.05)),
    "triangle": PolygonSocket(3, 1.5, 1.65),
    "hexagon": PolygonSocket(6, 1.2, 1.26),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", type=int, default=64)
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--quick", action="store_true", help="5 repeats")
    args = parser.parse_args()
    repeats = 5 if args.quick else args.repeats
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    print(
        f"Python {platform.python_version()}, NumPy {np.__version__}, {platform.machine()}; "
        f"{args.resolution}×{args.resolution}, {repeats} calls, one core"
    )
    print("| socket    | best ms | median ms | cells in tolerance | max theta (rad) |")
    print("|-----------|--------:|----------:|-------------------:|----------------:|")
    for name, spec in SOCKETS.items():
        values = image(spec, args.resolution)
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            image(spec, args.resolution)
            times.append(time.perf_counter() - start)
        share = float(np.mean(values >= 0))
        print(
            f"| {name:9} | {min(times) * 1e3:7.2f} | {statistics.median(times) * 1e3:9.2f} "
            f"| {share:18.3f} | {values.max():15.4f} |"
        )


if __name__ == "__main__":
    main()
