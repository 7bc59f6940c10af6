"""Where things live in a tolins recording: entity paths, timelines and the default layout.

Static (logged once per file): ``/world`` (z up, mm) and the board under
``/world/board/{walls,boxes,holes}``. Per episode ``k`` (``episode_{k:03d}``), so that
several episodes in one file stay separable:

=================================  ==========================================
``/world/{ep}/workpiece``          pose per step (``Transform3D``); pins and
                                   carrier below it, static, in its frame
``/world/{ep}/force``              contact force on the workpiece (arrow)
``/pose/{ep}``                     ``[x, y, theta, z]`` (mm, rad), float64
``/wrench/{ep}``                   ``[Fx, Fy, q_theta, Fz]`` (N, N·mm)
``/outcome/{ep}``                  ``[reward, collision, success]`` per step
                                   (steps ≥ 1; collision and success 0 or 1)
``/contact/{ep}``                  ``[peak force, collision force]`` per step
                                   (N, steps ≥ 1: the force timeline against the
                                   threshold of a collision)
``/events/{ep}``                   start, collision, success, end (text log)
``/metadata/{ep}``                 env id, spec, seed, policy (static)
=================================  ==========================================

When a robot holds the part (:mod:`tolins.record.arm`), in the same world frame and units:

=================================  ==========================================
``/world/{ep}/arm/{link}``         each link's pose per step; its mesh below
                                   it, static
``/world/{ep}/workpiece/handle``   the handle the fingers hold (static)
``/world/{ep}/wrist_force``        the wrist sensor's force, an arrow at the
                                   flange per step
``/sensed_wrench/{ep}``            ``[Fx, Fy, q_theta, Fz]`` at the wrist, less
                                   the hand's and the part's weight
=================================  ==========================================

Timelines: ``step`` (control steps, 0 = reset) and ``sim_time`` (``step * control_dt`` s).
"""

from __future__ import annotations

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

STEP = "step"
SIM_TIME = "sim_time"
WORLD = "/world"
BOARD = "/world/board"
#: Arrow length per newton of contact force (mm/N).
FORCE_SCALE = 2.0
FORCE_COLOR = (220, 60, 50)
#: The wrist sensor's force, drawn at the flange.
WRIST_FORCE_COLOR = (60, 130, 230)
POSE_NAMES = ["x (mm)", "y (mm)", "theta (rad)", "z (mm)"]
WRENCH_NAMES = ["Fx (N)", "Fy (N)", "q_theta (N·mm)", "Fz (N)"]
OUTCOME_NAMES = ["reward", "collision", "success"]
CONTACT_NAMES = ["peak contact force (N)", "collision threshold (N)"]
#: A robot scene's default camera (:func:`robot_eye`): what it looks at (mm: the pins
#: over their holes), from where (degrees from +x, the side away from the arm's base,
#: towards -y; degrees above the board) and how far (the board's half-size times
#: ``ROBOT_EYE_DISTANCE``, at least ``ROBOT_EYE_MIN_DISTANCE`` mm: the hand's size).
ROBOT_EYE_TARGET = (0.0, 0.0, 3.0)
ROBOT_EYE_AZIMUTH = 25.0
ROBOT_EYE_ELEVATION = 30.0
ROBOT_EYE_DISTANCE = 4.0
ROBOT_EYE_MIN_DISTANCE = 40.0


def episode_name(index: int) -> str:
    """``episode_007`` for ``index`` 7."""
    if index < 0:
        raise ValueError(f"episode index={index!r}; allowed: ≥ 0")
    return f"episode_{index:03d}"


def workpiece_path(index: int) -> str:
    return f"{WORLD}/{episode_name(index)}/workpiece"


def plugs_path(index: int) -> str:
    """The plugs of the blocked holes of episode ``index``'s workpiece (world frame)."""
    return f"{WORLD}/{episode_name(index)}/plugs"


def force_path(index: int) -> str:
    return f"{WORLD}/{episode_name(index)}/force"


def arm_path(index: int) -> str:
    """The robot's links of episode ``index`` (``arm/{link}``), when a robot holds the part."""
    return f"{WORLD}/{episode_name(index)}/arm"


