"""An exclusive lock on a bench's ``--out`` folder: two benches never fill one cache at
once (both would train every stage). ``fcntl.flock`` on ``DIR/.lock``: the kernel drops it
when the process ends, however it ends, so a stale lock never blocks a later run."""

from __future__ import annotations

import contextlib
import os
import socket
from collections.abc import Iterator
from pathlib import Path

from tolins import atomic

LOCK = ".lock"


class FolderInUse(ValueError):
    """Another process holds the folder's lock."""


@contextlib.contextmanager
def locked_folder(folder: str | os.PathLike) -> Iterator[Path]:
    """Hold ``folder/.lock`` (creating the folder) for the block; :class:`FolderInUse`
    naming the holder (its pid and host, as it wrote them) when another process has it."""

    def busy(holder: str) -> FolderInUse:
        return FolderInUse(
            f"{folder} is in use by another tolins bench ({holder}); allowed: wait for "
            "it to finish, or another --out"
        )

    holder = f"pid {os.getpid()} on {socket.gethostname()}"
    with atomic.exclusive_lock(Path(folder) / LOCK, holder, busy):
        yield Path(folder)
