"""The plastic set of elastic-plastic pins and its return mapping (``pins="elastic-plastic"``).

Each pin of a model made with :func:`tolins.make_mjcf`'s ``elastic`` turns on two root
hinges whose joint equalities (:mod:`tolins.mjcf.elastic_pins`) pull them towards the
pin's plastic set θp, held in the model's ``eq_data[:, 0]``. After a physics step the
elastic rotation ``e = q − θp`` of a pin whose root moment ``k_θ |e|`` exceeds its yield
moment (``|e| > θ_y = M_y/k_θ``; a round section yields alike in every direction) is
returned radially onto the yield surface: ``θp += e (1 − θ_y/|e|)``, so the pin keeps
what went beyond yield as a permanent bend (elastic, perfectly plastic).

The mapping must follow every physics step in which a pin may yield (``benchmarks/
pin_beam.py``: every 5 steps overshoots the yield load by 12 %, every 50 by 42 %), but
steps in which no pin can reach yield may run as one ``mj_step(m, d, n)``:
:func:`safe_steps` bounds how many, from each pin's distance to yield and a bound on how
fast its elastic rotation can grow (the fastest its tip can move, over its length, plus
its hinges' speed now). :class:`ServoStepper <tolins.physics.servo.ServoStepper>` steps
in such chunks and calls :meth:`PinPlasticity.update` after each.

The kernels are plain loops, compiled with numba where it is installed (``tolins[robot]``)
when the first :class:`PinPlasticity` is made (bit-identical to their Python run: the same
operations in the same order), the GIL released.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import mujoco
import numpy as np

from tolins.mjcf.elastic_pins import tip_offsets
from tolins.mjcf.layout import ElasticPinLayout

#: Safety factor on how fast a pin's tip moves with the workpiece (the servos' overshoot
#: within a chunk, a pin's own ringing).
SPEED_MARGIN = 2.0


def return_mapping(
    qpos: np.ndarray,
    hinges: np.ndarray,
    theta_y: np.ndarray,
    plastic: np.ndarray,
    eq_data: np.ndarray,
    equalities: np.ndarray,
) -> None:
    """Return every pin beyond yield onto its yield surface, in place: ``plastic`` ``(n,
    2)`` and the equalities' ``eq_data[:, 0]``."""
    for i in range(hinges.shape[0]):
        ex = qpos[hinges[i, 0]] - plastic[i, 0]
        ey = qpos[hinges[i, 1]] - plastic[i, 1]
        size = math.sqrt(ex * ex + ey * ey)
        if size > theta_y[i]:
            scale = 1.0 - theta_y[i] / size
            plastic[i, 0] += ex * scale
            plastic[i, 1] += ey * scale
            eq_data[equalities[i, 0], 0] = plastic[i, 0]
            eq_data[equalities[i, 1], 0] = plastic[i, 1]


def safe_steps(
    qpos: np.ndarray,
    qvel: np.ndarray,
    ctrl: np.ndarray,
    hinges: np.ndarray,
    dofs: np.ndarray,
    theta_y: np.ndarray,
    plastic: np.ndarray,
    reach: np.ndarray,
    lengths: np.ndarray,
    timestep: float,
    most: int,
) -> int:
    """How many physics steps (1 … ``most``) may run before the next return mapping: no pin
    reaches yield within them. A pin's elastic rotation grows at most as fast as its tip
    moves against what it touches, over its length: :data:`SPEED_MARGIN` times the
    workpiece's speed there (each joint at the larger of its speed now and its command:
    slides x, y, z, then the hinge about z at the pin's ``reach``), plus its hinges' speed
    now."""
    linear = 0.0
    for j in range(3):
        linear += max(abs(qvel[j]), abs(ctrl[j])) ** 2
    linear = math.sqrt(linear)
    turn = max(abs(qvel[3]), abs(ctrl[3]))
    steps = most
    for i in range(hinges.shape[0]):
        ex = qpos[hinges[i, 0]] - plastic[i, 0]
        ey = qpos[hinges[i, 1]] - plastic[i, 1]
        left = theta_y[i] - math.sqrt(ex * ex + ey * ey)
        speed = SPEED_MARGIN * (linear + turn * reach[i]) / lengths[i]
        speed += math.sqrt(qvel[dofs[i, 0]] ** 2 + qvel[dofs[i, 1]] ** 2) + 1e-9
        allowed = int(left / (speed * timestep)) if left > 0.0 else 0
        if allowed < steps:
            steps = allowed
    return max(steps, 1)


@functools.cache
def kernels() -> tuple[Callable[..., None], Callable[..., int]]:
    """:func:`return_mapping` and :func:`safe_steps`, compiled with numba where it is
    installed (imported here, on first use, so that ``import tolins`` does not load it),
    else as they are."""
    try:
        import numba
    except ImportError:  # numba comes with tolins[robot]
        return return_mapping, safe_steps
    jit = numba.njit(cache=True, nogil=True)
    return jit(return_mapping), jit(safe_steps)


