"""The paper's simulator: straight moves that stop at the first collision, then slide.

Without a collision a control step moves the pose ``[x, y, theta, z]`` by
``delta = velocity · dt``. A pose collides when its pin tips are below the board's top
(``z < 0``) while ``[x, y, theta]`` is outside the tolerance
(:func:`tolins.tolerance.contains`). A step that would collide moves to the first
collision point (step fraction ``tau``) and there loses only the blocked components of
its motion; the rest of the step, the fraction ``1 - tau``, continues without them:

* **board top**: the pins reach ``z = 0`` outside the tolerance (found exactly, the
  crossing of ``z = 0``). The top blocks ``z``: the workpiece ends the step at ``z = 0``
  with ``x, y, theta`` moved by the whole commanded ``delta`` (sliding on the top is
  free, ``z = 0`` being touching, not colliding), and feels ``Fz = +1 N``. A slide that
  brings the pins over their holes does not descend in the same step; the next step
  does.
* **wall**: below the top, the part of the step under the surface is sampled at 16
  evenly spaced points; between the last free and the first colliding one a binary
  search of 28 halvings (to 2e-10 of the step) finds the contact ``tau``. A wall blocks
  ``x, y, theta``: they stay at the contact, while ``z`` continues by the rest of the
  step (``z`` ends at ``z + delta_z`` as in free motion; descending or ascending with
  ``x, y, theta`` at a free pose cannot collide). The workpiece feels ``-1 N`` along its
  blocked horizontal motion and ``-1 N·mm`` against its rotation. An ascending step
  that leaves the hole after a wall contact ends at the contact's ``x, y, theta``.

**Short pins** (``pin_shortenings``): pin ``i`` is inside the board when ``z + s_i < 0``
(``s_i`` its shortening, :func:`~tolins.geometry.tolerance.pin_levels`) outside its hole.
Only the full-length pins land on the top at ``z = 0``; a short pin outside its hole that
reaches the top lower down is found by the wall search (it was already outside its hole
before the contact, a wall contact's pin was inside) and stops the whole step there,
``z`` at ``-s_i`` and ``x, y, theta`` at the contact (no sliding on the top with other
pins down in their holes), with ``Fz = +1 N``.

The workpiece stays in the servo range (:data:`~tolins.geometry.workspace.POSE_LOW` …
``POSE_HIGH``): a step that would leave it stops at its edge, as the MuJoCo joints do,
with no contact force; the lower end of z is the carrier plate on the board's top.

The contact force is binary (:data:`CONTACT_FORCE`, :data:`CONTACT_TORQUE`);
``peak_force`` is 1 N for a step with a collision (top or wall) and 0 otherwise. There
is no floor: inserted pins go down freely to the carrier. A collision narrower than a
sixteenth of the submerged step between two free samples would be missed (a thin
sliver of wall; none at these clearances and speeds).

:class:`KinematicBatch` moves many workpieces at once: the simulations that step together and
share a workpiece (every one, unless bent pins are drawn per episode) move in one call of
:func:`kinematic_step`, whose rows are independent, so each is the single env's step bit for
bit. The single env's :class:`KinematicBackend` is a batch of one.
"""

from __future__ import annotations

import mujoco
import numpy as np

from tolins.geometry.defects import DEFECT_KINDS
from tolins.geometry.specs import SocketSpec
from tolins.geometry.tolerance import contains, pin_levels, pins_inside_pose
from tolins.geometry.validation import check_int
from tolins.geometry.workspace import POSE_HIGH, POSE_LOW
from tolins.mjcf import model_layout
from tolins.physics.compiled import SocketCache, compile_model
from tolins.physics.protocol import BackendState, BatchState, Capabilities
from tolins.physics.schedule import check_control_dt
from tolins.physics.versions import PhysicsVersion
from tolins.physics.versions import physics_version as physics_version_of

#: The binary contact force (N) and torque (N·mm) of a colliding workpiece.
CONTACT_FORCE = 1.0
CONTACT_TORQUE = 1.0
_SAMPLES = 16
_BISECTIONS = 28
_FRACTIONS = np.arange(1, _SAMPLES + 1) / _SAMPLES