def handle_path(index: int) -> str:
    """The handle on episode ``index``'s workpiece that the fingers hold (a robot's only)."""
    return f"{workpiece_path(index)}/handle"


def wrist_force_path(index: int) -> str:
    """The wrist sensor's force, drawn at the flange, when a robot holds the part."""
    return f"{WORLD}/{episode_name(index)}/wrist_force"


def series_path(quantity: str, index: int) -> str:
    """``/{quantity}/episode_{index:03d}`` for pose, wrench, reward, collision, success,
    events and metadata."""
    return f"/{quantity}/{episode_name(index)}"


def robot_eye(extent: float) -> rrb.EyeControls3D:
    """The default camera of a robot's scene (the board's half-size ``extent``, mm): on
    the side of the board away from the arm's base and a little above it, looking along
    the pads between the fingers at the pins over their holes (from across the pads, a
    finger would hide them)."""
    distance = max(ROBOT_EYE_DISTANCE * extent, ROBOT_EYE_MIN_DISTANCE)
    azimuth, elevation = np.radians(ROBOT_EYE_AZIMUTH), np.radians(ROBOT_EYE_ELEVATION)
    direction = np.array(
        [
            np.cos(elevation) * np.cos(azimuth),
            -np.cos(elevation) * np.sin(azimuth),
            np.sin(elevation),
        ]
    )
    target = np.array(ROBOT_EYE_TARGET)
    return rrb.EyeControls3D(
        position=tuple(float(v) for v in target + distance * direction),
        look_target=tuple(float(v) for v in target),
        eye_up=(0.0, 0.0, 1.0),
    )


def default_blueprint(
    extent: float | None = None, *, follow: bool = False, robot: bool = False
) -> rrb.Blueprint:
    """The 3-D scene beside the plots and the event log, on the ``step`` timeline.

    ``extent`` (mm), the board's half-size, places the camera in front of and above the
    socket, looking down at it (as the MJCF's ``overview`` camera); ``None`` lets the
    viewer choose. ``follow``: the time panel follows the latest data (the viewer opens
    at the last step) instead of playing from step 0. ``robot``: the one 3-D view holds
    the arm, the part in its fingers and the board (all under ``/world``), its camera
    :func:`robot_eye`'s, and the wrench plot has a tab for the wrist sensor's.
    """

    def plot(quantity: str, names: list[str]) -> rrb.TimeSeriesView:
        return rrb.TimeSeriesView(
            origin=f"/{quantity}", name=quantity, defaults=[rr.SeriesLines(names=names)]
        )

    wrench = plot("wrench", WRENCH_NAMES)
    if robot:  # the board's push and the wrist sensor's, one tab each
        wrench = rrb.Tabs(wrench, plot("sensed_wrench", WRENCH_NAMES))
    plots = rrb.Vertical(
        plot("pose", POSE_NAMES),
        wrench,
        plot("contact", CONTACT_NAMES),
        plot("outcome", OUTCOME_NAMES),
        rrb.TextLogView(origin="/events", name="events"),
    )
    eye = None
    if robot and extent is not None:
        eye = robot_eye(extent)
    elif extent is not None:
        eye = rrb.EyeControls3D(
            position=(0.0, -2.4 * extent, 1.2 * extent + 10.0),
            look_target=(0.0, 0.0, 8.0),
            eye_up=(0.0, 0.0, 1.0),
        )
    scene = rrb.Spatial3DView(
        origin=WORLD,
        name="scene (mm)" if robot else "socket (mm)",
        defaults=[rr.Arrows3D.from_fields(colors=FORCE_COLOR)],
        eye_controls=eye,
        # The grid lies at z = 0, the board's top, and shows through its sides; the arm's
        # world has no floor to put it on (the board is fixed in space, the arm's base
        # 60 mm below its top).
        line_grid=rrb.LineGrid3D(visible=False) if robot else None,
    )
    return rrb.Blueprint(
        rrb.Horizontal(scene, plots, column_shares=[3, 2]),
        rrb.TimePanel(timeline=STEP, play_state="following" if follow else None),
        collapse_panels=True,
    )
