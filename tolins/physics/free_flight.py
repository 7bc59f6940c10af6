"""Free flight: the larger physics step of ``-v2`` physics, taken where nothing can touch.

A control step runs on the model's own (contact) physics step unless, for the whole control
step, no part of the workpiece can reach the board or a joint limit and the larger step is
proven to give the same state at every contact read. :func:`free_step_factors` decides that
per simulation, at the start of the control step, from numbers alone:

**Reach.** The servos are re-anchored at the start of every control step
(:mod:`tolins.physics.servo`), so along each joint the workpiece travels at most
``|u| T + |v0| tau`` during a control step of ``T`` seconds under the command ``u`` after
moving at ``v0``: the commanded travel plus the overshoot of a critically damped servo
whose set-point is reset while it moves, ``tau = 1 / omega`` with ``omega = sqrt(kp / M)``
(2.35 ms at the nominal gains; measured at most 2.03 ms on the contact step and 0.95 ms on
a 5 ms one). Everything a pin can touch lies at or below the board's top or outside the
circle within its hole's walls, so the step is free when every joint stays
:data:`CLEARANCE` inside its range (MuJoCo's joint limits are constraints as contacts are)
and either the workpiece's lowest point stays :data:`CLEARANCE` above the board's top after
the downward reach, or every pin stays :data:`CLEARANCE` inside that circle after its
sideways reach (``|x| + |y|`` travel plus the hinge's arc) with the carrier above the board.

**The step.** In free flight each joint is a linear servo, integrated by ``implicitfast``
with its damping implicit: a step ``h`` ends every contact-read chunk at the state of the
contact step (to 1e-12 mm over hundreds of control steps, the rounding of the sums) while
``omega h`` ≤ :data:`LINEAR_STABLE` and no servo reaches its force limit, and while
``omega h`` ≤ :data:`SATURATED_STABLE` when one may (a saturated servo's force is explicit;
beyond that it chatters at its limit). A servo is pushed hardest right after the
re-anchoring (``-kv v0``: the hinge's saturates from 0.022 rad/s on), and its force decays
with the transient (:data:`FORCE_AFTER`), so a control step may start with a window of
contact steps (:data:`WINDOWS`) and take the longer step after it, once no servo can reach
its limit. Of the ways to do this (:func:`free_steps`) the cheapest that the rules allow is
taken: at the nominal gains, 5 ms steps, after a window of 0–15 ms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from tolins.mjcf import model_layout

#: The largest physics step taken in free flight (s).
MAX_FREE_STEP = 0.005
#: The shortest contact step (s) whose models take the longer step in free flight. On the
#: finer grades' 0.5 and 0.25 ms steps, contact outcomes turn on the last bits of the state:
#: moving ``-v1``'s start by 1e-12 mm changes 3 of 20 efficient-expert episodes on the 2*2
#: at 20 µm and on the 2*8 at 50 µm (none at 1 ms), so no other arithmetic, however
#: close, keeps their outcomes; those grades take ``-v2``'s board in the world body only.
MIN_CONTACT_STEP = 1e-3
#: Gap (mm, and rad for the hinge's limits) left between the workpiece's reach and anything
#: it could touch.
CLEARANCE = 1e-3
#: ``omega h`` up to which a step of servos below their force limits is exact (measured
#: exact to 3.0).
LINEAR_STABLE = 2.5
#: ``omega h`` up to which a step is exact when a servo may saturate (measured exact to
#: 1.26, off by 8e-5 mm at 1.30).
SATURATED_STABLE = 1.2
#: The z joint's place in ``qpos`` (x, y, z, theta: :func:`tolins.mjcf.model_layout`).
_Z = 2
#: Margin on the servo forces of :data:`FORCE_AFTER`.
SATURATION_FACTOR = 1.25
#: ``(omega t, bound)``: a servo's largest force from ``t`` after the re-anchoring on, over
#: ``kv (|v0| + |u|)``, at the contact step and at 5 ms (the largest measured on the 2*2 over
#: a 9 × 9 grid of ``v0`` and ``u`` from -1 to 1 times every joint's full speed; ``t`` of 0,
#: 5, 10 and 15 ms at the slides' nominal ``omega``).
FORCE_AFTER = ((0.0, 1.12), (2.13, 0.33), (4.26, 0.19), (6.39, 0.13))
#: The windows (s) on the contact step a free-flight control step may start with, so that
#: the servos' transient has decayed below their force limits when the longer step begins.
WINDOWS = (0.0, 0.005, 0.010, 0.015)


@dataclass(frozen=True)
class ServoLimits:
    """What :func:`free_step_factors` reads of one model, in joint (``qpos``) order.

    Attributes:
        timestep: The model's (contact) physics step (s).
        kv: Each servo's velocity gain.
        force_limit: Each servo's force limit (the smaller magnitude of its range).
        omega: Each servo's natural frequency ``sqrt(kp / M)`` (rad/s), ``M`` the joint's
            inertia with its armature.
        low, high: Each joint's range.
        lowest: The workpiece's lowest point below its pose's ``z`` (mm; 0 for pins of
            full length, less for shortened ones).
        board_top: The highest point of everything else (mm; the board's top, 0).
        rest_lowest: The lowest point of the workpiece but its pins, below its pose's ``z``
            (mm; -4, the carrier over pins 4 mm long).
        pin_xy: ``(pins, 2)`` each pin's axis in the workpiece's frame (mm).
        pin_radius: Each pin's radius about its axis (mm; its bounding circle).
        hole_xy: ``(pins, 2)`` the centre of each pin's hole (mm).
        hole_radius: The radius of the circle inside each hole's walls (mm); ``-inf`` where
            that cannot be told (a plugged hole, a hole of other walls than a circle's).

    Of one model, the joints' fields are ``(4,)`` and the others scalars; of a batch
    (:meth:`stack`), ``(n, 4)`` and ``(n,)``.
    """

    timestep: np.ndarray
    kv: np.ndarray
    force_limit: np.ndarray
    omega: np.ndarray
    low: np.ndarray
    high: np.ndarray
    lowest: np.ndarray
    board_top: np.ndarray
    rest_lowest: np.ndarray
    pin_xy: np.ndarray
    pin_radius: np.ndarray
    hole_xy: np.ndarray
    hole_radius: np.ndarray

    @classmethod
    def stack(cls, limits: list[ServoLimits]) -> ServoLimits:
        """The limits of several simulations, one row each."""
        fields = cls.__dataclass_fields__
        return cls(**{name: np.array([getattr(lim, name) for lim in limits]) for name in fields})

    def rows(self, ids: np.ndarray) -> ServoLimits:
        """The stacked limits of simulations ``ids``."""
        return ServoLimits(**{name: getattr(self, name)[ids] for name in self.__dataclass_fields__})


def _top_and_bottom(data: mujoco.MjData, geoms: np.ndarray, model: mujoco.MjModel) -> np.ndarray:
    """``(len(geoms), 2)``: the lowest and highest world z of each geom's bounding box."""
    rows = data.geom_xmat[geoms].reshape(-1, 3, 3)[:, 2, :]  # world z of each local axis
    centre = data.geom_xpos[geoms, 2] + np.einsum("gi,gi->g", rows, model.geom_aabb[geoms, :3])
    half = np.einsum("gi,gi->g", np.abs(rows), model.geom_aabb[geoms, 3:])
    return np.stack([centre - half, centre + half], axis=1)


def servo_limits(model: mujoco.MjModel) -> ServoLimits:
    """The :class:`ServoLimits` of ``model`` (a model of :func:`tolins.make_mjcf`), read from
    its current parameters (a randomised-physics draw included)."""
    layout = model_layout(model)
    data = mujoco.MjData(model)
    z = layout.pose_joint[3]
    data.qpos[z] = 10.0
    mujoco.mj_forward(model, data)
    mass_matrix = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass_matrix)
    inertia = np.diag(mass_matrix)[: model.nu].copy()  # the servos' joints (not pin hinges)
    kp = model.actuator_gainprm[:, 0]
    ranges = model.actuator_forcerange
    workpiece = model.body("workpiece").id
    moving = np.isin(
        model.geom_bodyid, [b for b in range(model.nbody) if _under(model, b, workpiece)]
    )
    extents = _top_and_bottom(data, np.arange(model.ngeom), model)
    pins = np.array(layout.pin_geoms)
    rest = moving.copy()
    rest[pins] = False
    hole_xy, hole_radius = _holes(model, data, len(pins))
    return ServoLimits(
        timestep=np.float64(model.opt.timestep),
        kv=-model.actuator_biasprm[:, 2].copy(),
        force_limit=np.minimum(-ranges[:, 0], ranges[:, 1]),
        omega=np.sqrt(kp / inertia),
        low=model.jnt_range[: model.nu, 0].copy(),
        high=model.jnt_range[: model.nu, 1].copy(),
        lowest=np.float64(data.qpos[z] - extents[moving, 0].min()),
        board_top=np.float64(extents[~moving, 1].max()),
        rest_lowest=np.float64(data.qpos[z] - extents[rest, 0].min()),
        pin_xy=data.geom_xpos[pins, :2].copy(),
        pin_radius=np.array([_axial_radius(model, g) for g in pins]),
        hole_xy=hole_xy,
        hole_radius=hole_radius,
    )


def _axial_radius(model: mujoco.MjModel, geom: int) -> float:
    """The radius of a pin about its axis: a cylinder's, else its bounding box's corner."""
    if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return float(model.geom_size[geom, 0])
    centre, half = model.geom_aabb[geom, :2], model.geom_aabb[geom, 3:5]
    return float(np.hypot(*(np.abs(centre) + half)))


def _holes(model: mujoco.MjModel, data: mujoco.MjData, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Each hole's centre and the radius of the circle inside its walls: for walls of a
    regular polygon in a square cell (a circle's 16-gon), the centre of their vertices and
    the nearest vertex's distance times ``cos(pi / sides)`` (the faces' distance)."""
    centres, radii = np.zeros((n, 2)), np.full(n, -np.inf)
    names = [model.geom(g).name for g in range(model.ngeom)]
    for h in range(n):
        walls = [g for g, name in enumerate(names) if name.startswith(f"hole{h}_wall")]
        points = [_mesh_points(model, data, g) for g in walls]
        if not points:
            continue
        vertices = np.concatenate(points)
        centres[h] = vertices.mean(axis=0)
        if len(walls) % 4 == 0 and f"plug{h}" not in names:
            nearest = np.linalg.norm(vertices - centres[h], axis=1).min()
            radii[h] = nearest * math.cos(math.pi / len(walls))
    return centres, radii


def _mesh_points(model: mujoco.MjModel, data: mujoco.MjData, geom: int) -> np.ndarray:
    """World ``(x, y)`` of the vertices of a mesh geom."""
    mesh = model.geom_dataid[geom]
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    local = model.mesh_vert[start : start + count]
    world = data.geom_xpos[geom] + local @ data.geom_xmat[geom].reshape(3, 3).T
    return world[:, :2]


def _under(model: mujoco.MjModel, body: int, root: int) -> bool:
    """Whether ``body`` is ``root`` or one of its descendants."""
    while body > 0:
        if body == root:
            return True
        body = model.body_parentid[body]
    return False


@dataclass(frozen=True)
class FreeStep:
    """How a control step in free flight runs: ``window`` contact steps first (while the
    servos' re-anchoring transient may saturate them), then physics steps ``factor`` contact
    steps long. ``cost``: physics steps in all."""

    window: int
    factor: int
    cost: float


def free_steps(timestep: float, chunks: list[int]) -> list[FreeStep]:
    """The ways to run a control step of ``chunks`` contact steps (of ``timestep`` s)
    between the contact reads in free flight, cheapest first: a window of
    :data:`WINDOWS` on the contact step, then a longer step of ``factor`` contact steps, at
    most :data:`MAX_FREE_STEP`, ending every chunk on a whole step; none for a contact step
    under :data:`MIN_CONTACT_STEP`."""
    if timestep < MIN_CONTACT_STEP - 1e-12:
        return []
    total = sum(chunks)
    largest = math.floor(MAX_FREE_STEP / timestep + 1e-9)
    options = []
    for seconds in WINDOWS:
        window = round(seconds / timestep)
        if abs(window * timestep - seconds) > 1e-12 or window > chunks[0]:
            continue
        for factor in range(largest, 1, -1):
            rest = [chunks[0] - window, *chunks[1:]]
            if all(n % factor == 0 for n in rest):
                options.append(FreeStep(window, factor, window + (total - window) / factor))
    return sorted(options, key=lambda option: option.cost)


def free_flight_plan(
    limits: ServoLimits,
    qpos: np.ndarray,
    qvel: np.ndarray,
    ctrl: np.ndarray,
    control_time: float,
    options: list[FreeStep],
) -> tuple[np.ndarray, np.ndarray]:
    """Each simulation's ``(window, factor)`` for this control step: ``(0, 1)`` (the contact
    step throughout) unless it is in free flight, else the cheapest of ``options`` (from
    :func:`free_steps`) that the module docstring's rules allow.

    Args:
        limits: The simulations' limits (:meth:`ServoLimits.stack`).
        qpos, qvel, ctrl: ``(n, 4)`` joint positions, speeds and servo commands now.
        control_time: The control step's length (s).
        options: The ways to step it, cheapest first (one contact step for all).
    """
    n = len(qpos)
    window, factor = np.zeros(n, dtype=np.intp), np.ones(n, dtype=np.intp)
    if not options:
        return window, factor
    lim, z = limits, _Z
    speed, command = np.abs(qvel), np.abs(ctrl)
    reach = command * control_time + speed / lim.omega
    down = np.maximum(-ctrl[:, z], 0.0) * control_time
    down += np.maximum(-qvel[:, z], 0.0) / lim.omega[:, z]
    height = qpos[:, z] - down - lim.board_top
    in_range = np.all(
        (qpos - reach - lim.low > CLEARANCE) & (lim.high - qpos - reach > CLEARANCE), axis=1
    )
    above = height - lim.lowest > CLEARANCE
    inside = _inside_holes(lim, qpos, reach) & (height - lim.rest_lowest > CLEARANCE)
    clear = in_range & (above | inside)
    pushed = SATURATION_FACTOR * lim.kv * (speed + command) / lim.force_limit
    slowest, fastest = lim.omega.min(axis=1), lim.omega.max(axis=1)
    open_ = clear.copy()
    for option in options:
        h = option.factor * lim.timestep
        after = _force_after(slowest * option.window * lim.timestep)
        linear = np.all(pushed * after[:, None] < 1.0, axis=1)
        stable = (linear & (fastest * h <= LINEAR_STABLE)) | (
            (option.window == 0) & (fastest * h <= SATURATED_STABLE)
        )
        take = open_ & stable
        window[take], factor[take] = option.window, option.factor
        open_ &= ~take
    return window, factor


def _inside_holes(lim: ServoLimits, qpos: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Whether every pin stays inside the circle within its hole's walls, whatever its height
    (a pin there touches nothing: the board's top and walls lie outside that circle)."""
    theta = qpos[:, 3]
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    px, py = lim.pin_xy[..., 0], lim.pin_xy[..., 1]
    x = c * px - s * py + qpos[:, :1]
    y = s * px + c * py + qpos[:, 1:2]
    off_centre = np.hypot(x - lim.hole_xy[..., 0], y - lim.hole_xy[..., 1])
    sway = reach[:, :1] + reach[:, 1:2] + reach[:, 3:4] * np.hypot(px, py)
    return np.all(off_centre + lim.pin_radius + sway < lim.hole_radius - CLEARANCE, axis=1)


def _force_after(x: np.ndarray) -> np.ndarray:
    """The largest servo force after ``x = omega t`` of a control step, over
    ``kv (|v0| + |u|)`` (:data:`FORCE_AFTER`, the bound of the last window reached)."""
    bounds = np.array([bound for start, bound in FORCE_AFTER])
    starts = np.array([start for start, bound in FORCE_AFTER])
    return bounds[np.searchsorted(starts, x + 1e-9, side="right") - 1]
