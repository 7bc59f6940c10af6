"""How well ``tolins bench``'s progress bar foresaw the time left: its estimates against
the time the run's stages actually took to finish.

Usage::

    python benchmarks/progress_accuracy.py DIR            # the estimates the run logged
    python benchmarks/progress_accuracy.py DIR --replay   # today's estimator over its run.json

``DIR`` is a bench's folder. Without ``--replay`` it reads ``DIR/progress.jsonl``, the
estimate the bar showed at the start and at each stage's start and end (the run must have
finished every stage). With ``--replay`` it re-estimates offline from ``DIR/run.json``:
at each stage's start and end, the stages finished by then (their wall times, and cached
ones that ran on this host), the ones running and for how long, the dependencies and
expected costs of the run's plan today, and the workers (``config.workers`` locally, else
the most stages that ran at once): what the bar would show now on that run.

Either way, the actual time left at an event is the last stage's end less the event's
time, and the error ``|estimate - actual| / actual``; printed: the events, and the largest
error from a quarter of the run on (while at least ``--floor`` seconds are left: in the
last seconds any relative error grows without bound), with the largest error in seconds
after that, and how many events from a quarter on had no estimate. ``--json PATH`` writes
the figures.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import socket
import tempfile
from pathlib import Path

from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.pipeline.progress import estimate_remaining, expected_cost
from tolins.bench.pipeline.runner import plan_bench, study_workers


def logged(folder: Path) -> list[tuple[float, float | None]]:
    """``(t, estimate)`` of each line of ``folder/progress.jsonl`` (t from the bar's start)."""
    lines = [json.loads(line) for line in (folder / "progress.jsonl").read_text().splitlines()]
    if not lines or lines[-1]["finished"] != lines[-1]["total"]:
        raise SystemExit(f"{folder}/progress.jsonl: the run did not finish every stage")
    return [(line["t"], line["remaining_s"]) for line in lines]


def replayed(folder: Path) -> list[tuple[float, float | None]]:
    """``(t, estimate)`` at each stage's start and end of ``folder/run.json``'s run, by
    today's estimator (t from the first stage's start)."""
    record = json.loads((folder / "run.json").read_text())
    stages = record["stages"]
    fields = {f.name for f in dataclasses.fields(BenchConfig)}
    config = {k: v for k, v in record["config"].items() if k in fields and k != "out"}
    with tempfile.TemporaryDirectory() as empty:
        plan = plan_bench(BenchConfig(**config, out=empty))
    needs = {stage.name: stage.needs for stage in plan}
    profile = PROFILES[record["config"]["profile"]]
    workers = study_workers(record["config"].get("executor", "local") == "local")
    expected = {n: expected_cost(n, profile, record["config"]["backend"], workers) for n in stages}
    ran = {n: s for n, s in stages.items() if not s["cached"]}
    here = socket.gethostname()
    cached = {n: s["wall_s"] for n, s in stages.items() if s["cached"] and s["host"] == here}
    begin = min(s["started"] for s in ran.values())
    workers = record["config"]["workers"]
    if record["config"]["executor"] != "local":
        workers = _most_at_once(ran.values())
    order = [name for name in needs if name in ran] + [n for n in ran if n not in needs]
    todo_needs = {name: tuple(d for d in needs.get(name, ()) if d in ran) for name in order}
    events = sorted({s["started"] for s in ran.values()} | {s["finished"] for s in ran.values()})
    estimates = []
    for now in events:
        done = {n: s["wall_s"] for n, s in ran.items() if s["finished"] <= now}
        todo = {n: d for n, d in todo_needs.items() if n not in done}
        started = {n: s["started"] for n, s in ran.items() if n in todo and s["started"] <= now}
        running = {name: now - began for name, began in started.items()}
        walls = {**cached, **done}
        ages = {n: now - ran[n]["finished"] if n in ran else now - begin for n in walls}
        left = estimate_remaining(todo, expected, walls, running, workers, ages)
        estimates.append((now - begin, left))
    return estimates


def _most_at_once(stages) -> int:
    points = sorted([(s["started"], 1) for s in stages] + [(s["finished"], -1) for s in stages])
    most = count = 0
    for _, step in sorted(points, key=lambda p: (p[0], p[1])):
        count += step
        most = max(most, count)
    return most


def errors(estimates: list[tuple[float, float | None]], floor: float) -> dict:
    """The figures of ``estimates`` (``(t, estimate)``, the last at the run's end)."""
    end = estimates[-1][0]
    rows, tail, estimating = [], [], 0
    for t, estimate in estimates:
        left = end - t
        if t < end / 4 or left <= 0:
            continue
        if estimate is None:
            estimating += 1
        elif left >= floor:
            rows.append((t, estimate, left, abs(estimate - left) / left))
        else:
            tail.append(abs(estimate - left))
    first = next((t for t, e in estimates if e is not None), None)
    return {
        "run_s": end,
        "first_estimate_at_s": first,
        "events_from_a_quarter_on": len(rows) + len(tail) + estimating,
        "estimating_from_a_quarter_on": estimating,
        "max_error_from_a_quarter_on": max((r[3] for r in rows), default=None),
        "mean_error_from_a_quarter_on": sum(r[3] for r in rows) / len(rows) if rows else None,
        "floor_s": floor,
        "max_error_s_in_the_last_floor": max(tail, default=None),
        "worst": max(rows, key=lambda r: r[3], default=None),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path, help="a tolins bench folder")
    parser.add_argument("--replay", action="store_true", help="re-estimate from run.json")
    parser.add_argument("--floor", type=float, default=60.0, help="seconds left (default 60)")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    parser.add_argument("--quiet", action="store_true", help="the figures only, no events")
    args = parser.parse_args()
    estimates = replayed(args.folder) if args.replay else logged(args.folder)
    end = estimates[-1][0]
    if not args.quiet:
        print("    t (s)  run %  estimate (s)  actual (s)  error")
        for t, estimate in estimates:
            left = end - t
            error = "" if estimate is None or left <= 0 else f"{abs(estimate - left) / left:6.1%}"
            shown = "estimating" if estimate is None else f"{estimate:10.0f}"
            print(f"{t:9.1f}  {t / end:5.0%}  {shown:>12}  {left:10.0f}  {error}")
    figures = errors(estimates, args.floor)
    print(json.dumps(figures, indent=1))
    if args.json:
        args.json.write_text(json.dumps(figures, indent=1) + "\n")


if __name__ == "__main__":
    main()
