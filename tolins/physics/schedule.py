"""One control period in physics steps: which control periods are allowed, how many physics
steps make one, and after which of them the contact force is read."""

from __future__ import annotations

from typing import TYPE_CHECKING

from tolins.geometry.validation import check_int, check_real
from tolins.mjcf.model import TIMESTEP
from tolins.paper import CONTROL_DT

if TYPE_CHECKING:
    import mujoco

#: Longest control period (s): four times the paper's.
MAX_CONTROL_DT = 1.0
#: Shortest control period (s): two physics steps. The servos are re-anchored at the start
#: of every control step and push only from the second physics step on, so in one step the
#: workpiece cannot move. Of the commanded motion they cover 10 % at 2 ms, 55 % at 10 ms
#: and 98 % at 0.25 s (about ``1 - 4.7 ms / control_dt`` from 10 ms on;
#: benchmarks/servo_tracking.py).
MIN_PHYSICS_STEPS = 2
MIN_CONTROL_DT = MIN_PHYSICS_STEPS * TIMESTEP
#: Contact-force reads per control step: five, as long as a step has five physics steps.
CONTACT_CHECKS = 5


def check_control_dt(control_dt: object) -> float:
    """``control_dt`` (s) if finite, in ``[MIN_CONTROL_DT, MAX_CONTROL_DT]`` and a whole number
    of MuJoCo physics steps (:data:`~tolins.mjcf.model.TIMESTEP`); the same rule on every
    simulator."""
    allowed = (
        f"a multiple of the {TIMESTEP} s physics step in [{MIN_CONTROL_DT}, {MAX_CONTROL_DT}] s "
        f"(the paper's: {CONTROL_DT}; in one physics step the servos cannot move)"
    )
    value = check_real("control_dt", control_dt, allowed)
    steps = round(value / TIMESTEP)
    if (
        not MIN_PHYSICS_STEPS <= steps <= MAX_CONTROL_DT / TIMESTEP
        or abs(steps * TIMESTEP - value) > 1e-9
    ):
        raise ValueError(f"control_dt={control_dt!r} is not allowed; allowed: {allowed}")
    return value


def physics_steps(model: mujoco.MjModel, control_dt: float) -> int:
    """How many physics steps of ``model`` make one control period; ``ValueError`` for a
    ``control_dt`` that :func:`check_control_dt` refuses."""
    return round(check_control_dt(control_dt) / model.opt.timestep)


def default_contact_checks(substeps: int) -> int:
    """Contact-force reads per control step of ``substeps`` physics steps: ``min(5, substeps)``
    (the 250 steps of the paper's 0.25 s: five reads, 50 steps apart)."""
    return min(CONTACT_CHECKS, substeps)


def control_plan(
    model: mujoco.MjModel, control_dt: float, contact_checks: int | None = None
) -> tuple[int, int]:
    """``(physics steps, contact reads)`` of one control step of ``model``: the steps of
    ``control_dt`` (:func:`physics_steps`) and ``contact_checks`` reads, default
    :func:`default_contact_checks`, checked to lie in 1 … the steps."""
    substeps = physics_steps(model, control_dt)
    if contact_checks is None:
        contact_checks = default_contact_checks(substeps)
    return substeps, check_int("contact_checks", contact_checks, minimum=1, maximum=substeps)


def contact_chunks(nstep: int, checks: int) -> list[int]:
    """The physics steps between the contact reads of one control step: ``checks`` chunks
    of ``nstep // checks`` steps, the first ``nstep % checks`` one step longer, empty ones
    dropped (every MuJoCo stepper's schedule)."""
    chunk, extra = divmod(nstep, checks)
    return [n for n in (chunk + (i < extra) for i in range(checks)) if n]
