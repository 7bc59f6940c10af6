"""Hidden temporaries of processes that are gone: a killed ``tolins record`` (or a
screenshot) leaves ``.NAME.PID.tmp`` beside its output; the next writer there removes the
ones whose process no longer runs (a live one's are left alone)."""

from __future__ import annotations

import os
import re
from pathlib import Path


def remove_dead_temporaries(path: Path) -> list[Path]:
    """Remove ``.NAME.PID.tmp``, ``.STEM.PID.tmpSUFFIX`` and ``.STEM.PID.cut.rrd`` beside
    ``path`` (the temporaries of :class:`~tolins.record.recorder.RrdFile` and of a
    screenshot) whose process ``PID`` is not running; the paths removed."""
    name, stem, suffix = (re.escape(part) for part in (path.name, path.stem, path.suffix))
    pattern = re.compile(rf"^\.(?:{name}\.(\d+)\.tmp|{stem}\.(\d+)\.(?:tmp{suffix}|cut\.rrd))$")
    removed = []
    if not path.parent.is_dir():
        return removed
    for candidate in path.parent.glob(".*"):
        match = pattern.match(candidate.name)
        if match and not _running(int(match.group(1) or match.group(2))):
            candidate.unlink(missing_ok=True)
            removed.append(candidate)
    return removed


def _running(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True
