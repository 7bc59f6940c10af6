"""One episode buffered per control step and sent as columns at its end (``send_columns``)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
import rerun as rr

from tolins.geometry.specs import SocketSpec
from tolins.record.arm import ArmDrawing, log_arm, log_handle
from tolins.record.geometry import pin_geometry
from tolins.record.layout import (
    FORCE_SCALE,
    SIM_TIME,
    STEP,
    WRIST_FORCE_COLOR,
    arm_path,
    force_path,
    handle_path,
    plugs_path,
    series_path,
    workpiece_path,
    wrist_force_path,
)
from tolins.record.metadata import spec_to_dict
from tolins.record.scene import BENT_COLOR, PIN_COLOR, bent_pin_strips, log_workpiece


@lru_cache(maxsize=64)
def _spec_json(spec: SocketSpec) -> str:
    return json.dumps(spec_to_dict(spec))


@dataclass
class EpisodeBuffer:
    """What the env reported at the reset (row 0) and after each control step: a
    collector (:class:`tolins.rollouts.collectors.Collector`) that keeps nothing in the
    episode's record; :func:`send_episode` logs it.

    ``metadata`` holds the env id, policy name, seed and the episode's socket spec.
    """

    index: int
    control_dt: float
    metadata: dict[str, Any]
    #: The env's collision threshold (N), drawn beside the peak force.
    collision_force: float = float("nan")
    steps: list[int] = field(default_factory=list)
    poses: list[np.ndarray] = field(default_factory=list)
    wrenches: list[np.ndarray] = field(default_factory=list)
    rewards: list[float] = field(default_factory=list)
    collisions: list[bool] = field(default_factory=list)
    successes: list[bool] = field(default_factory=list)
    peak_forces: list[float] = field(default_factory=list)
    events: list[tuple[int, str, str]] = field(default_factory=list)
    #: A robot's drawing, its links' poses ``(links, 7)`` and its flange's position per
    #: row (:meth:`add_arm`), and the wrist sensor's wrench per row (from ``info``).
    arm: ArmDrawing | None = None
    arm_poses: list[np.ndarray] = field(default_factory=list)
    flange_positions: list[np.ndarray] = field(default_factory=list)
    sensed_wrenches: list[np.ndarray] = field(default_factory=list)
    #: Pins that bend (docs/delicate.md): each pin's tip offset, elastic included, and its
    #: permanent one per row ``(n_pins, 2)`` (mm), from ``info``.
    pin_deflections: list[np.ndarray] = field(default_factory=list)
    pin_bends: list[np.ndarray] = field(default_factory=list)

    def on_reset(self, observation: np.ndarray, info: Mapping[str, Any]) -> None:
        """Row 0: the state after ``reset``."""
        self._add_state(info)
        pose = ", ".join(f"{v:.4g}" for v in info["pose"])
        self.events.append((info["step"], "INFO", f"start: pose [{pose}], seed {self.seed}"))

    def on_step(
        self,
        observation: np.ndarray,
        action: np.ndarray,
        reward: float,
        terminated: bool,
        truncated: bool,
        info: Mapping[str, Any],
    ) -> None:
        """One control step's outcome, as ``env.step`` returned it."""
        step = int(info["step"])
        self._add_state(info)
        self.rewards.append(float(reward))
        self.collisions.append(bool(info["collision"]))
        self.successes.append(bool(info["success"]))
        self.peak_forces.append(float(info["peak_force"]))
        if info["collision"]:
            self.events.append((step, "WARN", f"collision: peak {info['peak_force']:.3g} N"))
        if "error" in info:
            self.events.append((step, "ERROR", f"simulator fault: {info['error']}"))
        if len(self.pin_bends) > 1:
            self._bend_events(step, info)
        if terminated or truncated:
            outcome = "success" if info["success"] else "truncated without success"
            self.events.append(
                (
                    step,
                    "INFO" if info["success"] else "WARN",
                    f"{outcome} at step {step}: return {sum(self.rewards):.4g}, "
                    f"{info['n_collisions']} collision steps",
                )
            )

    def result(self) -> dict[str, Any]:
        """Nothing for the episode's record: the buffer is sent to rerun."""
        return {}

    def _bend_events(self, step: int, info: Mapping[str, Any]) -> None:
        """The step's events of pins that bend: which yielded (their permanent offset grew)
        and, on the step it happened, the part's damage."""
        before, now = self.pin_bends[-2], self.pin_bends[-1]
        grew = np.flatnonzero(np.any(now != before, axis=1))
        if grew.size:
            offsets = np.hypot(now[grew, 0], now[grew, 1]) * 1e3
            pins = ", ".join(f"pin {i} {um:.1f} µm" for i, um in zip(grew, offsets, strict=True))
            self.events.append((step, "WARN", f"yielded: permanent tip offsets {pins}"))
        if info.get("damaged_at") == step:
            worst = float(np.max(np.hypot(now[:, 0], now[:, 1])))
            self.events.append((step, "ERROR", f"part damaged: a pin bent {worst:.3f} mm for good"))

    @property
    def seed(self) -> int | None:
        return self.metadata.get("seed")

    def add_arm(self, data: Any) -> None:
        """The robot's links and flange in ``data`` (a ``MjData``) for the row just added."""
        self.arm_poses.append(self.arm.poses(data))
        self.flange_positions.append(self.arm.flange_position(data))

    def _add_state(self, info: Mapping[str, Any]) -> None:
        self.steps.append(int(info["step"]))
        self.poses.append(np.array(info["pose"], dtype=float))
        self.wrenches.append(np.array(info["wrench"], dtype=float))
        if "sensed_wrench" in info:
            self.sensed_wrenches.append(np.array(info["sensed_wrench"], dtype=float))
        if "pin_deflection" in info:
            self.pin_deflections.append(np.array(info["pin_deflection"], dtype=float))
            self.pin_bends.append(np.array(info["pin_bend"], dtype=float))


