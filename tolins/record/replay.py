"""Replay a recording: check the file, then hand it to the viewer that ships with rerun-sdk.

Three ways: the native viewer, the web viewer served on 127.0.0.1, or a headless
screenshot (software Vulkan: Debian's ``mesa-vulkan-drivers``, see ``scripts/setup.sh``),
taken once the recording has streamed in (:mod:`tolins.record.capture`).
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path
from urllib.parse import quote

import numpy as np
from rerun.chunk import RrdReader

from tolins.record.capture import LOOPBACK, CaptureError, base_args, capture
from tolins.record.layout import STEP
from tolins.record.snapshot import cut_recording
from tolins.record.stale import remove_dead_temporaries

#: Screenshot size in logical points.
WINDOW_SIZE = "1280x800"
SCREENSHOT_TIMEOUT_S = 180.0


class RrdError(ValueError):
    """A file that is missing or is not a readable rerun recording."""


def check_rrd(path: str | os.PathLike[str]) -> int:
    """Decode every chunk of ``path``; return the number of chunks.

    Raises:
        RrdError: one line naming the file and what is wrong with it.
    """
    path = Path(path)
    if not path.exists():
        raise RrdError(f"{path}: no such file")
    if not path.is_file():
        raise RrdError(f"{path}: not a file")
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            reader = RrdReader(path)
            if not reader.recordings():
                raise RrdError(f"{path}: holds no recording")
            chunks = sum(1 for _ in reader.stream())
    except RrdError:
        raise
    except (RuntimeError, ValueError, OSError) as error:
        detail = str(error).splitlines()[0] if str(error) else type(error).__name__
        detail = detail.split(f"{path}: ", 1)[-1]
        raise RrdError(f"{path}: not a readable .rrd recording ({detail})") from error
    if any("no footer" in str(w.message) for w in caught):
        raise RrdError(f"{path}: incomplete .rrd recording (no footer: truncated or still open)")
    return chunks


def rerun_command() -> list[str]:
    """The ``rerun`` executable beside this Python, else ``python -m rerun_cli``."""
    beside = Path(sys.executable).with_name("rerun")
    if beside.is_file():
        return [str(beside)]
    return [sys.executable, "-m", "rerun_cli"]


def web_address(web_port: int, grpc_port: int) -> str:
    """The address of the web viewer showing the recording served on ``grpc_port``."""
    proxy = quote(f"rerun+http://{LOOPBACK}:{grpc_port}/proxy", safe="")
    return f"http://{LOOPBACK}:{web_port}/?url={proxy}"


def viewer_args(
    path: Path,
    *,
    web: bool = False,
    web_port: int = 9090,
    grpc_port: int = 9876,
) -> list[str]:
    """Arguments of ``rerun`` that show ``path`` in the native or (``web``) the web viewer;
    a screenshot's are :func:`tolins.record.capture.headless_args`."""
    args = base_args(path)
    if web:
        return [*args, "--web-viewer", "--web-viewer-port", str(web_port), "--port", str(grpc_port)]
    return [*args, "--port", "auto"]


def _temporary_beside(path: Path) -> Path:
    return path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")


def take_screenshot(
    path: Path,
    out: Path,
    *,
    step: int | None = None,
    time: float | None = None,
    timeout: float = SCREENSHOT_TIMEOUT_S,
) -> int:
    """Render ``path`` headless to the PNG ``out`` (written atomically) as it stands at
    control step ``step`` or simulated time ``time`` (s), by default at its last step;
    returns the step shown. The viewer renders a copy cut there
    (:func:`tolins.record.snapshot.cut_recording`: the viewer itself cannot be told a time),
    and the PNG is taken once all of it is drawn (:func:`tolins.record.capture.capture`).

    Raises:
        RuntimeError: the viewer could not render (e.g. no Vulkan driver), did not finish
            drawing the recording within ``timeout`` seconds, or drew a blank picture.
    """
    if out.suffix.lower() != ".png":
        raise ValueError(f"screenshot={str(out)!r}; allowed: a path ending in .png")
    if not out.parent.is_dir():
        raise ValueError(f"screenshot={str(out)!r}: folder {out.parent} does not exist")
    remove_dead_temporaries(out)
    tmp = _temporary_beside(out)
    cut = out.with_name(f".{out.stem}.{os.getpid()}.cut.rrd")
    try:
        shown = cut_recording(path, cut, step=step, time=time)
        has_steps = _has_steps(cut)
        try:
            png = capture(
                rerun_command(),
                cut,
                step=shown if has_steps else None,
                timeout=timeout,
                window_size=WINDOW_SIZE,
            )
        except CaptureError as error:
            raise RuntimeError(f"{path}: headless rendering failed: {error}") from error
        tmp.write_bytes(png)
        if _blank(tmp):
            raise RuntimeError(f"{path}: headless rendering drew a blank picture")
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
        cut.unlink(missing_ok=True)
    return shown


def _has_steps(path: Path) -> bool:
    """Whether the recording ``path`` has tolins's ``step`` timeline."""
    return any(STEP in chunk.timeline_names for chunk in RrdReader(path).stream())


def _blank(png: Path) -> bool:
    """Whether the middle of the screenshot ``png`` is one flat colour (nothing drawn)."""
    from PIL import Image

    image = np.asarray(Image.open(png).convert("L"), dtype=float)
    height, width = image.shape
    return float(image[height // 4 : 3 * height // 4, width // 4 : 3 * width // 4].std()) < 1.0


def _has_display() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def replay(
    path: str | os.PathLike[str],
    *,
    web: bool = False,
    screenshot: str | os.PathLike[str] | None = None,
    web_port: int = 9090,
    grpc_port: int = 9876,
    step: int | None = None,
    time: float | None = None,
) -> int:
    """Check ``path`` and show it; returns the viewer's exit status.

    The native viewer and the web server run until closed (Ctrl-C); a screenshot returns
    once the PNG is written, showing control step ``step`` or simulated time ``time`` (s)
    (default: the last step).
    """
    path = Path(path)
    check_rrd(path)
    if screenshot is not None:
        take_screenshot(path, Path(screenshot), step=step, time=time)
        return 0
    if step is not None or time is not None:
        raise ValueError("step/time pick what a screenshot shows; allowed: with a screenshot")
    if web:
        print(f"web viewer: {web_address(web_port, grpc_port)}  (Ctrl-C to stop)", flush=True)
    elif sys.platform.startswith("linux") and not _has_display():
        raise RuntimeError(
            f"{path}: no display for the native viewer (DISPLAY and WAYLAND_DISPLAY are "
            "unset); use --web or --screenshot OUT.png"
        )
    args = viewer_args(path, web=web, web_port=web_port, grpc_port=grpc_port)
    try:
        return subprocess.call([*rerun_command(), *args])
    except KeyboardInterrupt:
        return 130
