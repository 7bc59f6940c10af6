"""Stages of the benchmark, cached by a hash of their configuration.

A stage writes into its own folder ``DIR/stages/{name}-{key}`` (``key``: the first 12
hex digits of the SHA-256 of its canonical JSON config). It counts as finished only once
``stage.json`` (config and wall time) is there, written atomically after everything
else: an interrupted stage is run again (an RS-GAIL stage resumes from its checkpoint),
and a finished one is never run twice. Every file of a stage is written atomically by
the one task that runs it (the executors submit each stage once), so any number of
workers can fill one cache.
"""

from __future__ import annotations

import hashlib
import json
import os
import socket
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from tolins.atomic import atomic_json

MARKER = "stage.json"


def stage_key(config: Mapping[str, Any]) -> str:
    """12 hex digits identifying ``config`` (JSON-serialisable, key order irrelevant)."""
    text = json.dumps(config, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:12]


class StageCache:
    """The stage folders under ``root/stages``."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root) / "stages"

    def folder(self, name: str, config: Mapping[str, Any]) -> Path:
        return self.root / f"{name}-{stage_key(config)}"

    def finished(self, name: str, config: Mapping[str, Any]) -> bool:
        return (self.folder(name, config) / MARKER).is_file()

    def run(
        self, name: str, config: Mapping[str, Any], build: Callable[[Path], object]
    ) -> tuple[Path, bool]:
        """The finished folder of the stage and whether it was cached; ``build(folder)``
        runs only when the stage has not finished before."""
        folder = self.folder(name, config)
        if (folder / MARKER).is_file():
            return folder, True
        folder.mkdir(parents=True, exist_ok=True)
        began, started = time.perf_counter(), time.time()
        build(folder)
        record = {
            "name": name,
            "config": dict(config),
            "wall_s": time.perf_counter() - began,
            "started": started,
            "finished": time.time(),
            "host": socket.gethostname(),
            "pid": os.getpid(),
        }
        atomic_json(folder / MARKER, record, sort_keys=True)
        return folder, False

    def record(self, folder: Path) -> dict[str, Any]:
        """The marker of the finished stage in ``folder``: its config, wall time, when
        (``started``, ``finished``: Unix time) and where (``host``, ``pid``) it ran."""
        return json.loads((folder / MARKER).read_text())

    def wall_s(self, folder: Path) -> float:
        """The wall time (s) the finished stage in ``folder`` took when it ran."""
        return float(json.loads((folder / MARKER).read_text())["wall_s"])
