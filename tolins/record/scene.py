"""Log the static geometry: the board once per file, the workpiece once per episode."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import rerun as rr

from tolins.geometry.specs import SocketSpec
from tolins.record.geometry import (
    TriangleMesh,
    board_geometry,
    carrier_box,
    flat_shaded,
    pin_geometry,
    plug_boxes,
)
from tolins.record.layout import BOARD, WORLD

BOARD_COLOR = (64, 115, 77)
HOLE_COLOR = (20, 30, 25)
PIN_COLOR = (217, 179, 77)
#: A burred (oversized) pin, a short pin, and the plug of a blocked hole.
BURR_COLOR = (220, 60, 50)
SHORT_COLOR = (70, 130, 220)
PLUG_COLOR = (200, 60, 160)
#: A pin bent for good (pins that bend, docs/delicate.md).
BENT_COLOR = (230, 110, 30)
CARRIER_COLOR = (153, 153, 166, 110)


def shaded_mesh(mesh: TriangleMesh, color: tuple[int, ...]) -> rr.Mesh3D:
    """``mesh`` as a flat-shaded ``Mesh3D`` of one colour."""
    vertices, triangles, normals = flat_shaded(mesh)
    return rr.Mesh3D(
        vertex_positions=vertices,
        triangle_indices=triangles,
        vertex_normals=normals,
        albedo_factor=color,
    )


def log_board(stream: rr.RecordingStream, spec: SocketSpec) -> None:
    """The world frame (z up, mm) and ``spec``'s board, static."""
    board = board_geometry(spec)
    stream.log(WORLD, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    stream.log(f"{BOARD}/walls", shaded_mesh(board.walls, BOARD_COLOR), static=True)
    stream.log(
        f"{BOARD}/boxes",
        rr.Boxes3D(
            centers=board.boxes.centers,
            half_sizes=board.boxes.half_sizes,
            colors=BOARD_COLOR,
            fill_mode="solid",
        ),
        static=True,
    )
    stream.log(
        f"{BOARD}/holes",
        rr.LineStrips3D(board.hole_outlines, colors=HOLE_COLOR, radii=0.01),
        static=True,
    )


def bent_pin_strips(spec: SocketSpec, deflections: np.ndarray) -> np.ndarray:
    """Round pins that bend as line strips ``(rows, n_pins, 2, 3)`` from root to tip, in the
    workpiece frame: each pin turned about its root (the carrier's underside) so that its
    tip is offset by ``deflections`` ``(rows, n_pins, 2)`` (mm), its length kept."""
    centers, _, lengths = pin_geometry(spec).cylinders
    offsets = np.asarray(deflections, dtype=float)
    root_z = centers[:, 2] + lengths / 2
    reach = np.minimum(np.hypot(offsets[..., 0], offsets[..., 1]), lengths)
    strips = np.empty((*offsets.shape[:2], 2, 3))
    strips[:, :, 0, :2] = centers[:, :2]
    strips[:, :, 0, 2] = root_z
    strips[:, :, 1, :2] = centers[:, :2] + offsets
    strips[:, :, 1, 2] = root_z - np.sqrt(lengths**2 - reach**2)
    return strips


@lru_cache(maxsize=64)
def workpiece_archetypes(spec: SocketSpec) -> tuple[rr.AsComponents, rr.AsComponents]:
    """The pins and the carrier of ``spec`` (built once per spec: episodes share them)."""
    pins = pin_geometry(spec)
    if pins.cylinders is not None:
        centers, radii, lengths = pins.cylinders
        colors = np.tile(PIN_COLOR, (len(centers), 1))
        colors[pins.short] = SHORT_COLOR
        colors[pins.burred] = BURR_COLOR
        archetype = rr.Cylinders3D(
            centers=centers,
            lengths=lengths,
            radii=radii,
            colors=colors.astype(np.uint8),
            fill_mode="solid",
        )
    elif pins.box is not None:
        archetype = rr.Boxes3D(
            centers=pins.box.centers,
            half_sizes=pins.box.half_sizes,
            colors=PIN_COLOR,
            fill_mode="solid",
        )
    else:
        archetype = shaded_mesh(pins.mesh, PIN_COLOR)
    carrier = carrier_box(spec)
    carrier_archetype = rr.Boxes3D(
        centers=carrier.centers,
        half_sizes=carrier.half_sizes,
        colors=CARRIER_COLOR,
        fill_mode="solid",
    )
    return archetype, carrier_archetype


def log_workpiece(
    stream: rr.RecordingStream,
    path: str,
    spec: SocketSpec,
    plugs: str | None = None,
    pins: bool = True,
) -> None:
    """``spec``'s pins and carrier under the workpiece entity ``path``, static; with
    ``plugs`` (a world-frame entity), the plugs of its blocked holes there. ``pins=False``:
    the carrier only (pins that bend are drawn step by step: :func:`bent_pin_strips`)."""
    straight, carrier = workpiece_archetypes(spec)
    if pins:
        stream.log(f"{path}/pins", straight, static=True)
    stream.log(f"{path}/carrier", carrier, static=True)
    boxes = plug_boxes(spec)
    if plugs is not None and boxes is not None:
        stream.log(
            plugs,
            rr.Boxes3D(
                centers=boxes.centers,
                half_sizes=boxes.half_sizes,
                colors=PLUG_COLOR,
                fill_mode="solid",
            ),
            static=True,
        )