def _indexes(steps: np.ndarray, control_dt: float) -> list[rr.TimeColumn]:
    return [
        rr.TimeColumn(STEP, sequence=steps),
        rr.TimeColumn(SIM_TIME, duration=steps * control_dt),
    ]


def _quaternions(theta: np.ndarray) -> np.ndarray:
    """Rotations about z as ``xyzw`` quaternions ``(n, 4)``."""
    zeros = np.zeros_like(theta)
    return np.column_stack([zeros, zeros, np.sin(theta / 2), np.cos(theta / 2)])


def send_episode(stream: rr.RecordingStream, episode: EpisodeBuffer) -> None:
    """Log ``episode``: its static parts, then every buffered column in one call each."""
    k = episode.index
    if not episode.steps:
        raise ValueError(f"episode {k} has no rows; allowed: a buffer started by on_reset()")
    spec = episode.metadata["spec"]
    bending = len(episode.pin_deflections) == len(episode.steps)
    log_workpiece(stream, workpiece_path(k), spec, plugs=plugs_path(k), pins=not bending)
    meta = {key: v for key, v in episode.metadata.items() if key != "spec" and v is not None}
    stream.log(
        series_path("metadata", k),
        rr.AnyValues(**meta, spec=_spec_json(spec)),
        static=True,
    )

    steps = np.array(episode.steps, dtype=np.int64)
    poses = np.array(episode.poses)
    wrenches = np.array(episode.wrenches)
    n = len(steps)
    rows = _indexes(steps, episode.control_dt)
    position = poses[:, [0, 1, 3]]
    stream.send_columns(
        workpiece_path(k),
        indexes=rows,
        columns=rr.Transform3D.columns(translation=position, quaternion=_quaternions(poses[:, 2])),
    )
    stream.send_columns(
        force_path(k),
        indexes=rows,
        columns=rr.Arrows3D.columns(
            origins=position,
            vectors=wrenches[:, [0, 1, 3]] * FORCE_SCALE,
        ),
    )
    if episode.arm is not None and episode.arm_poses:
        _send_arm(stream, episode, rows)
    if bending:
        _send_bent_pins(stream, episode, rows)
    for name, values in (("pose", poses), ("wrench", wrenches)):
        stream.send_columns(
            series_path(name, k),
            indexes=rows,
            columns=rr.Scalars.columns(scalars=values.ravel()).partition(np.full(n, 4)),
        )
    if n > 1:
        outcome = np.column_stack([episode.rewards, episode.collisions, episode.successes])
        stream.send_columns(
            series_path("outcome", k),
            indexes=_indexes(steps[1:], episode.control_dt),
            columns=rr.Scalars.columns(scalars=outcome.ravel()).partition(np.full(n - 1, 3)),
        )
        threshold = np.full(n - 1, episode.collision_force)
        contact = np.column_stack([episode.peak_forces, threshold])
        stream.send_columns(
            series_path("contact", k),
            indexes=_indexes(steps[1:], episode.control_dt),
            columns=rr.Scalars.columns(scalars=contact.ravel()).partition(np.full(n - 1, 2)),
        )
    ev_steps, levels, texts = zip(*episode.events, strict=True)
    stream.send_columns(
        series_path("events", k),
        indexes=_indexes(np.array(ev_steps, dtype=np.int64), episode.control_dt),
        columns=rr.TextLog.columns(text=list(texts), level=list(levels)),
    )


