"""Stages of the benchmark, cached by a hash of their configuration.

A stage writes into its own folder ``DIR/stages/{name}-{key}`` (``key``: the first 12
hex digits of the SHA-256 of its canonical JSON config). It counts as finished only once
``stage.json`` (config, wall time and the SHA-256 of every file it wrote) is there,
written atomically after everything else: an interrupted stage is run again in the same
folder (an RS-GAIL or deep-RL training resumes from its checkpoint there), and a finished
one is never run twice. A finished folder whose files are missing or differ from their
digests is bad: :meth:`StageCache.discard_bad` moves it aside (``stages/.bad/``) and says
why, and the stage runs afresh. Every file of a stage is written atomically by the one
task that runs it (the executors submit each stage once), so any number of workers can
fill one cache.
"""

from __future__ import annotations

import hashlib
import json
import os
import socket
import time
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

from tolins.atomic import atomic_json
from tolins.bench.machine import cpu
from tolins.bench.store.integrity import (
    STAGES,
    StageFileError,
    digest_problem,
    folder_digests,
    read_json,
)

MARKER = "stage.json"

#: What a stage's job needs to run (a frozen dataclass of its kind).
SpecT = TypeVar("SpecT")


def stage_key(config: Mapping[str, Any]) -> str:
    """12 hex digits identifying ``config`` (JSON-serialisable, key order irrelevant)."""
    text = json.dumps(config, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:12]


@dataclass(frozen=True)
class Stage(Generic[SpecT]):
    """A stage as the run planned it, handed to its job as such.

    Attributes:
        name: Its name, e.g. ``eval-C2.3-seed0``.
        config: Its config, built once when it was planned: the key (and so the folder)
            is its hash, and its marker records it.
        spec: What its job needs to run, typed (the config is derived from it).
    """

    name: str
    config: Mapping[str, Any]
    spec: SpecT


class StageCache:
    """The stage folders under ``root/stages``."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root) / STAGES

    def folder(self, name: str, config: Mapping[str, Any]) -> Path:
        return self.root / f"{name}-{stage_key(config)}"

    def finished(self, name: str, config: Mapping[str, Any]) -> bool:
        return (self.folder(name, config) / MARKER).is_file()

    def run_stage(
        self,
        stage: Stage[Any],
        build: Callable[[Path], object],
        transient: Collection[str] = (),
    ) -> Path:
        """The finished folder of the planned ``stage`` (:meth:`run` with its name and
        config)."""
        return self.run(stage.name, stage.config, build, transient)[0]

    def run(
        self,
        name: str,
        config: Mapping[str, Any],
        build: Callable[[Path], object],
        transient: Collection[str] = (),
    ) -> tuple[Path, bool]:
        """The finished folder of the stage and whether it was cached; ``build(folder)``
        runs only when the stage has not finished before. Files named in ``transient``
        (a training's checkpoint) are what an interrupted ``build`` resumes from: they
        stay until the stage's record is written, are not part of it, and go then."""
        folder = self.folder(name, config)
        if (folder / MARKER).is_file():
            return folder, True
        folder.mkdir(parents=True, exist_ok=True)
        began, started = time.perf_counter(), time.time()
        build(folder)
        record = {
            "files": folder_digests(folder, skip=(MARKER, *transient)),
            "name": name,
            "config": dict(config),
            "wall_s": time.perf_counter() - began,
            "started": started,
            "finished": time.time(),
            "host": socket.gethostname(),
            "cpu": cpu()["description"],
            "pid": os.getpid(),
        }
        atomic_json(folder / MARKER, record, sort_keys=True)
        for file in transient:
            (folder / file).unlink(missing_ok=True)
        return folder, False

    def problem(self, folder: Path) -> str | None:
        """Why the finished stage in ``folder`` is bad (``None``: its marker is readable
        and every file it wrote is there with its digest)."""
        try:
            marker = read_json(folder / MARKER)
            if not isinstance(marker, dict) or not isinstance(marker.get("wall_s"), float):
                return f"{MARKER} is not a stage record"
        except StageFileError as error:
            return f"{MARKER}: {error.problem}"
        return digest_problem(folder, marker.get("files"))

    def discard_bad(self, name: str, config: Mapping[str, Any]) -> str | None:
        """Move the stage's finished folder aside when it is bad (:meth:`problem`), so
        that the stage runs again; the line that says so, else ``None``."""
        folder = self.folder(name, config)
        if not (folder / MARKER).is_file():
            return None
        problem = self.problem(folder)
        if problem is None:
            return None
        aside = self.root / ".bad" / f"{folder.name}-{time.time_ns()}"
        aside.parent.mkdir(parents=True, exist_ok=True)
        os.replace(folder, aside)
        return f"{folder}: bad ({problem}); moved to {aside}, running the stage again"

    def record(self, folder: Path) -> dict[str, Any]:
        """The marker of the finished stage in ``folder``: its config, wall time, when
        (``started``, ``finished``: Unix time), where (``host``, ``cpu``, ``pid``) it ran,
        and ``files`` (the SHA-256 of each file it wrote)."""
        return read_json(folder / MARKER)

    def ran_here(self, folder: Path) -> bool:
        """Whether the finished stage in ``folder`` ran on this machine: its marker's host
        is this one's, and so is its CPU (a marker written before markers named the CPU:
        the host alone)."""
        marker = self.record(folder)
        same_cpu = marker.get("cpu", cpu()["description"]) == cpu()["description"]
        return marker.get("host") == socket.gethostname() and same_cpu

    def wall_s(self, folder: Path) -> float:
        """The wall time (s) the finished stage in ``folder`` took when it ran."""
        return float(self.record(folder)["wall_s"])
