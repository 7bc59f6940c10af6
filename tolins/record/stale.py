"""Hidden temporaries of processes that are gone: a killed ``tolins record`` (or a
screenshot) leaves ``.NAME.PID.tmp`` beside its output; the next writer there removes the
ones whose process no longer runs (a live one's are left alone)."""

from __future__ import annotations

import re
from pathlib import Path

from tolins import atomic


def remove_dead_temporaries(path: Path) -> list[Path]:
    """Remove ``.NAME.PID.tmp``, ``.STEM.PID.tmpSUFFIX`` and ``.STEM.PID.cut.rrd`` beside
    ``path`` (the temporaries of :class:`~tolins.record.recorder.RrdFile` and of a
    screenshot) whose process ``PID`` is not running; the paths removed."""
    name, stem, suffix = (re.escape(part) for part in (path.name, path.stem, path.suffix))
    pattern = re.compile(rf"\.(?:{name}\.(\d+)\.tmp|{stem}\.(\d+)\.(?:tmp{suffix}|cut\.rrd))")
    return atomic.remove_dead_temporaries(path.parent, pattern)
