"""Contact physics: one MuJoCo model of a socket, stepped one control period at a time."""

from __future__ import annotations

import math

import mujoco
import numpy as np

from tolins.envs.backend import BackendState
from tolins.geometry.specs import SocketSpec
from tolins.mjcf import make_mjcf

#: Model units (mN, µN·m) to the API's N and N·mm.
_FORCE_SCALE = 1e-3
#: Pose ``[x, y, theta, z]`` ↔ joint order ``x, y, z, theta`` (qpos, act and ctrl); the
#: swap is its own inverse.
_SWAP_Z_THETA = np.array([0, 1, 3, 2])


class MujocoBackend:
    """Steps a compiled socket model with re-anchored velocity servos.

    At the start of every control step each servo's integrated set-point is reset to
    the joint's current position, then the commanded velocity is integrated over the
    step. A blocked workpiece so stops at the first contact and pushes with at most
    the servo's force limit instead of winding up.

    Args:
        spec: The socket.
        control_dt: Control period (s); a whole number of physics steps.
        contact_checks: How many times per control step the contact force is read
            (evenly spaced), for ``peak_force``.
    """

    def __init__(self, spec: SocketSpec, control_dt: float, contact_checks: int = 5) -> None:
        self.spec = spec
        self.model = mujoco.MjModel.from_xml_string(make_mjcf(spec))
        self.data = mujoco.MjData(self.model)
        substeps = round(control_dt / self.model.opt.timestep)
        if substeps < 1 or abs(substeps * self.model.opt.timestep - control_dt) > 1e-9:
            raise ValueError(
                f"control_dt={control_dt!r} is not a whole number of physics steps of "
                f"{self.model.opt.timestep} s"
            )
        if not 1 <= contact_checks <= substeps or substeps % contact_checks:
            raise ValueError(
                f"contact_checks={contact_checks!r} must divide the {substeps} physics "
                "steps of a control step"
            )
        self.substeps = substeps
        self._chunk = substeps // contact_checks
        self._checks = contact_checks
        self._force = self.model.sensor("force").adr[0]
        self._torque = self.model.sensor("torque").adr[0]
        touch = [self.model.sensor(f"pin{i}_touch").adr[0] for i in range(spec.n_pins)]
        if touch != list(range(touch[0], touch[0] + spec.n_pins)):
            raise RuntimeError("the pins' touch sensors are not stored contiguously")
        # Views into MjData's buffers (valid for its lifetime): the hot loop reads them
        # without building new arrays.
        self._touch = self.data.sensordata[touch[0] : touch[0] + spec.n_pins]
        self._wrench = self.data.sensordata[self._force : self._force + 3]
        self._warnings = self.data.warning.number

    def _state(self, peak_force: float, error: str | None = None) -> BackendState:
        d = self.data
        theta = d.qpos[3]
        fx, fy, fz = self._wrench.tolist()
        c, s = math.cos(theta), math.sin(theta)
        wrench = np.array([s * fy - c * fx, -s * fx - c * fy, -d.sensordata[self._torque + 2], -fz])
        return BackendState(
            pose=d.qpos[_SWAP_Z_THETA],
            wrench=wrench * _FORCE_SCALE,
            peak_force=peak_force,
            error=error,
        )

    def _contact_force(self) -> float:
        return sum(self._touch.tolist()) * _FORCE_SCALE

    def pin_forces(self) -> np.ndarray:
        """Summed normal contact force on each pin now (N), ``(n_pins,)``."""
        return self._touch * _FORCE_SCALE

    def reset(self, pose: np.ndarray) -> BackendState:
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        d.qpos[:] = np.asarray(pose, dtype=float)[_SWAP_Z_THETA]
        d.act[:] = d.qpos
        mujoco.mj_forward(m, d)
        return self._state(self._contact_force())

    def step(self, velocity: np.ndarray) -> BackendState:
        m, d = self.model, self.data
        warnings_before = sum(self._warnings.tolist())
        d.act[:] = d.qpos
        d.ctrl[:] = np.asarray(velocity, dtype=float)[_SWAP_Z_THETA]
        touch, peak = self._touch, 0.0
        for _ in range(self._checks):
            mujoco.mj_step(m, d, nstep=self._chunk)
            peak = max(peak, sum(touch.tolist()))
        return self._state(peak * _FORCE_SCALE, self._fault(warnings_before))

    def _fault(self, warnings_before: int) -> str | None:
        d = self.data
        if sum(self._warnings.tolist()) != warnings_before:
            raised = [mujoco.mjtWarning(i).name for i, w in enumerate(d.warning) if w.number > 0]
            return f"MuJoCo warning during the step: {', '.join(raised)}"
        if not math.isfinite(sum(d.qpos.tolist()) + sum(d.qvel.tolist())):
            return "non-finite MuJoCo state"
        return None
