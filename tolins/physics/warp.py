"""Contact physics of many workpieces at once on MuJoCo Warp (GPU, or Warp's CPU device).

:class:`WarpBatch` is the :class:`~tolins.physics.protocol.BatchPhysics` of the vector env on
``mujoco_warp``: the model :func:`tolins.make_mjcf` writes, put on the device as one
``mjw.Model`` with ``nworld = num_envs`` worlds, stepped by the control step every MuJoCo
simulator of tolins shares, :func:`~tolins.physics.servo.servo_control_step` (servo
set-points re-anchored ``act = qpos``, ``contact_checks`` chunks of physics steps, the
summed pin touch force read after each for ``peak_force``; the wrench from the
force/torque sensors), always on the contact step: the worlds step in lockstep. Physics
steps run as a captured Warp graph (a CUDA graph on a GPU, Warp's replayed CPU graph on
``"cpu"``): on the CPU device a captured step is about 10× faster than launching its ~120
kernels from Python.

How it differs from C MuJoCo (``docs/backends.md`` has the measured consequences): float32
arithmetic; the solver tolerance is clamped to ≥ 1e-6 (ours is 1e-10); contacts and
constraint rows live in fixed buffers (``nconmax`` per world, ``njmax`` rows per world),
sized here from the socket: pins × :data:`CONTACTS_PER_PIN`; an overflow is a fault.

**Subsets.** Warp steps every world at once. A call on a subset steps all worlds and then
writes the saved state (``qpos, qvel, act, ctrl, qacc_warmstart, time, sensordata,
overflow``) back into the others, so they do not move: exactly, bit for bit (tested).

**Per-world workpieces** (bent pins). ``mjw.put_model`` can give a model field one row
per world (``batch_sizes``). The fields that a bent pin changes in the compiled model
(:func:`tolins.mjcf.bend_fields`: pin geom and site positions, the board body's inertia,
the board pieces' sizes), those that Warp can batch, are held with ``num_envs`` rows, and
:meth:`WarpBatch.set_socket` writes the rows of the model the single env would compile for
that workpiece. A workpiece whose model differs in any other field is refused.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import mujoco
import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int
from tolins.mjcf import FORCE_SCALE, bend_fields, model_layout
from tolins.physics.compiled import model_builder
from tolins.physics.protocol import BatchState, Capabilities
from tolins.physics.schedule import control_plan
from tolins.physics.servo import servo_control_step
from tolins.physics.versions import PhysicsVersion

_INSTALL = "pip install 'tolins[warp]'"
#: Contact buffer per pin and world (at least :data:`MIN_CONTACTS`). The most contacts on
#: one pin that C MuJoCo made in random pushes, tilts and jams (12 episodes of 6 steps each
#: of 2*2, 2*8, square and hexagon sockets) were 6 (round pins), 10 (square peg: box-box),
#: 4 (hexagon); twice the round pins' 6 leaves room for Warp's own narrowphase.
CONTACTS_PER_PIN = 12
MIN_CONTACTS = 16
#: Constraint rows per contact: condim 3, elliptic cone.
ROWS_PER_CONTACT = 3


def _import_warp() -> tuple[Any, Any]:
    """``(warp, mujoco_warp)``, or an ImportError that names the install line."""
    try:
        import mujoco_warp as mjw
        import warp as wp
    except ImportError as error:
        raise ImportError(
            f"backend='warp' needs mujoco-warp and warp-lang ({error}); install them with "
            f"{_INSTALL}"
        ) from error
    return wp, mjw


def _device(wp: Any, device: str) -> Any:
    """Warp's device ``device``, or a ValueError naming the devices this machine has."""
    wp.init()
    available = [d.alias for d in wp.get_devices()]
    if device not in available:
        raise ValueError(
            f"device={device!r} is not available on this machine; allowed: "
            f"{', '.join(map(repr, available))} (a CUDA device needs an NVIDIA GPU and driver)"
        )
    return wp.get_device(device)


