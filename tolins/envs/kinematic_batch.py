"""The paper's simulator for many workpieces at once: one numpy call per workpiece shape.

:class:`KinematicBatch` is the :class:`~tolins.envs.batch.BatchPhysics` of the vector env
on the kinematic backend, and the single env's kinematic backend is a batch of one
(:class:`~tolins.envs.kinematic_backend.KinematicBackend`). The simulations that step
together and share a workpiece (every one, unless bent pins are drawn per episode) move
in one call of :func:`~tolins.envs.kinematic_backend.kinematic_step`, whose rows are
independent: each is the single env's step bit for bit.
"""

from __future__ import annotations

import mujoco
import numpy as np

from tolins.envs.batch import BatchState
from tolins.envs.episode import check_control_dt
from tolins.envs.kinematic_backend import CONTACT_FORCE, colliding, kinematic_step, posed_data
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int
from tolins.mjcf import make_mjcf


class KinematicBatch:
    """``num_envs`` kinematic workpieces, each of its own socket (default the nominal).

    Args:
        socket: The nominal socket.
        num_envs: Number of workpieces.
        control_dt: Control period (s).
    """

    def __init__(self, socket: SocketSpec, num_envs: int, control_dt: float) -> None:
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        self.control_dt = check_control_dt(control_dt)
        self._sockets: list[SocketSpec] = [socket] * self.num_envs
        self._pose = np.zeros((self.num_envs, 4))
        # MuJoCo models of the workpieces drawn so far, by identity of their socket.
        self._drawings: dict[int, tuple[SocketSpec, mujoco.MjModel, mujoco.MjData]] = {}

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        self._sockets[index] = socket

    def set_physics(self, index: int, draw: object) -> None:
        """Nothing: the kinematic model has no friction, stiffness or servos."""

    @property
    def pose(self) -> np.ndarray:
        """The current poses ``(num_envs, 4)`` (a copy)."""
        return self._pose.copy()

    def reset(self, ids: np.ndarray, poses: np.ndarray) -> BatchState:
        """Place workpiece ``ids[k]`` at ``poses[k]``; ``ValueError`` if one is inside the
        board."""
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
        socket = self._sockets[index]
        entry = self._drawings.get(id(socket))
        if entry is None or entry[0] is not socket:
            model = mujoco.MjModel.from_xml_string(make_mjcf(socket))
            if len(self._drawings) >= 2 * self.num_envs:  # the oldest are no longer drawn
                self._drawings.pop(next(iter(self._drawings)))
            entry = self._drawings[id(socket)] = (socket, model, mujoco.MjData(model))
        _, model, data = entry
        return model, posed_data(model, data, self._pose[index].copy())

    def close(self) -> None:
        """Release the drawing models (the poses are plain arrays)."""
        self._drawings.clear()
