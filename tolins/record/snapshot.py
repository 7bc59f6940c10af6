"""A copy of a recording cut at one step, so that a screenshot shows that step.

rerun 0.41's viewer has no option to open at a given time, and a blueprint's time panel
sets the timeline and the play state but not the time; from a file it plays from step 0,
so a plain screenshot catches whatever step playback had reached. The copy therefore
ends at the chosen step and its blueprint follows the latest data: the viewer shows the
last step kept, and the plots up to it. Its blueprint also hides the viewer's top bar (the
menu, the search field, the window's buttons and the renderer's badges), which a figure
does not need.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import rerun as rr
import rerun.blueprint as rrb
from rerun.chunk import Chunk, RrdReader

from tolins.mjcf.model import scene_extent
from tolins.record.layout import STEP, default_blueprint
from tolins.record.metadata import spec_from_dict

SIM_TIME = "sim_time"


def cut_recording(
    source: str | os.PathLike[str],
    target: str | os.PathLike[str],
    *,
    step: int | None = None,
    time: float | None = None,
) -> int:
    """Write ``source``'s data up to control step ``step`` (or simulated time ``time``, s;
    neither: all of it) to ``target``, with tolins's layout following the latest data.
    Returns the last step kept.

    Raises ``ValueError`` when ``step``/``time`` is negative or past the recording's end,
    or given for a recording without tolins's ``step`` timeline.
    """
    if step is not None and time is not None:
        raise ValueError("step and time are both set; allowed: at most one")
    if (step is not None and step < 0) or (time is not None and not 0 <= time < math.inf):
        raise ValueError(f"step={step}, time={time}; allowed: ≥ 0 (a time: finite)")
    reader = RrdReader(source)
    (entry,) = reader.recordings()
    last = {"kept": -1, "all": -1, "time_ns": -1}

    def cut(chunk: Chunk) -> list[Chunk]:
        if STEP not in chunk.timeline_names:
            return [chunk]
        batch = chunk.to_record_batch()
        steps = batch.column(STEP)
        last["all"] = max(last["all"], pc.max(steps).as_py())
        if step is not None:
            keep = pc.less_equal(steps, step)
        elif time is not None:
            times = batch.column(SIM_TIME).cast(pa.int64())
            last["time_ns"] = max(last["time_ns"], pc.max(times).as_py())
            limit = pa.scalar(round(min(time, 4e9) * 1e9), type=pa.duration("ns"))
            keep = pc.less_equal(batch.column(SIM_TIME), limit)
        else:
            keep = pc.greater_equal(steps, 0)
        kept = batch.filter(keep)
        if kept.num_rows == 0:
            return []
        last["kept"] = max(last["kept"], pc.max(kept.column(STEP)).as_py())
        return Chunk.from_record_batch(kept)

    chunks = reader.stream().flat_map(cut).to_chunks()
    if last["all"] < 0 and (step is not None or time is not None):
        raise ValueError(f"{source}: no {STEP!r} timeline; allowed: a recording made by tolins")
    if step is not None and step > last["all"]:
        raise ValueError(f"{source}: step {step} is past its last step; allowed: 0 … {last['all']}")
    if time is not None and time * 1e9 > last["time_ns"]:
        end = last["time_ns"] / 1e9
        raise ValueError(f"{source}: time {time:g} s is past its end; allowed: 0 … {end:g} s")
    stream = rr.RecordingStream(
        entry.application_id, recording_id=entry.recording_id, send_properties=False
    )
    stream.save(Path(target), default_blueprint=_figure_blueprint(*_scene(chunks)))
    stream.send_chunks(chunks)
    stream.flush()
    stream.disconnect()
    return max(last["kept"], 0)


def _figure_blueprint(extent: float | None, robot: bool = False) -> rrb.Blueprint:
    """tolins's layout following the latest data, without the viewer's top bar."""
    blueprint = default_blueprint(extent, follow=True, robot=robot)
    blueprint.top_panel = rrb.TopPanel(state="hidden")
    return blueprint


def _first(values: list | None) -> object:
    value = (values or [None])[0]
    return value[0] if isinstance(value, list) and value else value


def _scene(chunks: list[Chunk]) -> tuple[float | None, bool]:
    """The scene extent of the nominal spec in the recording's ``tolins`` properties, and
    whether a robot holds the part."""
    for chunk in chunks:
        if chunk.entity_path == "/__properties/tolins":
            columns = chunk.to_record_batch().to_pydict()
            robot = _first(columns.get("robot")) not in (None, "free")
            try:
                return scene_extent(spec_from_dict(json.loads(_first(columns.get("spec"))))), robot
            except (TypeError, ValueError):
                return None, robot
    return None, False
