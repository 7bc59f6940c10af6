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

A process that ends on a signal can first bring its work to a point it can resume from:
inside :class:`DeferredSignals` SIGINT and SIGTERM are only noted, and the work delivers
them (:meth:`DeferredSignals.deliver`) once it has written its checkpoint (a deep-RL
training's process, which the bench's executor ends with SIGTERM).
"""

from __future__ import annotations

import multiprocessing
import signal
import threading
from collections.abc import Callable
from types import FrameType
from typing import Any, TypeVar

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


class DeferredSignals:
    """SIGINT and SIGTERM held back inside the ``with`` block (in the main thread only:
    elsewhere Python delivers no signal, and nothing changes).

    A held signal is :attr:`pending` until :meth:`deliver` (or leaving the block) restores
    the previous handlers and raises it again, so it then does what it would have done at
    once: SIGINT raises ``KeyboardInterrupt``, SIGTERM ends the process. Of several, SIGTERM
    is the one delivered (the bench's executor follows a Ctrl-C with SIGTERM to its
    processes).
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.pending: int | None = None
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> DeferredSignals:
        if threading.current_thread() is threading.main_thread():
            for number in self.SIGNALS:
                self._previous[number] = signal.signal(number, self._hold)
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.deliver()

    def _hold(self, number: int, _frame: FrameType | None) -> None:
        if self.pending is None or number == signal.SIGTERM:
            self.pending = number

    def deliver(self) -> None:
        """Restore the handlers from before the block and raise the pending signal, if any."""
        previous, self._previous = self._previous, {}
        for number, handler in previous.items():
            signal.signal(number, signal.SIG_DFL if handler is None else handler)
        number, self.pending = self.pending, None
        if number is not None:
            signal.raise_signal(number)
