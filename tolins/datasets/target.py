"""Where a dataset goes: ``ROOT/NAME``, claimed by one writer at a time.

A dataset id is Minari's ``(namespace/)name-vN``, the version included. While a writer
builds ``ROOT/NAME`` it holds an exclusive lock on the hidden file ``.NAME.lock`` beside it
(``fcntl.flock``: the kernel drops it when the process ends, however it ends), so a second
writer of the same dataset is refused at once, before any work. The dataset is built in the
hidden folder ``.NAME.PID.RANDOM.tmp`` beside its place; the next writer of that dataset
removes the ones of processes that no longer run.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

from tolins import atomic

#: The dataset ids allowed, in words (what :func:`check_name` accepts).
#: Held around every HDF5 file access of this package's datasets: HDF5 locks the files it
#: opens, and two threads of one process that open datasets at once (the bench's stages
#: side by side) were refused (``BlockingIOError``, "unable to lock file").
HDF5_IO = threading.Lock()

ID_FORM = (
    "(namespace/)name-vN of letters, digits, '-' and '_' (a namespace of 2 or more "
    "characters, a version N of digits), e.g. tolins/circle2x2/expert-safe-v0"
)

#: The lock files this process holds, each with the thread that holds it.
_HELD: dict[Path, int] = {}


def check_name(name: str) -> None:
    """Raise ``ValueError`` naming ``name`` and :data:`ID_FORM` unless it is a Minari dataset
    id with a version."""
    from minari.dataset.minari_dataset import parse_dataset_id

    try:
        version = parse_dataset_id(name)[2]
    except (ValueError, TypeError):  # TypeError: Minari's parse of an id without a version
        version = None
    if not isinstance(version, int):
        raise ValueError(f"--name {name!r} is not a Minari dataset id; allowed: {ID_FORM}")


def check_target(root: str | os.PathLike, name: str) -> Path:
    """The folder ``ROOT/NAME`` a dataset would take; ``ValueError`` for a malformed Minari
    id or a folder that exists (nothing is created)."""
    check_name(name)
    target = Path(root).resolve() / name
    if target.exists():
        raise ValueError(f"{target} exists; allowed: a new --name or --out (or remove it)")
    for folder in target.parents:
        if folder.exists() and not folder.is_dir():
            raise ValueError(f"--name {name!r}: {folder} is a file; allowed: a path of folders")
    return target


@contextlib.contextmanager
def claim_target(root: str | os.PathLike, name: str) -> Iterator[Path]:
    """Hold the lock of ``ROOT/NAME`` for the block (creating the folders above it); the
    target. ``ValueError`` for a bad target (:func:`check_target`) or one that another
    process (or thread) is writing. Nested claims of one thread share the lock."""
    target = check_target(root, name)
    lock = target.parent / f".{target.name}.lock"
    if _HELD.get(lock) == threading.get_ident():
        yield target
        return

    def busy(holder: str) -> ValueError:
        return ValueError(
            f"{target} is being written by {holder}; allowed: wait for it to finish, "
            "or a new --name or --out"
        )

    with atomic.exclusive_lock(lock, f"process {os.getpid()}", busy, remove=True, holder_bytes=100):
        _HELD[lock] = threading.get_ident()
        try:
            yield check_target(root, name)  # the writer before may have finished meanwhile
        finally:
            del _HELD[lock]


def temporary_folder(target: Path) -> Path:
    """A new hidden folder ``.NAME.PID.RANDOM.tmp`` beside ``target`` (readable by all, as
    the dataset it becomes), after removing those of processes that no longer run."""
    remove_dead_temporaries(target)
    prefix = f".{target.name}.{os.getpid()}."
    temp = tempfile.mkdtemp(prefix=prefix, suffix=".tmp", dir=target.parent)
    os.chmod(temp, 0o755)  # mkdtemp makes it 0700; keep a folder's usual permissions
    return Path(temp)


def remove_dead_temporaries(target: Path) -> list[Path]:
    """Remove the temporary folders of ``target`` (:func:`temporary_folder`) whose process
    is not running; the paths removed."""
    pattern = re.compile(rf"\.{re.escape(target.name)}\.(\d+)\.[a-z0-9_]+\.tmp")
    return atomic.remove_dead_temporaries(target.parent, pattern)
