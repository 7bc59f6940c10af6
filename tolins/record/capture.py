"""Capture a headless rerun viewer once the recording it shows has streamed in.

``rerun --screenshot-to`` saves the frame drawn a fixed ten frames after start, whatever
has arrived by then: on a loaded machine, plots that still say "Loading..." and a scene
without its poses. Here the viewer runs headless as a server instead, and rerun's viewer
control client waits until the viewer has loaded the file, its time cursor stands at the
step expected, and :data:`SETTLED_SHOTS` screenshots in a row are identical before keeping
the last one (on two cores under four busy loops, every run gave the same picture, byte for
byte). A viewer that never settles is an error, not a screenshot.

The viewer runs with ``RUST_LOG=error``: it turns its log messages of lower levels (the
software rasterizer warning, the adapter and window size) into toasts over the top right
of the window otherwise.
"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from rerun.experimental import ViewerClient, ViewerState

from tolins.record.layout import STEP

#: The only interface a viewer listens on: nothing outside this machine reaches it.
LOOPBACK = "127.0.0.1"
#: The viewer's log level: what is less severe would be drawn as toasts over the screenshot.
VIEWER_LOG_LEVEL = "error"
#: Identical screenshots in a row that make the picture final.
SETTLED_SHOTS = 3
#: Seconds between two looks at the viewer.
POLL_S = 0.2
#: Seconds a stopped viewer gets to exit before it is killed.
STOP_S = 5.0
#: Ports tried, each picked free, before giving up (another process may take one first).
PORT_ATTEMPTS = 3


class CaptureError(RuntimeError):
    """The headless viewer did not start, or did not settle on the recording in time."""


def free_port() -> int:
    """A TCP port on the loopback interface that no one listens on now."""
    with socket.socket() as probe:
        probe.bind((LOOPBACK, 0))
        return probe.getsockname()[1]


def base_args(path: Path) -> list[str]:
    """Arguments of ``rerun`` that every viewer of ``path`` starts with: bound to
    :data:`LOOPBACK`, without the welcome screen."""
    return [str(path), "--bind", LOOPBACK, "--hide-welcome-screen"]


def headless_args(path: Path, port: int, window_size: str) -> list[str]:
    """Arguments of ``rerun`` that serve ``path`` in a headless viewer on ``port``."""
    return [
        *base_args(path),
        "--headless",
        *("--window-size", window_size, "--port", str(port)),
    ]


def viewer_environment(base: dict[str, str] | None = None) -> dict[str, str]:
    """``base`` (default: this process's environment) with the viewer's log level set."""
    return {**(os.environ if base is None else base), "RUST_LOG": VIEWER_LOG_LEVEL}


def settled(shots: Sequence[bytes], count: int = SETTLED_SHOTS) -> bool:
    """Whether the last ``count`` of ``shots`` (PNG bytes, oldest first) are identical."""
    return len(shots) >= count and len(set(shots[-count:])) == 1


def at_step(state: ViewerState, step: int | None, timeline: str = STEP) -> bool:
    """Whether the viewer's ``state`` (:meth:`ViewerClient.get_state`) has loaded
    everything and shows a recording whose time cursor on ``timeline`` stands at
    ``step`` (``None``: any time)."""
    if state.loading or not state.recordings:
        return False
    if step is None:
        return True
    return any(r.current_timeline == timeline and r.current_time == step for r in state.recordings)


def _stop(process: subprocess.Popen) -> None:
    """End ``process`` and what it started (its own process group)."""
    for sig, wait in ((signal.SIGTERM, STOP_S), (signal.SIGKILL, None)):
        try:
            os.killpg(process.pid, sig)
        except ProcessLookupError:
            break
        try:
            process.wait(timeout=wait)
            break
        except subprocess.TimeoutExpired:
            continue


def _stopped(log: Path, status: int | None) -> CaptureError:
    """The error of a viewer that exited: the first panic or error line of its log (else
    its exit status), and what it needs."""
    text = log.read_text(errors="replace") if log.is_file() else ""
    lines = [ln.strip() for ln in text.splitlines() if "panicked" in ln or "rror" in ln]
    lines = [ln for ln in lines if "XDG_RUNTIME_DIR" not in ln]  # harmless without a session
    hint = lines[0] if lines else f"exit status {status}"
    return CaptureError(
        f"the viewer stopped ({hint}); it needs a Vulkan driver, e.g. Debian's "
        "mesa-vulkan-drivers (scripts/setup.sh installs it)"
    )


def _connect(
    process: subprocess.Popen, port: int, log: Path, deadline: float
) -> ViewerClient | None:
    """A client of the viewer ``process`` serving on ``port``; ``None`` when it exited
    with status 0 before answering (``rerun`` hands its data to a viewer that already
    holds the port, and exits).

    Raises:
        CaptureError: it failed, or did not answer before ``deadline``.
    """
    while True:
        if process.poll() is not None:
            if process.returncode == 0:
                return None
            raise _stopped(log, process.returncode)
        if time.monotonic() > deadline:
            raise CaptureError(f"the viewer did not answer on port {port}")
        try:
            client = ViewerClient.connect(f"rerun+http://{LOOPBACK}:{port}/proxy")
        except ConnectionError:
            time.sleep(POLL_S)
            continue
        return client if process.poll() is None else None


@contextmanager
def headless_viewer(
    command: list[str], path: Path, *, window_size: str, deadline: float
) -> Iterator[ViewerClient]:
    """Start ``command`` (the ``rerun`` executable) serving ``path`` headless and yield a
    client connected to it; the viewer is stopped on exit.

    Raises:
        CaptureError: the viewer exited, or did not answer before ``deadline``
            (:func:`time.monotonic`).
    """
    with tempfile.TemporaryDirectory(prefix="tolins-viewer-") as folder:
        log = Path(folder) / "viewer.log"
        for _ in range(PORT_ATTEMPTS):
            port = free_port()
            with log.open("wb") as sink:
                process = subprocess.Popen(
                    [*command, *headless_args(path, port, window_size)],
                    env=viewer_environment(),
                    stdin=subprocess.DEVNULL,
                    stdout=sink,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,  # its own group: a wrapper script's child ends too
                )
            try:
                client = _connect(process, port, log, deadline)
                if client is not None:
                    yield client
                    return
            finally:
                _stop(process)
        raise CaptureError(
            f"the viewer exited before answering, {PORT_ATTEMPTS} times on free ports "
            "(exit status 0: as when another viewer takes the port first)"
        )


def capture(
    command: list[str],
    path: Path,
    *,
    step: int | None,
    timeout: float,
    window_size: str,
) -> bytes:
    """A PNG of the viewer showing ``path`` once everything has loaded, the time cursor
    stands at control step ``step`` (``None``: a recording without tolins's ``step``
    timeline) and the picture has stopped changing.

    Raises:
        CaptureError: the viewer failed, or had not settled after ``timeout`` seconds.
    """
    deadline = time.monotonic() + timeout
    with headless_viewer(command, path, window_size=window_size, deadline=deadline) as client:
        shots: list[bytes] = []
        while not settled(shots):
            if time.monotonic() > deadline:
                what = "the recording was still loading" if not shots else "it kept changing"
                raise CaptureError(f"the viewer had not settled after {timeout:g} s ({what})")
            try:
                ready = at_step(client.get_state(), step)
                shots = [*shots, client.take_screenshot()] if ready else []
            except (ConnectionError, RuntimeError, TimeoutError) as error:
                raise CaptureError(f"the viewer stopped answering ({error})") from error
            if not settled(shots):
                time.sleep(POLL_S)
        return shots[-1]
