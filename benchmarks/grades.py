"""The tolerance-grade table: agreement, capture and cost per radial clearance.

Usage::

    python benchmarks/grades.py                      # 4 shapes × 4 grades, the model's steps
    python benchmarks/grades.py --quick              # a smoke run (few probes, 2*2 only)
    python benchmarks/grades.py --timesteps 1 0.5 0.25 --grades 50 20 --probes 0
                                                     # capture per physics step (ms)

For each shape (2*2 and 2*8 sockets, square and hexagon pegs) and grade (radial clearance
200, 100, 50, 20 µm: holes resized, pins unchanged, ``with_clearance``) at the model's
physics step (``tolins.mjcf.model.physics_timestep``) or each ``--timesteps`` step:

* **agreement**: ``--probes`` poses near the boundary of the exact tolerance, offsets
  within ±25 % of the clearance, pushed down at 2.5 mm/s (``physics_vs_geometry.py``);
  the share whose outcome agrees with ``contains`` outside a band of ±5 % of the
  clearance (goal ≥ 99 %), and the largest distance beyond the boundary of a probe that
  went in (probe capture).
* **capture**: the largest x offset (and rotation, as the farthest pin point's
  displacement, for the shapes in ``--theta``: all but the 2*8 socket by default) that
  inserts at 2.5 mm/s, by bisection (``capture.py``), minus the geometric limit, in µm
  and in % of the clearance (goal ≤ 5 %).
* **cost**: control steps per CPU second, best of three (``time.process_time``, so
  that other load on a shared machine counts less) of a blocked push (0.1 mm beyond the
  clearance) and of a free descent, and their ratio to the same shape at 200 µm and 1 ms
  measured in the same run (compare ratios). ``--cost-only`` skips agreement and capture.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

import capture
import physics_vs_geometry as pvg

from tolins import CircularSocket, PolygonSocket
from tolins.envs import InsertionEnv
from tolins.geometry.specs import GRADES_UM, with_clearance
from tolins.geometry.workspace import THETA_RANGE
from tolins.mjcf import model as model_module

SHAPES = {
    "2*2": CircularSocket(2, 2),
    "2*8": CircularSocket(2, 8),
    "square": PolygonSocket(4, 1.5, 1.65),
    "hexagon": PolygonSocket(6, 1.2, 1.26),
}
BAND, OFFSETS, CAPTURE_GOAL = 0.05, 0.25, 0.05


def use_timestep(step_s: float | None) -> None:
    """Every model built from now on has physics step ``step_s`` (``None``: the grade's)."""
    table = model_module.__dict__.setdefault(
        "_GRADE_TIMESTEPS_DEFAULT", model_module.GRADE_TIMESTEPS
    )
    fixed = {family: ((0.0, step_s),) for family in table}
    model_module.GRADE_TIMESTEPS = table if step_s is None else fixed


def steps_per_second(spec, pose: list[float], steps: int = 4, rounds: int = 3) -> float:
    """Control steps per CPU second pushing down from ``pose``: the best of ``rounds``
    rounds of ``steps`` steps after a warm-up step, each round from a reset."""
    env = InsertionEnv(spec, measurement_noise=0)
    best = 0.0
    for _ in range(rounds):
        env.reset(seed=0, options={"pose": pose})
        env.step([0.0, 0.0, 0.0, -2.5])
        start = time.process_time()
        for _ in range(steps):
            env.step([0.0, 0.0, 0.0, -2.5])
        best = max(best, steps / (time.process_time() - start))
    return best


def capture_um(spec, axis: int) -> float:
    """Largest inserting offset along ``axis`` (0: x, 2: theta) minus the limit, as the
    farthest pin point's displacement (µm)."""
    limit = spec.clearance if axis == 0 else pvg.extents(spec).theta[1]
    blocked = 1.5 * limit if axis == 0 else min(1.5 * limit, 0.99 * THETA_RANGE)
    case = capture.Case("", spec, axis, limit, 0.8 * limit, blocked)
    resolution = 0.001 * spec.clearance * (1 if axis == 0 else 1 / 4.0)
    excess = capture.largest_inserting(case, capture.FAST, resolution)[0] - limit
    arm = 1.0 if axis == 0 else float(np.max(np.linalg.norm(pvg.pin_points(spec), axis=1)))
    return excess * arm * 1e3


def row(pool, name: str, grade: float, step_s: float | None, args) -> dict:
    use_timestep(step_s)
    spec = with_clearance(SHAPES[name], grade * 1e-3)
    c_um = spec.clearance * 1e3
    result = {"shape": name, "grade": grade, "step_ms": model_module.physics_timestep(spec) * 1e3}
    if args.probes and not args.cost_only:
        # physics_vs_geometry caches an env per thread and socket name: one per step.
        sock = pvg.Socket(f"{name} fit{grade:g} {result['step_ms']:g} ms", spec.family, spec)
        probes = pvg.make_probes(sock, args.probes, args.seed, OFFSETS * c_um, args.directions)
        outcomes = pvg.run_physics(pool, sock, probes, pvg.FAST)
        summary = pvg.summarise(probes, outcomes, BAND * c_um)
        result.update(
            agree=summary["agree_rate"],
            outside=summary["outside_band"],
            probe_capture=summary["capture_max_um"],
        )
    if not args.cost_only:
        result["capture_x"] = capture_um(spec, 0)
        if name in args.theta:
            result["capture_theta"] = capture_um(spec, 2)
    result["blocked_sps"] = steps_per_second(spec, [spec.clearance + 0.1, 0.0, 0.0, 0.05])
    result["free_sps"] = steps_per_second(spec, [0.0, 0.0, 0.0, 30.0])
    return result


def line(r: dict, base: dict) -> str:
    c_um = r["grade"]
    if "capture_x" not in r:
        return (
            f"| {r['shape']} | {c_um:g} | {r['step_ms']:g} | "
            f"{r['blocked_sps']:.1f} ({r['blocked_sps'] / base['blocked_sps']:.2f}) | "
            f"{r['free_sps']:.0f} ({r['free_sps'] / base['free_sps']:.2f}) |"
        )
    capture_max = max(r["capture_x"], r.get("capture_theta", -np.inf))
    agree = f"{100 * r['agree']:.1f} % ({r['outside']})" if "agree" in r else "–"
    probe = f"{r['probe_capture']:.2f}" if "probe_capture" in r else "–"
    theta = f" / {r['capture_theta']:+.2f}" if "capture_theta" in r else ""
    ok = capture_max <= CAPTURE_GOAL * c_um and ("agree" not in r or r["agree"] >= 0.99)
    return (
        f"| {r['shape']} | {c_um:g} | {r['step_ms']:g} | {agree} | {probe} | "
        f"{r['capture_x']:+.2f}{theta} | {100 * capture_max / c_um:.1f} % | "
        f"{r['blocked_sps']:.1f} ({r['blocked_sps'] / base['blocked_sps']:.2f}) | "
        f"{r['free_sps']:.0f} ({r['free_sps'] / base['free_sps']:.2f}) | "
        f"{'yes' if ok else 'NO'} |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--shapes", nargs="*", default=list(SHAPES), choices=list(SHAPES))
    parser.add_argument("--grades", nargs="*", type=float, default=list(GRADES_UM))
    parser.add_argument("--timesteps", nargs="*", type=float, help="ms (default: the model's)")
    parser.add_argument("--probes", type=int, default=100, help="per shape and grade (0: none)")
    parser.add_argument("--directions", type=int, default=48)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--cost-only", action="store_true", help="steps/s only")
    parser.add_argument(
        "--theta", nargs="*", default=["2*2", "square", "hexagon"], help="shapes whose θ capture"
    )
    args = parser.parse_args(argv)
    if args.quick:
        args.shapes, args.grades, args.probes, args.directions = ["2*2"], [200, 20], 12, 16
    steps = [None] if not args.timesteps else [t * 1e-3 for t in args.timesteps]
    started = time.perf_counter()
    if args.cost_only:
        print(
            "| shape | clearance µm | step ms | blocked steps/CPU-s (× 200 µm) | "
            "free steps/CPU-s (× 200 µm) |\n|---|--:|--:|--:|--:|"
        )
    else:
        print(
            "| shape | clearance µm | step ms | agree outside ±5 % | probe capture µm | "
            "capture x / θ µm | capture % | blocked steps/CPU-s (× 200 µm) | "
            "free steps/CPU-s (× 200 µm) | goals met |\n|---|--:|--:|--:|--:|--:|--:|--:|--:|---|",
            flush=True,
        )
    with concurrent.futures.ThreadPoolExecutor(args.workers) as pool:
        for name in args.shapes:
            base = None
            for grade in args.grades:
                for step_s in steps:
                    if base is None:  # the same shape at 200 µm and 1 ms
                        use_timestep(None)
                        reference = with_clearance(SHAPES[name], 0.2)
                        base = {
                            "blocked_sps": steps_per_second(reference, [0.3, 0.0, 0.0, 0.05]),
                            "free_sps": steps_per_second(reference, [0.0, 0.0, 0.0, 30.0]),
                        }
                    spec = with_clearance(SHAPES[name], grade * 1e-3)
                    if not np.isfinite(pvg.extents(spec).theta[1]):
                        print(f"| {name} | {grade:g} | – | the peg turns freely in its hole |")
                        continue
                    r = row(pool, name, grade, step_s, args)
                    print(line(r, base), flush=True)
    use_timestep(None)
    print(f"\ntotal {time.perf_counter() - started:.0f} s wall")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
