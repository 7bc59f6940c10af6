"""Checks of command-line options, shared by every ``tolins`` command.

Each runs before any work starts, so a bad option costs nothing and loses nothing. The
argparse ``type=`` functions (:func:`seed`, :func:`port`, :func:`positive_int`,
:func:`env_ids`) report through argparse; the path checks (:func:`output_file`,
:func:`output_folder`, :func:`input_file`) and the optional parts' checks
(:func:`require_robot`: the Panda model of ``tolins[robot]``) raise :class:`OptionError`.
Both end as one line on stderr and exit status 2 (:func:`tolins.cli.main`).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import NoReturn

from tolins.geometry.validation import SEED_MAX

PORT_MAX = 65535
#: The help of ``--trust-pickle`` (``tolins evaluate``, ``tolins record``): what it lets run.
TRUST_PICKLE_HELP = (
    "load an SB3 PATH.zip with SB3's own load, which unpickles and so runs code "
    "stored in the zip (default: rebuilt from its JSON and weights, without pickle)"
)


class OptionError(ValueError):
    """An option's value that is not allowed: one line naming the option, the value and
    what is allowed."""


class UsageError(OptionError):
    """What argparse found wrong with the command line of ``prog``."""

    def __init__(self, prog: str, message: str) -> None:
        super().__init__(f"{message} (see {prog} --help)")
        self.prog = prog


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors raise :class:`UsageError` (:func:`tolins.cli.main`
    prints it as one line and returns 2; ``--help`` has the usage)."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(self.prog, message)


def _integer(text: str, low: int, high: int | None = None) -> int:
    """``text`` as an integer in ``[low, high]`` (no upper end with ``high=None``)."""
    allowed = f"an integer ≥ {low}" if high is None else f"an integer {low} … {high}"
    try:
        value = int(text)
    except ValueError:
        message = f"{text!r} is not an integer; allowed: {allowed}"
        raise argparse.ArgumentTypeError(message) from None
    if value < low or (high is not None and value > high):
        raise argparse.ArgumentTypeError(f"{value} is not allowed; allowed: {allowed}")
    return value


def seed(text: str) -> int:
    """A seed option: an integer 0 … 2**32 - 1."""
    return _integer(text, 0, SEED_MAX)


def port(text: str) -> int:
    """A TCP port option: an integer 1 … 65535."""
    return _integer(text, 1, PORT_MAX)


def positive_int(text: str) -> int:
    """A count option: an integer ≥ 1."""
    return _integer(text, 1)


def non_negative_int(text: str) -> int:
    """A count option that may be 0 (none): an integer ≥ 0."""
    return _integer(text, 0)


class JoinedList(argparse.Action):
    """A comma-separated list option that adds up when repeated: ``--rows A --rows B,C``
    is ``--rows A,B,C`` (not the last one alone)."""

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        before = getattr(namespace, self.dest, None)
        setattr(namespace, self.dest, values if before is None else f"{before},{values}")


def non_negative_float(text: str) -> float:
    """A finite number option ≥ 0 (a time, a distance)."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}; allowed: a finite number ≥ 0")
    return value


def env_ids(
    allowed: Collection[str],
    *,
    several: bool = False,
    reasons: Mapping[str, str] | None = None,
) -> Callable[[str], str]:
    """A ``type=`` for ``--env``: one id of ``allowed`` (or, with ``several``, a
    comma-separated list of them), returned unchanged. ``reasons`` says why a known id
    is not among the allowed ones."""
    reasons = reasons or {}

    def check(text: str) -> str:
        parts = text.split(",") if several else [text]
        for part in parts:
            if part not in allowed:
                why = f" ({reasons[part]})" if part in reasons else ""
                raise argparse.ArgumentTypeError(
                    f"{part!r} is not supported here{why}; allowed: {', '.join(allowed)}"
                )
        return text

    check.__name__ = "env id"
    return check


