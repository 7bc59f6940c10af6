"""A recording cut at one step (what `tolins replay --screenshot --step` renders)."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from rerun.blueprint.components import PanelState, PlayState
from rerun.chunk import RrdReader
from rrd_tables import read_tables

import tolins  # noqa: F401  (registers the env ids)
from tolins.cli import main
from tolins.policies.experts import SafeExpert
from tolins.record import check_rrd, record_episodes
from tolins.record.snapshot import cut_recording


def _vulkan_driver() -> bool:
    folders = [Path("/usr/share/vulkan/icd.d"), Path("/etc/vulkan/icd.d")]
    return any(f.is_dir() and any(f.glob("*.json")) for f in folders)


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rrd") / "circle.rrd"
    env = gym.make("tolins/Circle2x2-v1", backend="kinematic")
    record_episodes(env, SafeExpert(), 2, path, seed=0)
    return path


def _temporal(tables: dict) -> dict:
    return {k: v for k, v in tables.items() if k.endswith("#temporal")}


def test_a_cut_keeps_every_row_up_to_the_step_and_nothing_after(recording, tmp_path) -> None:
    whole = read_tables(recording)
    assert cut_recording(recording, tmp_path / "k.rrd", step=10) == 10
    assert check_rrd(tmp_path / "k.rrd") > 0
    cut = read_tables(tmp_path / "k.rrd")
    assert _temporal(cut).keys() == _temporal(whole).keys()
    for entity, table in _temporal(whole).items():
        keep = [i for i, step in enumerate(table["step"]) if step <= 10]
        for column, values in cut[entity].items():
            if column != "rerun.controls.RowId":
                assert values == [table[column][i] for i in keep], (entity, column)
    static = {k: v for k, v in whole.items() if k.endswith("#static")}
    assert {k: cut[k] for k in static} == static  # board, pins, metadata, properties


def test_a_cut_by_time_and_the_default_cut(recording, tmp_path) -> None:
    assert cut_recording(recording, tmp_path / "t.rrd", time=2.6) == 10  # 0.25 s per step
    last = max(max(t["step"]) for t in _temporal(read_tables(recording)).values())
    assert cut_recording(recording, tmp_path / "all.rrd") == last
    assert read_tables(tmp_path / "all.rrd").keys() == read_tables(recording).keys()


def test_the_cut_opens_following_its_last_step_without_the_top_bar(recording, tmp_path) -> None:
    cut_recording(recording, tmp_path / "k.rrd", step=5)
    reader = RrdReader(tmp_path / "k.rrd")
    (blueprint,) = reader.blueprints()
    states = [
        state
        for chunk in reader.stream(store=blueprint)
        if chunk.entity_path == "/time_panel"
        for state in chunk.to_record_batch().to_pydict().get("TimePanelBlueprint:play_state", [])
    ]
    assert states == [[PlayState.Following.value]]
    top = [
        state
        for chunk in reader.stream(store=blueprint)
        if chunk.entity_path == "/top_panel"
        for state in chunk.to_record_batch().to_pydict()["PanelBlueprint:state"]
    ]
    assert top == [[PanelState.Hidden.value]]  # no menu, badges or window buttons in a figure


def test_steps_outside_the_recording_are_refused(recording, tmp_path) -> None:
    last = max(max(t["step"]) for t in _temporal(read_tables(recording)).values())
    with pytest.raises(ValueError, match=rf"allowed: 0 … {last}"):
        cut_recording(recording, tmp_path / "x.rrd", step=last + 1)
    with pytest.raises(ValueError, match="allowed: ≥ 0"):
        cut_recording(recording, tmp_path / "x.rrd", step=-1)
    with pytest.raises(ValueError, match="at most one"):
        cut_recording(recording, tmp_path / "x.rrd", step=1, time=1.0)


@pytest.mark.slow
@pytest.mark.skipif(not _vulkan_driver(), reason="no Vulkan driver for the headless viewer")
def test_screenshots_show_the_chosen_step_fully_drawn_without_toasts(recording, tmp_path) -> None:
    from PIL import Image

    def shot(name: str, *args: str) -> np.ndarray:
        path = tmp_path / f"{name}.png"
        assert main(["replay", str(recording), "--screenshot", str(path), *args]) == 0
        return np.asarray(Image.open(path).convert("RGB")).astype(int)

    def scene(image: np.ndarray) -> np.ndarray:
        height, width, _ = image.shape
        return image[height // 10 : height * 3 // 4, : width * 3 // 5]  # the 3-D view

    def changed(a: np.ndarray, b: np.ndarray) -> float:
        return float((np.abs(a - b).max(axis=2) > 30).mean())  # share of pixels changed

    # One try each: the screenshot waits until the viewer has drawn the whole recording,
    # so a shot taken while the poses or the plots were still streaming in cannot pass.
    early, late, by_time = shot("early", "--step", "2"), shot("late"), shot("time", "--time", "0.5")
    assert changed(scene(early), scene(late)) > 0.02  # the workpiece has moved (measured: 0.037)
    assert changed(early, by_time) == 0.0  # 0.5 s is step 2, and the same picture each time
    assert np.array_equal(late, shot("again"))  # a settled picture is the same every time
    height, width, _ = late.shape
    for image in (early, late):
        plots = image[height // 20 : height * 3 // 5, width * 5 // 8 :]
        coloured = (plots.max(axis=2) - plots.min(axis=2)) > 60  # the series and legends
        assert coloured.mean() > 0.005, "the plots are empty (still loading)"
        corner = image[height // 20 : height * 7 // 20, width * 3 // 4 :]
        toast = (np.abs(corner - 33) <= 1).all(axis=2)  # a toast's grey box
        assert toast.mean() < 0.05, f"a toast covers {toast.mean():.0%} of the top right"
    assert not list(tmp_path.glob(".*"))  # no cut copy or temporary left


def test_a_recording_without_steps_is_copied_whole_and_refuses_a_step(tmp_path) -> None:
    import rerun as rr

    path = tmp_path / "other.rrd"
    stream = rr.RecordingStream("other")
    stream.save(path)
    stream.log("points", rr.Points3D([[0.0, 0.0, 0.0]]), static=True)
    stream.flush()
    stream.disconnect()
    assert cut_recording(path, tmp_path / "copy.rrd") == 0
    assert check_rrd(tmp_path / "copy.rrd") > 0
    with pytest.raises(ValueError, match="no 'step' timeline"):
        cut_recording(path, tmp_path / "x.rrd", step=0)
