"""Control steps per second of the kinematic backend, batched, on one core.

Usage::

    python benchmarks/kinematic_throughput.py            # full run, about 10 s
    python benchmarks/kinematic_throughput.py --quick    # a second or two, a smoke test

A :class:`~tolins.physics.kinematic.KinematicBatch` of ``--batch`` workpieces (256)
steps ``--steps`` control steps (40 = one episode) from a reset, in three regimes:

* ``free``: in the air (``z`` 15–18 mm), random actions: no step checks collisions;
* ``landing``: 0.05 mm above the board beside the holes (0.5 mm off for circles, 0.3 mm
  for polygons), pushing down at full speed: every step lands on the board's top;
* ``wall``: inserted (``z = -0.5`` mm) at the goal, moving at full speed in x and theta:
  every step meets a hole's wall, found by sampling and binary search (the worst case);
* ``expert``: the paper's episode, initial poses from ``InitialPoseDistribution`` and the
  efficient expert's action on the true pose (computed for the whole batch with NumPy,
  included in the time), so free flight, landing and insertion mix.

Steps/s = batch × steps / time of the fastest of ``--repeats`` blocks (resets excluded).
The process is pinned to one core (``os.sched_setaffinity``) and BLAS to one thread.
Target: ≥ 50,000 control steps/s for a batch of 256.
"""

from __future__ import annotations

import os

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from tolins import CircularSocket, PolygonSocket  # noqa: E402
from tolins.envs import InitialPoseDistribution  # noqa: E402
from tolins.paper import A_MAX, CONTROL_DT  # noqa: E402
from tolins.physics.kinematic import KinematicBatch  # noqa: E402

SOCKETS = {
    "2*2": CircularSocket(2, 2),
    "2*20": CircularSocket(2, 20),
    "square": PolygonSocket(4, 1.5, 1.65),
    "hexagon": PolygonSocket(6, 1.2, 1.26),
}


def _start(regime: str, socket, n: int, rng: np.random.Generator) -> np.ndarray:
    if regime == "free":
        return np.column_stack([rng.uniform(-3, 3, (n, 3)) * [1, 1, 0.03], rng.uniform(15, 18, n)])
    if regime == "landing":
        offset = 0.5 if isinstance(socket, CircularSocket) else 0.3
        return np.tile([offset, 0.0, 0.0, 0.05], (n, 1))
    if regime == "wall":
        return np.tile([0.0, 0.0, 0.0, -0.5], (n, 1))
    dist = InitialPoseDistribution()
    return np.array([dist.sample(rng, np.zeros(3)) for _ in range(n)])


def _efficient(pose: np.ndarray, depth: float = 2.0) -> np.ndarray:
    """The efficient expert on the true poses ``(n, 4)``: straight at full speed to the goal."""
    error = pose + np.array([0.0, 0.0, 0.0, depth])
    time_to_go = np.maximum(np.max(np.abs(error) / A_MAX, axis=1), CONTROL_DT)
    return -error / time_to_go[:, None]


def _actions(regime: str, n: int, steps: int, seed: int) -> np.ndarray:
    """Actions ``(steps, n, 4)`` of the open-loop regimes."""
    if regime == "free":
        rng = np.random.default_rng(seed)
        return rng.uniform(-A_MAX, A_MAX, (steps, n, 4)) * [1, 1, 1, 0.1]
    action = [0.0, 0.0, 0.0, -A_MAX[3]] if regime == "landing" else [A_MAX[0], 0, A_MAX[2], 0]
    return np.broadcast_to(action, (steps, n, 4))


def _block(batch: KinematicBatch, regime: str, start: np.ndarray, steps: int, seed: int) -> float:
    ids = np.arange(batch.num_envs)
    actions = _actions(regime, batch.num_envs, steps, seed)
    state = batch.reset(ids, start)
    begin = time.perf_counter()
    for k in range(steps):
        state = batch.step(ids, _efficient(state.pose) if regime == "expert" else actions[k])
    return time.perf_counter() - begin


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=256)
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--quick", action="store_true", help="3 repeats")
    args = parser.parse_args()
    repeats = 3 if args.quick else args.repeats
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    print(
        f"Python {platform.python_version()}, NumPy {np.__version__}, {platform.machine()}; "
        f"batch {args.batch}, {args.steps} steps per block, best of {repeats}, one core"
    )
    print("| socket  | regime  |    steps/s | µs per batch step | colliding steps |")
    print("|---------|---------|-----------:|------------------:|--------------:|")
    for name, socket in SOCKETS.items():
        for regime in ("free", "landing", "wall", "expert"):
            batch = KinematicBatch(socket, args.batch, CONTROL_DT)
            start = _start(regime, socket, args.batch, np.random.default_rng(0))
            best = min(_block(batch, regime, start, args.steps, r) for r in range(repeats))
            stopped = _count_stops(batch, regime, start, args.steps)
            rate = args.batch * args.steps / best
            print(
                f"| {name:7} | {regime:7} | {rate:10,.0f} | {best / args.steps * 1e6:17.0f} "
                f"| {stopped:>13} |"
            )


def _count_stops(batch: KinematicBatch, regime: str, start: np.ndarray, steps: int) -> str:
    """How many of the block's workpiece steps stopped at a collision."""
    ids = np.arange(batch.num_envs)
    state, stops = batch.reset(ids, start), 0
    actions = _actions(regime, batch.num_envs, steps, 0)
    for k in range(steps):
        state = batch.step(ids, _efficient(state.pose) if regime == "expert" else actions[k])
        stops += int(np.count_nonzero(state.peak_force))
    return f"{stops}/{batch.num_envs * steps}"


if __name__ == "__main__":
    main()
