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

Timelines: ``step`` (control steps, 0 = reset) and ``sim_time`` (``step * control_dt`` s).
"""

from __future__ import annotations

import rerun as rr
import rerun.blueprint as rrb

STEP = "step"
SIM_TIME = "sim_time"
WORLD = "/world"
BOARD = "/world/board"
#: Arrow length per newton of contact force (mm/N).
FORCE_SCALE = 2.0
FORCE_COLOR = (220, 60, 50)
POSE_NAMES = ["x (mm)", "y (mm)", "theta (rad)", "z (mm)"]
WRENCH_NAMES = ["Fx (N)", "Fy (N)", "q_theta (N·mm)", "Fz (N)"]
OUTCOME_NAMES = ["reward", "collision", "success"]
CONTACT_NAMES = ["peak contact force (N)", "collision threshold (N)"]


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


def wrist_force_path(index: int) -> str:
    """The wrist sensor's force, drawn at the flange, when a robot holds the part."""
    return f"{WORLD}/{episode_name(index)}/wrist_force"


def series_path(quantity: str, index: int) -> str:
    """``/{quantity}/episode_{index:03d}`` for pose, wrench, reward, collision, success,
    events and metadata."""
    return f"/{quantity}/{episode_name(index)}"


def default_blueprint(
    extent: float | None = None, *, follow: bool = False, robot: bool = False
) -> rrb.Blueprint:
    """The 3-D scene beside the plots and the event log, on the ``step`` timeline.

    ``extent`` (mm), the board's half-size, places the camera in front of and above the
    socket, looking down at it (as the MJCF's ``overview`` camera); ``None`` lets the
    viewer choose. ``follow``: the time panel follows the latest data (the viewer opens
    at the last step) instead of playing from step 0. ``robot``: a second 3-D view under
    the socket's shows the whole arm holding the part.
    """
    plots = rrb.Vertical(
        *(
            rrb.TimeSeriesView(
                origin=f"/{quantity}", name=quantity, defaults=[rr.SeriesLines(names=names)]
            )
            for quantity, names in (
                ("pose", POSE_NAMES),
                ("wrench", WRENCH_NAMES),
                ("contact", CONTACT_NAMES),
                ("outcome", OUTCOME_NAMES),
            )
        ),
        rrb.TextLogView(origin="/events", name="events"),
    )
    eye = None
    if extent is not None:
        eye = rrb.EyeControls3D(
            position=(0.0, -2.4 * extent, 1.2 * extent + 10.0),
            look_target=(0.0, 0.0, 8.0),
            eye_up=(0.0, 0.0, 1.0),
        )
    scene = rrb.Spatial3DView(
        origin=WORLD,
        name="socket (mm)",
        defaults=[rr.Arrows3D.from_fields(colors=FORCE_COLOR)],
        eye_controls=eye,
    )
    if robot:
        arm = rrb.Spatial3DView(
            origin=WORLD,
            name="robot (mm)",
            defaults=[rr.Arrows3D.from_fields(colors=FORCE_COLOR)],
            eye_controls=rrb.EyeControls3D(
                position=(120.0, -620.0, 330.0),
                look_target=(-220.0, 0.0, 130.0),
                eye_up=(0.0, 0.0, 1.0),
            ),
        )
        scene = rrb.Vertical(scene, arm)
    return rrb.Blueprint(
        rrb.Horizontal(scene, plots, column_shares=[3, 2]),
        rrb.TimePanel(timeline=STEP, play_state="following" if follow else None),
        collapse_panels=True,
    )