class PinPlasticity:
    """The plastic set of a model's elastic-plastic pins (one simulation).

    Args:
        model: A model with elastic-plastic pins; its ``eq_data`` holds this simulation's
            plastic set, so each simulation needs its own model.
        pins: Where its pins are (:func:`~tolins.mjcf.layout.elastic_pin_layout`).
    """

    def __init__(self, model: mujoco.MjModel, pins: ElasticPinLayout) -> None:
        self.model, self.layout = model, pins
        self.hinges = pins.hinges
        joints = np.searchsorted(model.jnt_qposadr, self.hinges)
        self.dofs = model.jnt_dofadr[joints].astype(np.intp)
        self.equalities = pins.equalities
        self.theta_y = np.ascontiguousarray(pins.yield_rotation, dtype=float)
        self.lengths = np.asarray(pins.length, dtype=float)
        # Each pin's farthest point from the axis of the workpiece's hinge about z (mm).
        roots = model.body_pos[model.jnt_bodyid[joints[:, 0]], :2]
        self.reach = np.hypot(roots[:, 0], roots[:, 1]) + self.lengths
        self.plastic = np.zeros((len(self.hinges), 2))
        kernels()  # numba imported now, not in the first step

    def on(self, model: mujoco.MjModel) -> PinPlasticity:
        """These pins on ``model`` (itself if it is theirs, else a new one with their
        plastic set): a simulation whose model changed keeps its part's bends."""
        if model is self.model:
            return self
        moved = PinPlasticity(model, self.layout)
        moved.assign(self.plastic)
        return moved

    def assign(self, plastic: np.ndarray | None = None) -> None:
        """Set the plastic set ``(n_pins, 2)`` (rad; ``None``: straight pins)."""
        self.plastic = np.zeros_like(self.plastic) if plastic is None else np.array(plastic)
        self.model.eq_data[self.equalities, 0] = self.plastic

    def place(self, qpos: np.ndarray, qvel: np.ndarray) -> None:
        """Put every pin at rest at its plastic set in a simulation's ``qpos`` and ``qvel``
        (after its reset)."""
        qpos[self.hinges] = self.plastic
        qvel[self.dofs] = 0.0

    def hold(self, qpos: np.ndarray, qvel: np.ndarray) -> np.ndarray:
        """Stop every pin (its hinges' speed in a simulation's ``qvel`` to zero) for steps in
        which its model holds them (:func:`~tolins.physics.servo.pins_held`); returns their
        hinges' angles, for :meth:`release`."""
        qvel[self.dofs] = 0.0
        return qpos[self.hinges].copy()

    def release(self, qpos: np.ndarray, qvel: np.ndarray, angles: np.ndarray) -> None:
        """After steps that held them, every pin exactly at ``angles`` (from :meth:`hold`),
        at rest."""
        qpos[self.hinges] = angles
        qvel[self.dofs] = 0.0

    def steps(self, qpos: np.ndarray, qvel: np.ndarray, ctrl: np.ndarray, most: int) -> int:
        """:func:`safe_steps` of a simulation's ``qpos``, ``qvel`` and ``ctrl``."""
        return kernels()[1](
            qpos,
            qvel,
            ctrl,
            self.hinges,
            self.dofs,
            self.theta_y,
            self.plastic,
            self.reach,
            self.lengths,
            self.model.opt.timestep,
            most,
        )

    def update(self, qpos: np.ndarray) -> None:
        """The return mapping after a physics step that left the simulation at ``qpos``."""
        kernels()[0](
            qpos, self.hinges, self.theta_y, self.plastic, self.model.eq_data, self.equalities
        )

    def bend(self) -> np.ndarray:
        """Each pin's permanent tip offset ``(n_pins, 2)`` (mm, workpiece frame)."""
        return tip_offsets(self.plastic, self.lengths)

    def deflection(self, qpos: np.ndarray) -> np.ndarray:
        """Each pin's tip offset at ``qpos`` ``(n_pins, 2)`` (mm, workpiece frame), elastic
        included."""
        return tip_offsets(qpos[self.hinges], self.lengths)


def pin_states(
    plasticity: list[PinPlasticity], qpos: list[np.ndarray], n_pins: int
) -> tuple[np.ndarray, np.ndarray]:
    """Each simulation's pins' permanent tip offsets and their tip offsets now, elastic
    included, ``(n, n_pins, 2)`` each (mm, workpiece frame), from its ``plasticity`` and
    ``qpos``."""
    n = len(plasticity)
    bends = np.array([p.bend() for p in plasticity]).reshape(n, n_pins, 2)
    deflections = [p.deflection(q) for p, q in zip(plasticity, qpos, strict=True)]
    return bends, np.array(deflections).reshape(n, n_pins, 2)
