"""An exclusive lock on a bench's ``--out`` folder: two benches never fill one cache at
once (both would train every stage). ``fcntl.flock`` on ``DIR/.lock``: the kernel drops it
when the process ends, however it ends, so a stale lock never blocks a later run."""

from __future__ import annotations

import contextlib
import fcntl
import os
import socket
from collections.abc import Iterator
from pathlib import Path

LOCK = ".lock"


class FolderInUse(ValueError):
    """Another process holds the folder's lock."""


@contextlib.contextmanager
def locked_folder(folder: str | os.PathLike) -> Iterator[Path]:
    """Hold ``folder/.lock`` (creating the folder) for the block; :class:`FolderInUse`
    naming the holder (its pid and host, as it wrote them) when another process has it."""
    path = Path(folder) / LOCK
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 200, 0).decode(errors="replace").strip() or "another process"
            raise FolderInUse(
                f"{folder} is in use by another tolins bench ({holder}); allowed: wait for "
                "it to finish, or another --out"
            ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode(), 0)
        yield Path(folder)
    finally:
        os.close(fd)  # releases the lock
