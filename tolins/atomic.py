"""Atomic file writes: a reader sees the old file or the whole new one, never half of it."""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any


def atomic_write(path: str | os.PathLike, write: Callable[[Any], None], mode: str = "wb") -> Path:
    """Call ``write(file)`` on a temp file beside ``path``, flush it to disk, then
    ``os.replace`` it onto ``path`` (creating the folder). On any error the temp file is
    removed and ``path`` is left as it was."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.chmod(temp, 0o644)  # mkstemp makes it 0600; keep the usual permissions
        with os.fdopen(handle, mode) as file:
            write(file)
            file.flush()
            os.fsync(file.fileno())
        os.replace(temp, path)
    except BaseException:
        Path(temp).unlink(missing_ok=True)
        raise
    return path


def atomic_json(path: str | os.PathLike, data: Any, *, sort_keys: bool = False) -> Path:
    """``data`` as indented JSON (and a final newline) at ``path``, atomically."""
    text = json.dumps(data, indent=2, sort_keys=sort_keys) + "\n"
    return atomic_write(path, lambda file: file.write(text), mode="w")