def _differing_fields(a: mujoco.MjModel, b: mujoco.MjModel, names: set[str]) -> list[str]:
    """The array fields of ``names`` whose values differ between models ``a`` and ``b``."""
    return sorted(n for n in names if not np.array_equal(getattr(a, n), getattr(b, n)))


def _model_arrays(model: mujoco.MjModel) -> set[str]:
    """Names of ``model``'s array fields."""
    return {
        n
        for n in dir(model)
        if not n.startswith("_") and isinstance(getattr(model, n, None), np.ndarray)
    }


#: Overflow bits that make a world's step invalid (solver iteration limits are not faults,
#: as in C MuJoCo).
_FAULT_BITS = {
    "NEFC": 1 << 0,
    "NJMAX_NNZ": 1 << 1,
    "BROADPHASE": 1 << 2,
    "NARROWPHASE": 1 << 3,
    "CCD": 1 << 4,
    "EPA_HORIZON": 1 << 8,
}
#: The state of a world that its next step reads, and what a caller reads after a step.
_STATE = ("qpos", "qvel", "act", "ctrl", "qacc_warmstart", "time", "sensordata", "overflow")


class WarpBatch(Capabilities):
    """``num_envs`` worlds of one socket family on MuJoCo Warp (see the module docstring).

    Its worlds take bent pins (``defect_sigma``) only: no ``defects`` kind, no randomised
    physics, and they are not drawn.

    Args:
        socket: The nominal socket; every world starts with it.
        num_envs: Number of worlds.
        control_dt: Control period (s), as the single env's.
        device: Warp's device: ``"cpu"`` or a CUDA device such as ``"cuda:0"``.
        contact_checks: Contact-force reads per control step; default as the single env.
        nconmax: Contacts per world; default pins × :data:`CONTACTS_PER_PIN` (≥ 16).
        njmax: Constraint rows per world; default ``3 * nconmax`` plus two per joint.
        physics_version: 1 or 2 (:mod:`tolins.physics.versions`): version 2's model (the
            board in the world body). Its worlds step on the contact step throughout, free
            flight included, so they follow C MuJoCo's ``-v2`` within the free-flight bound
            rather than bit for bit (Warp is compared with C MuJoCo by tolerance anyway).
    """

    supports_render = False
    supports_randomization = False
    supports_touch_points = False
    defect_kinds = frozenset()
    batch_options = frozenset({"device"})

    def __init__(
        self,
        socket: SocketSpec,
        num_envs: int,
        control_dt: float,
        device: str = "cpu",
        contact_checks: int | None = None,
        nconmax: int | None = None,
        njmax: int | None = None,
        physics_version: int | PhysicsVersion = 1,
    ) -> None:
        self._build = model_builder(physics_version)
        wp, mjw = _import_warp()
        self._wp, self._mjw = wp, mjw
        self.device = _device(wp, device)
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        self.socket = socket
        self.model = self._build(socket)
        self.substeps, self.checks = control_plan(self.model, control_dt, contact_checks)
        self.layout = model_layout(self.model)
        self.n_pins = self.layout.n_pins
        if nconmax is None:
            nconmax = max(MIN_CONTACTS, self.n_pins * CONTACTS_PER_PIN)
        self.nconmax = check_int("nconmax", nconmax, minimum=1)
        if njmax is None:
            njmax = ROWS_PER_CONTACT * self.nconmax + 2 * self.model.njnt
        self.njmax = check_int("njmax", njmax, minimum=1)
        self._sockets: list[SocketSpec] = [socket] * self.num_envs
        with wp.ScopedDevice(self.device):
            self.per_world_fields = self._per_world_fields()
            sizes = dict.fromkeys(self.per_world_fields, self.num_envs)
            self.m = mjw.put_model(self.model, batch_sizes=sizes)
            self.m.opt.warn_overflow = sum(_FAULT_BITS.values())
            self.d = mjw.make_data(
                self.model, nworld=self.num_envs, nconmax=self.nconmax, njmax=self.njmax
            )
        self._graph_steps = 1 if self.device.is_cpu else 0  # 0: one graph per chunk length
        self._graphs: dict[int, Any] = {}

    def _per_world_fields(self) -> list[str]:
        """The Warp model fields a bent pin changes (one row per world), see the module."""
        batchable = {
            f.name
            for f in dataclasses.fields(self._mjw.Model)
            if getattr(f.type, "shape", ())[:1] == ("*",)
        }
        return sorted(set(bend_fields(self.socket)) & batchable & _model_arrays(self.model))

    def set_socket(self, index: int, socket: SocketSpec) -> None:
        if socket is self._sockets[index]:
            return
        model = self._build(socket)
        shared = _model_arrays(self.model) - set(self.per_world_fields) - {"bvh_aabb", "dof_length"}
        other = [
            n for n in _differing_fields(self.model, model, shared) if not n.startswith("name")
        ]
        if other:
            raise ValueError(
                f"socket {socket!r} changes model fields that the Warp batch shares between "
                f"worlds ({', '.join(other)}); allowed: workpieces of the batch's family that "
                f"differ only in {', '.join(self.per_world_fields) or 'nothing'}"
            )
        for name in self.per_world_fields:
            array = getattr(self.m, name)
            rows = array.numpy()
            rows[index] = getattr(model, name).reshape(rows.shape[1:])
            array.assign(rows)
        self._sockets[index] = socket

    def reset(
        self, ids: np.ndarray, poses: np.ndarray, keep_part: np.ndarray | None = None
    ) -> BatchState:
        wp, mjw = self._wp, self._mjw
        ids = np.asarray(ids, dtype=np.intp)
        mask = np.zeros(self.num_envs, dtype=bool)
        mask[ids] = True
        saved = self._save()
        with wp.ScopedDevice(self.device):
            mjw.reset_data(self.m, self.d, reset=wp.array(mask, dtype=bool))
            qpos = self.d.qpos.numpy()
            qpos[ids] = np.asarray(poses, dtype=float)[:, self.layout.joint_pose]
            self.d.qpos.assign(qpos)
            self.d.act.assign(qpos)
            mjw.forward(self.m, self.d)
        self._restore(saved, ~mask)
        sensordata = self.d.sensordata.numpy()[ids]
        force = sensordata[:, self.layout.touch].astype(float).sum(axis=1) * FORCE_SCALE
        return self._state(ids, force, None)

    def step(self, ids: np.ndarray, velocities: np.ndarray) -> BatchState:
        ids = np.asarray(ids, dtype=np.intp)
        mask = np.zeros(self.num_envs, dtype=bool)
        mask[ids] = True
        saved = self._save() if not mask.all() else None
        ctrl = self.d.ctrl.numpy()
        ctrl[ids] = np.asarray(velocities, dtype=float)[:, self.layout.joint_pose]
        self.d.ctrl.assign(ctrl)
        peak, faults = servo_control_step(_Worlds(self, ids), self.substeps, self.checks)
        if saved is not None:
            self._restore(saved, ~mask)
        return self._state(ids, peak * FORCE_SCALE, faults)

    def _touch(self, ids: np.ndarray) -> np.ndarray:
        """The summed pin touch force of worlds ``ids`` now (model units)."""
        return self.d.sensordata.numpy()[ids][:, self.layout.touch].astype(float).sum(axis=1)

    def _advance(self, nstep: int) -> None:
        """``nstep`` physics steps of every world, through captured graphs (of one step on
        the CPU device, of the whole chunk on a GPU)."""
        wp, mjw = self._wp, self._mjw
        length = self._graph_steps or nstep
        with wp.ScopedDevice(self.device):
            if length not in self._graphs:
                mjw.step(self.m, self.d)  # loads every kernel; a capture does not step
                nstep -= 1
                with wp.ScopedCapture() as capture:
                    for _ in range(length):
                        mjw.step(self.m, self.d)
                self._graphs[length] = capture.graph
            for _ in range(nstep // length):
                wp.capture_launch(self._graphs[length])
            for _ in range(nstep % length):
                mjw.step(self.m, self.d)

    def _save(self) -> dict[str, np.ndarray]:
        """A copy of every world's state (``numpy()`` of a CPU array is a view)."""
        return {name: getattr(self.d, name).numpy().copy() for name in _STATE}

    def _restore(self, saved: dict[str, np.ndarray], keep: np.ndarray) -> None:
        """Write ``saved`` back into the worlds of the mask ``keep``."""
        if not keep.any():
            return
        for name, before in saved.items():
            array = getattr(self.d, name)
            now = array.numpy()
            now[keep] = before[keep]
            array.assign(now)

    def _faults(self, ids: np.ndarray) -> tuple[str | None, ...]:
        """Per world of ``ids``: a buffer overflow, a non-finite state, or ``None``."""
        overflow = self.d.overflow.numpy()[ids]
        state = np.concatenate([self.d.qpos.numpy()[ids], self.d.qvel.numpy()[ids]], axis=1)
        finite = np.isfinite(state).all(axis=1)
        errors: list[str | None] = []
        for bits, ok in zip(overflow.tolist(), finite.tolist(), strict=True):
            raised = [name for name, bit in _FAULT_BITS.items() if bits & bit]
            if raised:
                errors.append(
                    f"MuJoCo Warp buffer overflow during the step: {', '.join(raised)} "
                    f"(nconmax={self.nconmax}, njmax={self.njmax}; raise them)"
                )
            elif not ok:
                errors.append("non-finite MuJoCo Warp state")
            else:
                errors.append(None)
        return tuple(errors)

    def _state(
        self, ids: np.ndarray, peak_force: np.ndarray, errors: tuple[str | None, ...] | None
    ) -> BatchState:
        layout = self.layout
        qpos = self.d.qpos.numpy()[ids].astype(float)
        sensordata = self.d.sensordata.numpy()[ids].astype(float)
        theta = qpos[:, layout.pose_joint[2]]
        fx, fy, fz = sensordata[:, layout.force].T
        c, s = np.cos(theta), np.sin(theta)
        wrench = np.stack(
            [s * fy - c * fx, -s * fx - c * fy, -sensordata[:, layout.torque_z], -fz], axis=1
        )
        return BatchState(qpos[:, layout.pose_joint], wrench * FORCE_SCALE, peak_force, errors)

    def close(self) -> None:
        """Release the device buffers and graphs."""
        self._graphs.clear()
        self.m = self.d = None


class _Worlds:
    """Worlds ``ids`` of a :class:`WarpBatch` as the simulations one
    :func:`~tolins.physics.servo.servo_control_step` drives. All worlds step at once, so
    they stay on the contact step (no free flight), and a fault is read from Warp's
    overflow bits and the state (MuJoCo Warp counts no warnings)."""

    def __init__(self, batch: WarpBatch, ids: np.ndarray) -> None:
        self.batch, self.ids = batch, ids

    def warning_counts(self) -> list[int]:
        return []

    def anchor(self) -> None:
        self.batch.d.act.assign(self.batch.d.qpos.numpy())

    def choose_steps(self, chunks: list[int]) -> None:
        pass

    def no_force(self) -> np.ndarray:
        return np.zeros(len(self.ids))

    def physics_steps(self, n: int) -> None:
        self.batch._advance(n)

    def higher_force(self, peak: np.ndarray) -> np.ndarray:
        return np.maximum(peak, self.batch._touch(self.ids))

    def faults(self, warnings_before: list[int]) -> tuple[str | None, ...]:
        return self.batch._faults(self.ids)
