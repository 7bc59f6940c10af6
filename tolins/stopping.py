"""A request that this process's work stop early: both episode loops (the vector env's,
:mod:`tolins.rollouts.runner`, and the single env's,
:func:`tolins.rollouts.episodes.run_episode`) raise :class:`Stopped` at their next control
step once :func:`request_stop` was called, until :func:`clear_stop`.

The bench's local executor requests it when it is interrupted (Ctrl-C) or a stage fails,
so that the stages running beside it end within a control step instead of running to
their end; their finished work (stage folders, RS-GAIL's per-iteration checkpoints) is
kept, as every file is written atomically. Work waiting on other processes (a deep-RL
training's, the inference study's) waits through :func:`wait_unless_stopped`, and its
owner ends those processes.
"""

from __future__ import annotations

import multiprocessing
import threading
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")
_requested = threading.Event()


class Stopped(Exception):
    """Work ended because a stop was requested (:func:`request_stop`)."""


def request_stop() -> None:
    """Ask every rollout loop of this process to stop at its next control step."""
    _requested.set()


def clear_stop() -> None:
    """Let rollouts run again."""
    _requested.clear()


def stop_requested() -> bool:
    """Whether a stop has been requested and not cleared."""
    return _requested.is_set()


def raise_if_stopped() -> None:
    """Raise :class:`Stopped` if a stop has been requested."""
    if _requested.is_set():
        raise Stopped("stopped on request (the run was interrupted or another stage failed)")


def wait_unless_stopped(get: Callable[[float], T], every: float = 0.5) -> T:
    """What ``get(timeout)`` returns (a result from another process: it raises
    ``multiprocessing.TimeoutError`` while there is none yet), checking for a stop request
    every ``every`` seconds meanwhile (:class:`Stopped`)."""
    while True:
        try:
            return get(every)
        except multiprocessing.TimeoutError:
            raise_if_stopped()
