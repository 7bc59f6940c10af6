"""When and where each stage of a bench run ran: the ``stages`` and ``executor`` entries
of ``run.json`` and ``timeline.png`` (one lane per worker, one bar per stage that ran).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from tolins.atomic import atomic_json
from tolins.bench.pipeline.config import BenchRun
from tolins.bench.pipeline.progress import stage_kind as progress_kind
from tolins.bench.reports.plots import pyplot, save_figure

KINDS = {
    "demonstrations": "tab:purple",
    "training": "tab:blue",
    "evaluation": "tab:orange",
    "study": "tab:green",
}


def stage_kind(name: str) -> str:
    """``demonstrations``, ``training``, ``evaluation`` or ``study`` for a stage name: the
    progress bar's kinds (:func:`~tolins.bench.pipeline.progress.stage_kind`), the
    robustness and robot stages drawn as the evaluations they are."""
    kind = progress_kind(name)
    return "evaluation" if kind in ("robustness", "robot", "delicate") else kind


def worker_label(entry: dict[str, Any]) -> str:
    """The lane of a stage: its Ray node (or host) and process, and its thread if not the
    main one (the local executor's evaluation threads)."""
    where = f"node {entry['node'][:6]}" if entry.get("node") else str(entry.get("host"))
    thread = entry.get("thread")
    label = f"{where} pid {entry.get('pid')}"
    return label if thread in (None, "MainThread") else f"{label} {thread}"


def timeline_rows(stage_times: dict[str, dict[str, Any]]) -> list[dict[str, Any]]:
    """The stages that ran in this run (not cached), by start: name, kind, lane, and
    start/end in seconds since the first start."""
    ran = {n: t for n, t in stage_times.items() if not t["cached"] and t.get("started")}
    if not ran:
        return []
    zero = min(t["started"] for t in ran.values())
    rows = [
        {
            "name": name,
            "kind": stage_kind(name),
            "lane": worker_label(t),
            "start": t["started"] - zero,
            "end": t["finished"] - zero,
        }
        for name, t in ran.items()
    ]
    return sorted(rows, key=lambda row: (row["start"], row["name"]))


def plot_timeline(path: str | Path, rows: list[dict[str, Any]], title: str) -> Path:
    """A bar per stage (``rows`` of :func:`timeline_rows`) on its worker's lane."""
    plt = pyplot()
    lanes = sorted({row["lane"] for row in rows})
    unit, scale = ("minutes", 60) if max(row["end"] for row in rows) > 180 else ("s", 1)
    figure, axes = plt.subplots(figsize=(11, 1.2 + 0.45 * len(lanes)))
    span = max(row["end"] for row in rows) / scale
    for row in rows:
        y, left = lanes.index(row["lane"]), row["start"] / scale
        width = (row["end"] - row["start"]) / scale
        axes.barh(y, width, left=left, color=KINDS[row["kind"]], edgecolor="white")
        if row["kind"] == "training" and width > 0.08 * span:  # room for its name
            axes.text(left, y, f" {row['name']}", va="center", fontsize=7)
    axes.set_yticks(range(len(lanes)), lanes, fontsize=8)
    axes.set_xlabel(f"{unit} since the first stage started")
    axes.set_title(title, fontsize=10)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in KINDS.values()]
    axes.legend(handles, list(KINDS), loc="upper left", bbox_to_anchor=(1, 1), fontsize=8)
    figure.tight_layout()
    return save_figure(figure, path)


def plot_run_json(path: str | Path, run_json: str | Path) -> Path:
    """:func:`plot_timeline` of a bench's ``run.json`` (e.g. one copied elsewhere)."""
    record = json.loads(Path(run_json).read_text())
    title = f"tolins bench --profile {record['config']['profile']} " + (
        f"--executor {record['executor']['name']}: {record['wall_s'] / 60:.1f} min"
    )
    return plot_timeline(path, timeline_rows(record["stages"]), title)


def write_timeline(out: str | Path, run: BenchRun) -> list[Path]:
    """Add ``stages`` (:attr:`BenchRun.stage_times`) and ``executor`` to ``out/run.json``;
    draw ``out/timeline.png`` if any stage ran in this run (and the run draws figures)."""
    out = Path(out)
    record = json.loads((out / "run.json").read_text())
    record["executor"] = {"name": run.config.executor, "address": run.config.address}
    record["stages"] = run.stage_times
    written = [atomic_json(out / "run.json", record)]
    rows = timeline_rows(run.stage_times)
    if rows and run.config.figures:
        ran = sum(row["end"] - row["start"] for row in rows) / 60
        title = (
            f"tolins bench --profile {run.config.profile} --executor {run.config.executor}: "
            f"{len(rows)} stages, {ran:.1f} stage-min in {run.wall_s / 60:.1f} min"
        )
        written.append(plot_timeline(out / "timeline.png", rows, title))
    return written
