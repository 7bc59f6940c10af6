"""Atomic file writes: a reader sees the old file or the whole new one, never half of it.

A writer that is killed leaves its hidden temporary behind. Writers that put their process
id into the temporary's name let the next writer there remove the leftovers of processes
that no longer run (:func:`remove_dead_temporaries`), and never a live writer's. Two
writers of one place exclude each other with :func:`exclusive_lock`.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import re
import shutil
import tempfile
from collections.abc import Callable, Iterator
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


def process_running(pid: int) -> bool:
    """Whether the process ``pid`` runs (this process does; another user's counts as
    running, since it cannot be asked)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_dead_temporaries(folder: str | os.PathLike, pattern: re.Pattern[str]) -> list[Path]:
    """Remove the files and folders in ``folder`` whose whole name matches ``pattern`` and
    whose process is not running; the paths removed. The process id is the first of
    ``pattern``'s groups that matched."""
    folder = Path(folder)
    removed: list[Path] = []
    if not folder.is_dir():
        return removed
    for candidate in folder.iterdir():
        match = pattern.fullmatch(candidate.name)
        pid = next((group for group in match.groups() if group), None) if match else None
        if pid is None or process_running(int(pid)):
            continue
        if candidate.is_dir() and not candidate.is_symlink():
            shutil.rmtree(candidate, ignore_errors=True)
        else:
            candidate.unlink(missing_ok=True)
        removed.append(candidate)
    return removed


@contextlib.contextmanager
def exclusive_lock(
    path: str | os.PathLike,
    holder: str,
    busy: Callable[[str], Exception],
    *,
    remove: bool = False,
    holder_bytes: int = 200,
) -> Iterator[Path]:
    """Hold an exclusive ``fcntl.flock`` on the file ``path`` (creating it and its folder)
    for the block, with the line ``holder`` (who holds it) written in it; the path.

    When another descriptor holds it, raises ``busy(text)`` at once, ``text`` being what its
    holder wrote (the first ``holder_bytes`` bytes) or "another process". The kernel drops
    the lock when its process ends, however it ends, so a stale file never blocks a later
    run. With ``remove`` the file is removed on release; a process that opened it before
    and locks it after finds it gone from ``path`` and opens the one there now, so no two
    processes ever hold the lock of ``path`` at once."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = _locked_descriptor(path, busy, reopen=remove, holder_bytes=holder_bytes)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{holder}\n".encode(), 0)
        yield path
    finally:
        if remove:
            path.unlink(missing_ok=True)  # still locked: whoever locks it next reopens
        os.close(fd)  # releases the lock


def _locked_descriptor(
    path: Path, busy: Callable[[str], Exception], *, reopen: bool, holder_bytes: int
) -> int:
    """A descriptor of ``path`` locked exclusively (:func:`exclusive_lock`); with ``reopen``,
    of the file at ``path`` now, not one that its holder removed since it was opened."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            text = os.pread(fd, holder_bytes, 0).decode(errors="replace").strip()
            os.close(fd)
            raise busy(text or "another process") from None
        except BaseException:
            os.close(fd)
            raise
        if not reopen or _same_file(fd, path):
            return fd
        os.close(fd)


def _same_file(fd: int, path: Path) -> bool:
    """Whether the open file ``fd`` is the file at ``path`` now."""
    try:
        return os.path.samestat(os.fstat(fd), os.stat(path))
    except FileNotFoundError:
        return False