def colliding(spec: SocketSpec, poses: np.ndarray) -> np.ndarray:
    """Whether each pose ``[..., 4]`` = ``[x, y, theta, z]`` has a pin inside the board."""
    levels = pin_levels(spec)
    if not levels.any():
        below = poses[..., 3] < 0.0
        return below & ~contains(spec, poses[..., :3])
    return np.any(_stuck_pins(spec, poses, levels), axis=-1)


def _stuck_pins(spec: SocketSpec, poses: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """``(..., n_pins)``: which pins of a spec with short pins are inside the board."""
    below = poses[..., 3, None] + levels < 0.0
    return below & ~pins_inside_pose(spec, poses[..., :3])


def _landed(spec: SocketSpec, poses: np.ndarray) -> np.ndarray:
    """Whether the full-length pins at ``poses`` ``[..., 3]`` on the top are outside a hole."""
    levels = pin_levels(spec)
    if not levels.any():
        return ~contains(spec, poses)
    return np.any(~pins_inside_pose(spec, poses) & (levels == 0.0), axis=-1)


def kinematic_step(
    spec: SocketSpec, poses: np.ndarray, velocities: np.ndarray, dt: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Move collision-free ``poses`` ``(n, 4)`` by ``velocities · dt``; at the first collision
    drop the blocked components and slide on (module docstring). Returns the new poses,
    the wrenches ``(n, 4)`` and which collided ``(n,)``."""
    delta = velocities * dt
    new = poses + delta
    wrench = np.zeros_like(poses)
    collided = np.zeros(len(poses), dtype=bool)
    # Only the part of a step below the board's top, [t_in, t_out], can collide.
    rows = np.flatnonzero(np.minimum(poses[:, 3], new[:, 3]) < 0.0)
    if rows.size == 0:
        return _in_range(new), wrench, collided
    z0, dz = poses[rows, 3], delta[rows, 3]
    crossing = -z0 / np.where(dz != 0.0, dz, 1.0)
    t_in = np.where(z0 > 0.0, crossing, 0.0)
    t_out = np.where(dz > 0.0, np.minimum(crossing, 1.0), 1.0)
    # Landing: the pins reach the board's top outside the tolerance (z0 < 0: inside).
    # The top blocks z; x, y, theta slide on by the whole step (free at z = 0).
    landing = poses[rows, :3] + t_in[:, None] * delta[rows, :3]
    landed = (z0 >= 0.0) & _landed(spec, landing)
    new[rows[landed], 3] = 0.0
    wrench[rows[landed], 3] = CONTACT_FORCE
    collided[rows[landed]] = True
    rows, t_in, t_out = rows[~landed], t_in[~landed], t_out[~landed]
    if rows.size == 0:
        return _in_range(new), wrench, collided
    # Walls: the first of _SAMPLES points below the top that collides, then bisection.
    taus = t_in[:, None] + (t_out - t_in)[:, None] * _FRACTIONS
    bad = colliding(spec, poses[rows, None, :] + taus[..., None] * delta[rows, None, :])
    hit = bad.any(axis=1)
    rows, taus, bad, t_in = rows[hit], taus[hit], bad[hit], t_in[hit]
    if rows.size == 0:
        return _in_range(new), wrench, collided
    first = np.argmax(bad, axis=1)
    index = np.arange(rows.size)
    lo, hi = np.where(first > 0, taus[index, first - 1], t_in), taus[index, first]
    start, step = poses[rows], delta[rows]
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        bad = colliding(spec, start + mid[:, None] * step)
        hi, lo = np.where(bad, mid, hi), np.where(bad, lo, mid)
    # A wall blocks x, y, theta at the contact; z goes on by the whole step.
    new[rows, :3] = start[:, :3] + lo[:, None] * step[:, :3]
    wrench[rows] = _wall_wrench(velocities[rows])
    collided[rows] = True
    levels = pin_levels(spec)
    if levels.any():
        _short_pin_tops(
            spec, new, wrench, rows, start + lo[:, None] * step, start + hi[:, None] * step
        )
    return _in_range(new), wrench, collided


def _short_pin_tops(
    spec: SocketSpec,
    new: np.ndarray,
    wrench: np.ndarray,
    rows: np.ndarray,
    before: np.ndarray,
    after: np.ndarray,
) -> None:
    """Contacts of short pins with the top (module docstring), in place: the pin stuck after
    the contact was outside its hole before it. The step stops at the contact, ``z`` on
    the highest such pin's level."""
    levels = pin_levels(spec)
    top = _stuck_pins(spec, after, levels) & ~pins_inside_pose(spec, before[:, :3])
    hit = top.any(axis=1)
    if not hit.any():
        return
    z = np.max(np.where(top[hit], -levels, -np.inf), axis=1)
    new[rows[hit], :3] = before[hit, :3]
    new[rows[hit], 3] = z
    wrench[rows[hit]] = 0.0
    wrench[rows[hit], 3] = CONTACT_FORCE


def _in_range(poses: np.ndarray) -> np.ndarray:
    """``poses`` stopped at the servo range, in place."""
    return np.clip(poses, POSE_LOW, POSE_HIGH, out=poses)


def _wall_wrench(velocities: np.ndarray) -> np.ndarray:
    """Binary wrench of a wall: against the blocked horizontal motion and rotation."""
    horizontal = velocities[:, :2]
    speed = np.hypot(horizontal[:, 0], horizontal[:, 1])[:, None]
    wrench = np.zeros((len(velocities), 4))
    wrench[:, :2] = -CONTACT_FORCE * np.divide(
        horizontal, speed, out=np.zeros_like(horizontal), where=speed > 0
    )
    wrench[:, 2] = -CONTACT_TORQUE * np.sign(velocities[:, 2])
    return wrench


def _drawing(socket: SocketSpec) -> tuple[mujoco.MjModel, mujoco.MjData, np.ndarray]:
    """The MuJoCo model of ``socket``, a data of it, to draw its workpiece's poses, and the
    model's ``joint_pose`` (:func:`tolins.mjcf.model_layout`: each ``qpos`` entry's pose
    component; the model's ``qpos`` is the workpiece's four joints)."""
    model = compile_model(socket)
    return model, mujoco.MjData(model), model_layout(model).joint_pose


def posed_data(
    model: mujoco.MjModel, data: mujoco.MjData, joint_pose: np.ndarray, pose: np.ndarray
) -> mujoco.MjData:
    """``data`` of ``model`` (made by :func:`tolins.make_mjcf`, ``joint_pose`` its layout's)
    with the workpiece's joints at ``pose`` ``[x, y, theta, z]`` and forward kinematics run:
    the drawing of a kinematic pose."""
    data.qpos[:] = pose[joint_pose]
    mujoco.mj_forward(model, data)
    return data


class KinematicBatch(Capabilities):
    """``num_envs`` kinematic workpieces, each of its own socket (default the nominal).

    Args:
        socket: The nominal socket.
        num_envs: Number of workpieces.
        control_dt: Control period (s).
    """

    supports_render = True
    supports_randomization = True
    supports_touch_points = False
    defect_kinds = frozenset(DEFECT_KINDS)

    def __init__(
        self,
        socket: SocketSpec,
        num_envs: int,
        control_dt: float,
        physics_version: int | PhysicsVersion = 1,
    ) -> None:
        physics_version_of(physics_version)  # the same simulator in every version
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        self.control_dt = check_control_dt(control_dt)
        self._sockets: list[SocketSpec] = [socket] * self.num_envs
        self._pose = np.zeros((self.num_envs, 4))
        # MuJoCo models (and a data each) of the workpieces drawn: the nominal one and the
        # last 2 num_envs others.
        self._drawings = SocketCache(_drawing, socket, 2 * self.num_envs)

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        self._sockets[index] = socket

    def set_physics(self, index: int, draw: object) -> None:
        """Nothing: the kinematic model has no friction, stiffness or servos."""

    @property
    def pose(self) -> np.ndarray:
        """The current poses ``(num_envs, 4)`` (a copy)."""
        return self._pose.copy()

    def reset(
        self, ids: np.ndarray, poses: np.ndarray, keep_part: np.ndarray | None = None
    ) -> BatchState:
        """Place workpiece ``ids[k]`` at ``poses[k]``; ``ValueError`` if one is inside the
        board (``keep_part``: nothing to keep, its pins do not bend)."""
        ids = np.asarray(ids, dtype=np.intp)
        poses = np.asarray(poses, dtype=float)
        for row, i in enumerate(ids.tolist()):
            if colliding(self._sockets[i], poses[row][None])[0]:
                raise ValueError(
                    f"poses[{row}]={poses[row].tolist()!r} puts a pin inside the board; "
                    "allowed: z ≥ 0, or z < 0 with [x, y, theta] in the tolerance"
                )
        self._pose[ids] = poses
        n = len(ids)
        return BatchState(self._pose[ids], np.zeros((n, 4)), np.zeros(n))

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        ids = np.asarray(ids, dtype=np.intp)
        velocities = np.asarray(velocities, dtype=float)
        wrench, peak = np.zeros((len(ids), 4)), np.zeros(len(ids))
        groups: dict[int, list[int]] = {}
        for row, i in enumerate(ids.tolist()):
            groups.setdefault(id(self._sockets[i]), []).append(row)
        for rows in groups.values():
            rows = np.array(rows)
            sims = ids[rows]
            socket = self._sockets[sims[0]]
            pose, wrench[rows], collided = kinematic_step(
                socket, self._pose[sims], velocities[rows], self.control_dt
            )
            self._pose[sims] = pose
            peak[rows] = np.where(collided, CONTACT_FORCE, 0.0)
        return BatchState(self._pose[ids], wrench, peak)

    def drawing(self, index: int) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """Workpiece ``index``'s MuJoCo model and a data posed at its pose (forward
        kinematics only), as the single env's ``KinematicBackend.data`` draws it. The data
        is shared by the workpieces of one socket: draw it before asking for the next."""
        model, data, joint_pose = self._drawings.get(self._sockets[index])
        return model, posed_data(model, data, joint_pose, self._pose[index].copy())

    def close(self) -> None:
        """Release the drawing models (the poses are plain arrays)."""
        self._drawings.clear()


#: The batch row of a single backend.
_ONE = np.zeros(1, dtype=np.intp)


class KinematicBackend(Capabilities):
    """One workpiece with the kinematic model, behind the
    :class:`~tolins.physics.protocol.Backend` protocol: a :class:`KinematicBatch` of one.

    ``model`` and ``data`` are the MuJoCo model of the workpiece, built on first use, and
    a data posed at its pose, for drawing only (``InsertionEnv.render``); they play no part
    in the motion.
    """

    supports_render = True
    supports_randomization = True
    supports_touch_points = False
    defect_kinds = frozenset(DEFECT_KINDS)

    def __init__(
        self, spec: SocketSpec, control_dt: float, physics_version: int | PhysicsVersion = 1
    ) -> None:
        self.spec = spec
        self._batch = KinematicBatch(spec, 1, control_dt, physics_version)

    def set_socket(self, socket: SocketSpec) -> None:
        """Move ``socket``'s workpiece from the next reset on."""
        self.spec = socket
        self._batch.set_socket(0, socket)

    def set_physics(self, draw: object) -> None:
        """Nothing: the kinematic model has no friction, stiffness or servos."""

    def reset(self, pose: np.ndarray, keep_part: bool = False) -> BackendState:
        return self._batch.reset(_ONE, np.reshape(pose, (1, 4))).row(0)

    def step(self, velocity: np.ndarray) -> BackendState:
        return self._batch.step(_ONE, np.reshape(velocity, (1, 4))).row(0)

    @property
    def model(self) -> mujoco.MjModel:
        return self._batch.drawing(0)[0]

    @property
    def data(self) -> mujoco.MjData:
        """MuJoCo data posed at the current pose (forward kinematics only)."""
        return self._batch.drawing(0)[1]