def _send_bent_pins(stream: rr.RecordingStream, episode: EpisodeBuffer, rows: list) -> None:
    """Pins that bend, drawn as they are after every row (:func:`~tolins.record.scene.
    bent_pin_strips`), a pin bent for good in :data:`~tolins.record.scene.BENT_COLOR`."""
    spec = episode.metadata["spec"]
    strips = bent_pin_strips(spec, np.array(episode.pin_deflections))
    rows_n, n_pins = strips.shape[:2]
    bent = np.any(np.array(episode.pin_bends) != 0.0, axis=2).ravel()
    colors = np.where(bent[:, None], BENT_COLOR, PIN_COLOR).astype(np.uint8)
    radii = np.tile(pin_geometry(spec).cylinders[1], rows_n)
    stream.send_columns(
        f"{workpiece_path(episode.index)}/pins",
        indexes=rows,
        columns=rr.LineStrips3D.columns(
            strips=list(strips.reshape(-1, 2, 3)), radii=radii, colors=colors
        ).partition(np.full(rows_n, n_pins)),
    )


def _send_arm(stream: rr.RecordingStream, episode: EpisodeBuffer, rows: list) -> None:
    """The robot of ``episode``: its meshes, the handle on the workpiece, its links' poses
    and the wrist's force (an arrow at the flange every row and the series
    ``sensed_wrench``) as columns."""
    k, drawing = episode.index, episode.arm
    root = arm_path(k)
    log_arm(stream, root, drawing)
    log_handle(stream, handle_path(k), drawing)
    poses = np.stack(episode.arm_poses)  # (rows, links, 7)
    for j, link in enumerate(drawing.links):
        stream.send_columns(
            f"{root}/{link}",
            indexes=rows,
            columns=rr.Transform3D.columns(translation=poses[:, j, :3], quaternion=poses[:, j, 3:]),
        )
    if len(episode.sensed_wrenches) == len(poses):
        sensed = np.array(episode.sensed_wrenches)
        stream.log(
            wrist_force_path(k), rr.Arrows3D.from_fields(colors=WRIST_FORCE_COLOR), static=True
        )
        stream.send_columns(
            wrist_force_path(k),
            indexes=rows,
            columns=rr.Arrows3D.columns(
                origins=np.array(episode.flange_positions),
                vectors=sensed[:, [0, 1, 3]] * FORCE_SCALE,
            ),
        )
        stream.send_columns(
            series_path("sensed_wrench", k),
            indexes=rows,
            columns=rr.Scalars.columns(scalars=sensed.ravel()).partition(np.full(len(sensed), 4)),
        )