def preset_env_ids(*, several: bool = False) -> Callable[[str], str]:
    """:func:`env_ids` of every preset task, the paper's and the grades
    (``tolins.envs.tasks.env_ids``); the generic id is refused, since its ``socket=`` has
    no option."""
    from tolins.envs import tasks

    reasons = dict.fromkeys(tasks.GENERIC_IDS.values(), "it needs socket=, which no option sets")
    known = env_ids(tasks.env_ids(generic=False), several=several, reasons=reasons)

    def check(text: str) -> str:
        known(text)
        for part in text.split(","):
            try:
                require_robot_for(part)
            except OptionError as error:
                raise argparse.ArgumentTypeError(str(error)) from None
        return text

    check.__name__ = "env id"
    return check


def require_robot(user: str) -> None:
    """:class:`OptionError` (one line naming ``tolins[robot]``) unless the Panda model is
    installed; ``user`` names what needs it."""
    from tolins.mjcf.panda import require_panda

    try:
        require_panda(user)
    except ImportError as error:
        raise OptionError(str(error)) from None


def require_robot_for(env_id: str, option: str | None = None) -> None:
    """:func:`require_robot` if ``env_id`` (the value of ``option``, if given) is a robot
    task's id."""
    from tolins.envs import tasks

    robot = {
        t.gym_id_of(v) for t in tasks.GYM_TASKS if t.robot != "free" for v in t.physics_versions
    }
    if env_id in robot:
        require_robot(env_id if option is None else f"{option} {env_id}")


def input_file(option: str, path: str | os.PathLike[str]) -> Path:
    """``path`` if it is an existing file."""
    path = Path(path)
    if not path.is_file():
        what = "is a folder" if path.is_dir() else "does not exist"
        raise OptionError(f"{option} {path}: {what}; allowed: an existing file")
    return path


def output_file(
    option: str, path: str | os.PathLike[str], *, suffixes: tuple[str, ...] = ()
) -> Path:
    """``path`` if a file can be written there: not a folder, one of ``suffixes`` (if
    given), in a folder that exists and is writable or can be created. Nothing is created."""
    path = Path(path)
    if suffixes and path.suffix.lower() not in suffixes:
        raise OptionError(
            f"{option} {path}: wrong file type; allowed: a path ending in {' or '.join(suffixes)}"
        )
    if path.is_dir():
        raise OptionError(f"{option} {path}: is a folder; allowed: a file path")
    _check_writable(option, path, path.parent)
    return path


def output_folder(option: str, path: str | os.PathLike[str]) -> Path:
    """``path`` if it is a writable folder or one can be created there. Nothing is created."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OptionError(f"{option} {path}: is a file; allowed: a folder (existing or new)")
    _check_writable(option, path, path)
    return path


def _check_writable(option: str, path: Path, folder: Path) -> None:
    """Raise unless a file can be created in ``folder`` or, where it is missing, in the
    nearest existing folder above it (probed with a temporary file, removed at once)."""
    existing = folder
    try:
        while not existing.exists():
            existing = existing.parent
        if not existing.is_dir():
            raise OptionError(f"{option} {path}: {existing} is a file; allowed: a path in a folder")
        handle, probe = tempfile.mkstemp(prefix=".tolins-probe-", dir=existing)
    except OSError as error:
        raise OptionError(
            f"{option} {path}: cannot write in {existing} ({error.strerror}); "
            "allowed: a path in a writable folder"
        ) from None
    os.close(handle)
    os.unlink(probe)


def fail(prog: str, error: Exception) -> int:
    """Print ``error`` as one line for ``prog`` on stderr; the exit status of a bad option."""
    print(f"{prog}: {error}", file=sys.stderr)
    return 2


#: The exit status of a training that refused to start or go on
#: (:class:`~tolins.learning.artefacts.RunRefused`).
REFUSED = 3


def refused(prog: str, error: Exception) -> int:
    """Print ``error`` (a refused run) as one line for ``prog`` on stderr; :data:`REFUSED`."""
    print(f"{prog}: {error}", file=sys.stderr)
    return REFUSED
