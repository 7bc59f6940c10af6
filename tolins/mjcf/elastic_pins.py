"""Elastic-plastic round pins in MJCF: each pin its own body on two root hinges.

Mechanism chosen by measurement (``benchmarks/pin_beam.py``, docs/delicate.md): pin ``i``
is a rigid cylinder in a body ``pin{i}_root`` at its root (the carrier's underside, ``z =``
:data:`~tolins.geometry.workspace.PIN_LENGTH`) on hinges ``pin{i}_bx`` and ``pin{i}_by``
(axes x and y of the workpiece). Each hinge is held by a joint equality ``pin{i}_b?_eq``,
``hinge = polycoef[0]`` (the plastic set, which the simulator's return mapping moves in
``eq_data[:, 0]``), with a direct (negative) ``solref`` and an impedance ``solimp`` that make
it a spring of the cantilever's root stiffness k_θ = 3EI/L with damping ratio
:data:`ZETA`, on an effective inertia J_eff = :data:`EFFECTIVE_SCALE`·k_θ·dt² that keeps it
stable at the model's physics step dt (ω·dt = 0.82); :data:`ARMATURE_SHARE` of J_eff is the
hinges' armature. A soft constraint's force is −(k r + b v + J d/(1 − d) a) with J the
hinge's own inertia (pin and armature) and d its impedance, so d = 1 − J/J_eff and

    solref = (−k_θ/J_eff, −2ζ·sqrt(k_θ/J_eff)),  solimp = (d, d, 0.001, 0.5, 2).

The pin's explicit ``<inertial>`` is its own (the ``pin`` class's default density in mm
units would make it about 1,000 kg); its tip site and touch zone are in its body, so the
sensors follow the bend. Each pin's yield rotation and length are in the model as
``<custom>`` numerics (:data:`YIELD_ROTATION`, :data:`LENGTH`), so a compiled model says
all that its simulator needs.
"""

from __future__ import annotations

import math

import numpy as np

from tolins.geometry.delicate import ElasticPins, pin_beams
from tolins.geometry.specs import CircularSocket
from tolins.geometry.workspace import PIN_LENGTH
from tolins.mjcf.xml import num, nums

#: J_eff / (k_θ dt²): ω·dt = 1/sqrt(1.5) = 0.82, inside the explicit damping's stability
#: limit 1.24 at ζ = 0.5 (``benchmarks/pin_beam.py``, "Stability").
EFFECTIVE_SCALE = 1.5
#: The hinges' armature as a share of J_eff (0.3 chatters at 10 mm/s impacts).
ARMATURE_SHARE = 0.1
#: Damping ratio of the pin's spring.
ZETA = 0.5
#: The hinges of each pin, ``(suffix, axis)``: rotation about x moves the tip along +y.
HINGES = (("bx", "1 0 0"), ("by", "0 1 0"))
#: The model's ``<custom>`` numerics the simulator reads: each pin's root rotation at first
#: yield, M_y/k_θ (rad), and its free length (mm).
YIELD_ROTATION = "pin_yield_rotation"
LENGTH = "pin_length"


def hinge_name(pin: int, suffix: str) -> str:
    """Name of pin ``pin``'s root hinge ``suffix`` (``bx`` or ``by``)."""
    return f"pin{pin}_{suffix}"


def equality_name(pin: int, suffix: str) -> str:
    """Name of the joint equality that holds hinge ``suffix`` of pin ``pin``."""
    return f"{hinge_name(pin, suffix)}_eq"


def calibration(
    k_theta: float, inertia: float, timestep: float
) -> tuple[float, tuple[float, float], tuple[float, ...]]:
    """``(armature, solref, solimp)`` of a hinge of root stiffness ``k_theta`` (mN·mm/rad)
    and pin inertia ``inertia`` (kg·mm²) at the physics step ``timestep`` (s)."""
    effective = EFFECTIVE_SCALE * k_theta * timestep**2
    armature = ARMATURE_SHARE * effective
    d = 1.0 - (inertia + armature) / effective
    omega2 = k_theta / effective
    solref = (-omega2, -2.0 * ZETA * math.sqrt(omega2))
    return armature, solref, (d, d, 0.001, 0.5, 2.0)


def elastic_pin_bodies(
    spec: CircularSocket, pins: ElasticPins, timestep: float, zone: str
) -> tuple[list[str], list[str]]:
    """The pins' bodies (geom, tip site, touch zone of size ``zone`` each) and the
    ``<equality>`` lines that hold their hinges, for a model stepped at ``timestep``."""
    beams = pin_beams(spec, pins.material)
    bodies, equalities = [], []
    for i, ((x, y), radius) in enumerate(zip(spec.pin_centers, spec.pin_radii, strict=True)):
        L, m = float(beams.length[i]), float(beams.mass[i])
        armature, solref, solimp = calibration(
            float(beams.k_theta[i]), float(beams.inertia[i]), timestep
        )
        transverse = float(beams.inertia[i]) - m * L * L / 4  # about the centre of mass
        bodies += [
            f'<body name="pin{i}_root" pos="{nums((x, y, PIN_LENGTH))}">',
            *(
                f'<joint name="{hinge_name(i, s)}" type="hinge" axis="{axis}" '
                f'armature="{num(armature)}"/>'
                for s, axis in HINGES
            ),
            f'<inertial pos="{nums((0, 0, -L / 2))}" mass="{num(m)}" '
            f'diaginertia="{nums((transverse, transverse, m * radius**2 / 2))}"/>',
            f'<geom name="pin{i}" class="pin" type="cylinder" pos="{nums((0, 0, -L / 2))}" '
            f'size="{nums((radius, L / 2))}"/>',
            f'<site name="pin{i}_tip" pos="{nums((0, 0, -L))}" size="0.05"/>',
            f'<site name="pin{i}_zone" type="box" pos="{nums((0, 0, -PIN_LENGTH / 2))}" '
            f'size="{zone}" rgba="0 0 0 0"/>',
            "</body>",
        ]
        equalities += [
            f'<joint name="{equality_name(i, s)}" joint1="{hinge_name(i, s)}" '
            f'polycoef="0 0 0 0 0" solref="{nums(solref)}" solimp="{nums(solimp)}"/>'
            for s, _ in HINGES
        ]
    custom = [
        "<custom>",
        f'<numeric name="{YIELD_ROTATION}" data="{nums(beams.yield_rotation)}"/>',
        f'<numeric name="{LENGTH}" data="{nums(beams.length)}"/>',
        "</custom>",
    ]
    return bodies, [*custom, "<equality>", *equalities, "</equality>"]


def tip_offsets(rotations: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Tip offsets ``(n, 2)`` (mm, workpiece frame) of pins of ``lengths`` turned by root
    rotations ``(n, 2)`` ``[about x, about y]`` (rad; MuJoCo applies ``bx`` then ``by``):
    ``(-L sin b, L sin a cos b)``."""
    a, b = rotations[:, 0], rotations[:, 1]
    return np.stack([-lengths * np.sin(b), lengths * np.sin(a) * np.cos(b)], axis=1) + 0.0
