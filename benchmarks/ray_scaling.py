"""RS-GAIL iteration throughput and a short ``tolins bench`` on threads vs Ray, same run.

Usage::

    python benchmarks/ray_scaling.py                      # about 8 min on 2 cores
    python benchmarks/ray_scaling.py --iterations 2 --rows C1.1 --profile tiny  # smoke test

What it measures, in one process:

1. **RS-GAIL iterations.** π_n on ``Circle2x2`` (MuJoCo) from a BC policy with the quick
   profile's population (16 candidates × 4 episodes, 8 curve episodes), ``--iterations``
   iterations, first on :class:`tolins.rollouts.pool.VectorPool` (2 threads, the local
   default), then on :class:`tolins.rollouts.ray_pool.RayPool` (one actor per CPU of a
   ``ray.init(num_cpus=CPUS)``); the first iteration's time (it starts the actors) and,
   from the median of the later ones, iterations per minute and env steps per second of
   each, their ratio, and whether both searches are identical (they must be).
2. **A short bench.** ``tolins bench --profile PROFILE --rows ROWS --no-study`` in fresh
   folders with ``--executor local`` then ``--executor ray`` (the same Ray instance):
   wall time of each, their ratio, identical ``results.json`` rows, and where the Ray
   run's ``timeline.png`` is (the stages on their workers, from ``run.json``).

It prints one JSON object (``--json PATH`` also writes it). The machine's load average
is recorded before and after: figures from a machine that others share are noisy.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

ENV = "tolins/Circle2x2-v1"


def rs_gail_throughput(iterations: int, cpus: int) -> dict:
    """Part 1: the same RS-GAIL run on threads and on Ray actors."""
    import numpy as np

    from tolins.learning.imitation.bc import behaviour_clone
    from tolins.learning.imitation.config import BCConfig, RSGailConfig
    from tolins.learning.imitation.demonstrations import collect
    from tolins.learning.imitation.rs_gail import Workpiece, train_rs_gail
    from tolins.rollouts.pool import VectorPool
    from tolins.rollouts.ray_pool import RayPool

    demos = collect(ENV, "safe", 50, seed=0, backend="mujoco")
    policy = behaviour_clone(demos, BCConfig(epochs=200), seed=0).policy
    config = RSGailConfig(iterations=iterations, popsize=16, episodes=4, eval_episodes=8)
    figures, runs = {}, {}
    for name, make in (("threads", lambda: VectorPool(num_threads=2)), ("ray", RayPool.start)):
        pool = make()
        out = Path(tempfile.mkdtemp(prefix=f"rs-gail-{name}-"))
        began = time.perf_counter()
        result = train_rs_gail(
            policy.with_flat(policy.get_flat()),
            [Workpiece(ENV)],
            demos,
            config,
            seed=0,
            backend="mujoco",
            out=out,
            metadata={},
            progress=False,
            pool=pool,
        )
        wall = time.perf_counter() - began
        (pool.shutdown if name == "ray" else pool.close)()
        shutil.rmtree(out)
        rows = result.history[1:] or result.history  # the first starts the workers
        steady = float(np.median([row["wall_s"] for row in rows]))
        steps = sum(row["env_steps"] for row in rows) / len(rows)
        figures[name] = {
            "wall_s": wall,
            "first_iteration_s": result.history[0]["wall_s"],
            "median_iteration_s": steady,
            "iterations_per_min": 60 / steady,
            "env_steps_per_s": steps / steady,
        }
        runs[name] = result
    same = [{k: v for k, v in r.items() if k != "wall_s"} for r in runs["ray"].history] == [
        {k: v for k, v in r.items() if k != "wall_s"} for r in runs["threads"].history
    ] and np.array_equal(runs["ray"].means, runs["threads"].means)
    ratio = figures["ray"]["iterations_per_min"] / figures["threads"]["iterations_per_min"]
    return {**figures, "ray_over_threads": ratio, "identical": bool(same)}


def bench_wall(profile: str, rows: str, seeds: int | None, keep: Path) -> dict:
    """Part 2: the same short bench with the local and the Ray executor."""
    from tolins.bench.pipeline.config import BenchConfig
    from tolins.bench.pipeline.runner import run_bench

    figures, outputs = {}, {}
    for executor in ("local", "ray"):
        out = Path(tempfile.mkdtemp(prefix=f"bench-{executor}-"))
        config = BenchConfig(
            profile=profile, rows=rows, seeds=seeds, out=str(out), study=False, executor=executor
        )
        run = run_bench(config, progress=False, log=lambda _: None)
        figures[executor] = {"wall_s": run.wall_s, "stages_s": sum(run.stage_wall_s.values())}
        outputs[executor] = json.loads((out / "results.json").read_text())["rows"]
        keep.mkdir(parents=True, exist_ok=True)
        shutil.copy(out / "timeline.png", keep / f"timeline_{executor}.png")
        shutil.copy(out / "run.json", keep / f"run_{executor}.json")
        shutil.rmtree(out)
    return {
        **figures,
        "ray_over_local": figures["ray"]["wall_s"] / figures["local"]["wall_s"],
        "identical": outputs["ray"] == outputs["local"],
        "timelines": str(keep),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--iterations", type=int, default=5, help="RS-GAIL iterations")
    parser.add_argument("--cpus", type=int, default=os.cpu_count(), help="Ray's num_cpus")
    parser.add_argument("--profile", default="quick", help="bench profile of part 2")
    parser.add_argument("--rows", default="C2.1,C2.3", help="bench rows of part 2")
    parser.add_argument("--seeds", type=int, help="training seeds of part 2")
    parser.add_argument("--keep", default="benchmarks/ray_scaling", help="timelines go here")
    parser.add_argument("--json", help="also write the figures here")
    args = parser.parse_args()
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    import ray

    load = os.getloadavg()
    ray.init(num_cpus=args.cpus, include_dashboard=False, log_to_driver=False)
    try:
        report = {
            "date": time.strftime("%Y-%m-%d"),
            "cpus": args.cpus,
            "rs_gail": rs_gail_throughput(args.iterations, args.cpus),
            "bench": bench_wall(args.profile, args.rows, args.seeds, Path(args.keep)),
            "load_before": load,
            "load_after": os.getloadavg(),
        }
    finally:
        ray.shutdown()
    text = json.dumps(report, indent=2)
    print(text)
    if args.json:
        Path(args.json).write_text(text + "\n")


if __name__ == "__main__":
    main()
