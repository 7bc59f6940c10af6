"""Waiting for the headless viewer, and failing loudly when it does not settle."""

from __future__ import annotations

import importlib
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import gymnasium as gym
import pytest

import tolins  # noqa: F401  (registers the env ids)
from tolins.cli import main
from tolins.policies.experts import SafeExpert
from tolins.record import record_episodes
from tolins.record.capture import (
    CaptureError,
    at_step,
    capture,
    headless_args,
    settled,
    viewer_environment,
)


def _state(*, loading=(), recordings=None) -> SimpleNamespace:
    if recordings is None:
        recordings = [SimpleNamespace(current_timeline="step", current_time=7)]
    return SimpleNamespace(loading=list(loading), recordings=recordings)


def test_a_picture_is_final_after_identical_shots_in_a_row() -> None:
    assert not settled([])
    assert not settled([b"a", b"a"], count=3)
    assert not settled([b"a", b"a", b"b"], count=3)
    assert settled([b"b", b"a", b"a", b"a"], count=3)


def test_the_viewer_is_ready_once_loaded_and_at_the_step() -> None:
    assert at_step(_state(), 7)
    assert at_step(_state(), None)
    assert not at_step(_state(), 6)  # the cursor has not reached the step yet
    assert not at_step(_state(loading=["file"]), 7)  # still loading
    assert not at_step(_state(recordings=[]), None)  # nothing open yet
    other = [SimpleNamespace(current_timeline="sim_time", current_time=7)]
    assert not at_step(_state(recordings=other), 7)


def test_the_viewer_logs_only_errors_so_no_toast_covers_the_picture(tmp_path: Path) -> None:
    assert viewer_environment({"RUST_LOG": "info", "HOME": "/h"}) == {
        "RUST_LOG": "error",
        "HOME": "/h",
    }
    args = headless_args(tmp_path / "x.rrd", 1234, "640x480")
    assert args[0] == str(tmp_path / "x.rrd")
    assert "--headless" in args and "--screenshot-to" not in args
    assert args[args.index("--port") + 1] == "1234" and "127.0.0.1" in args


def test_a_viewer_that_fails_is_reported_with_its_error(tmp_path: Path) -> None:
    failing = [sys.executable, "-c", "import sys; print('error: no adapter'); sys.exit(3)"]
    with pytest.raises(CaptureError, match=r"no adapter.*Vulkan driver"):
        capture(failing, tmp_path / "x.rrd", step=None, timeout=30, window_size="64x64")


def test_a_viewer_that_never_answers_times_out_and_is_stopped(tmp_path: Path) -> None:
    pid = tmp_path / "pid"
    silent = [
        sys.executable,
        "-c",
        f"import os, time; open({str(pid)!r}, 'w').write(str(os.getpid())); time.sleep(60)",
    ]
    start = time.monotonic()
    with pytest.raises(CaptureError, match="did not answer"):
        capture(silent, tmp_path / "x.rrd", step=None, timeout=1.0, window_size="64x64")
    assert time.monotonic() - start < 15
    assert not Path(f"/proc/{pid.read_text()}").exists()  # stopped, not left running


def test_replay_fails_loudly_when_the_viewer_does_not_settle(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    recording = tmp_path / "circle.rrd"
    record_episodes(
        gym.make("tolins/Circle2x2-v1", backend="kinematic"), SafeExpert(), 1, recording, seed=0
    )

    def unsettled(*_, **__) -> bytes:
        raise CaptureError("the viewer had not settled after 180 s (it kept changing)")

    # the module, not the function that tolins.record exports under the same name
    replay_module = importlib.import_module("tolins.record.replay")
    monkeypatch.setattr(replay_module, "capture", unsettled)
    shot = tmp_path / "shot.png"
    assert main(["replay", str(recording), "--screenshot", str(shot)]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "had not settled" in err and str(recording) in err
    assert not shot.exists() and not list(tmp_path.glob(".*"))  # no PNG, no temporary
