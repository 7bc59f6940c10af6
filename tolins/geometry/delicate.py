"""Delicate pins: the settings of pins that bend and stay bent, and their beams.

``pins="rigid"`` (the default) keeps the pins of every model rigid. ``pins="elastic-plastic"``
makes each round pin a cantilever of a :class:`~tolins.geometry.materials.PinMaterial`
(elastic up to its yield moment, then perfectly plastic: a bend that stays). Its
:class:`ElasticPins` is what the model generator and the simulator read; :func:`pin_beams`
gives each pin's beam in model units (mm, kg, s: mN, mN·mm). numpy only.

A polygon peg is refused: it is a solid section, far too stiff to bend under the servos'
force (:func:`peg_refusal` gives the numbers).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tolins.geometry import materials as mt
from tolins.geometry.specs import CircularSocket, SocketSpec, inradius
from tolins.geometry.validation import check_real
from tolins.geometry.workspace import PIN_LENGTH

#: The pin models a task may take.
PIN_MODELS = ("rigid", "elastic-plastic")
#: The default material of elastic-plastic pins.
DEFAULT_MATERIAL = "phosphor_bronze"
#: The servos' force limit (N): what a policy can push a pin with.
SERVO_FORCE = 5.0
#: The largest ``damage_penalty`` (the paper's success reward is 100).
MAX_DAMAGE_PENALTY = 1000.0


@dataclass(frozen=True)
class ElasticPins:
    """Elastic–perfectly plastic round pins.

    Attributes:
        material: The pins' material.
        damage_threshold: Permanent tip offset (mm) from which a pin counts as damaged.
        damage_penalty: The reward given on the step a pin becomes damaged, which then
            ends the episode, or ``None``: damage is only reported (the default).
    """

    material: mt.PinMaterial
    damage_threshold: float
    damage_penalty: float | None = None


def bent_beyond(bend: np.ndarray, threshold: float) -> bool:
    """Whether some pin's permanent tip offset in ``bend`` ``(n_pins, 2)`` (mm) reaches
    ``threshold`` (mm): a damaged part (:attr:`ElasticPins.damage_threshold`)."""
    return bool(np.max(np.hypot(bend[:, 0], bend[:, 1])) >= threshold)


@dataclass(frozen=True)
class PinBeams:
    """Each pin's beam, ``(n_pins,)`` arrays in model units.

    Attributes:
        length: Free length L (mm): root (the carrier) to tip.
        diameter: Diameter d (mm).
        k_theta: Root stiffness 3EI/L (mN·mm/rad).
        yield_moment: M_y (mN·mm).
        mass: Pin mass (kg).
        inertia: Moment of inertia about the root (kg·mm²).
    """

    length: np.ndarray
    diameter: np.ndarray
    k_theta: np.ndarray
    yield_moment: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray

    @property
    def yield_rotation(self) -> np.ndarray:
        """Root rotation at first yield, M_y / k_θ (rad)."""
        return self.yield_moment / self.k_theta


def pin_beams(spec: CircularSocket, material: mt.PinMaterial) -> PinBeams:
    """The beams of ``spec``'s pins (burrs and shortenings included) of ``material``."""
    lengths = PIN_LENGTH - spec.shortenings
    diameters = 2.0 * spec.pin_radii
    rows = [
        (
            mt.root_stiffness(material, d, L),
            mt.yield_moment(material, d),
            mt.pin_mass(material, d, L),
            mt.root_inertia(material, d, L),
        )
        for d, L in zip(diameters.tolist(), lengths.tolist(), strict=True)
    ]
    k, m_y, mass, inertia = (np.array(column) for column in zip(*rows, strict=True))
    return PinBeams(lengths, diameters, k, m_y, mass, inertia)


def peg_refusal(spec: SocketSpec) -> str:
    """Why a polygon peg does not bend: its inscribed round section's tip deflection under
    the servos' force and the tip load at which it would yield, in the default material."""
    d = 2.0 * inradius(spec.sides, spec.pin_circumradius)
    material = mt.MATERIALS[DEFAULT_MATERIAL]
    deflection = SERVO_FORCE * 1e3 / mt.tip_stiffness(material, d, PIN_LENGTH) * 1e3
    yield_load = mt.yield_tip_load(material, d, PIN_LENGTH) * 1e-3
    return (
        f"a solid {d:g} mm peg, {PIN_LENGTH:g} mm long, in {DEFAULT_MATERIAL} bends "
        f"{deflection:.1f} µm under the servos' {SERVO_FORCE:g} N and yields only at "
        f"{yield_load:.1f} N at its tip: it does not bend"
    )


def check_pins(
    socket: SocketSpec,
    pins: object,
    material: object,
    damage_threshold: object,
    damage_penalty: object = None,
) -> ElasticPins | None:
    """The elastic-plastic pins of the settings ``pins``, ``pin_material``,
    ``damage_threshold`` and ``damage_penalty``, or ``None`` for rigid pins; one-line
    ``ValueError`` naming the setting and what is allowed otherwise."""
    if not isinstance(pins, str) or pins not in PIN_MODELS:
        raise ValueError(f"pins={pins!r}; allowed: {', '.join(map(repr, PIN_MODELS))}")
    if pins == "rigid":
        given = (
            ("pin_material", material),
            ("damage_threshold", damage_threshold),
            ("damage_penalty", damage_penalty),
        )
        for name, value in given:
            if value is not None:
                raise ValueError(
                    f"{name}={value!r} applies to bending pins only; allowed: "
                    f"pins='elastic-plastic', or {name}=None with rigid pins"
                )
        return None
    if not isinstance(socket, CircularSocket):
        raise ValueError(
            f"pins={pins!r} is for round pins (a CircularSocket) only; {peg_refusal(socket)}"
        )
    resolved = mt.pin_material(DEFAULT_MATERIAL if material is None else material)
    clearance = socket.clearance
    allowed = f"0 < damage_threshold ≤ {clearance:g} mm (the radial clearance)"
    if damage_threshold is None:
        threshold = clearance / 2
    else:
        threshold = check_real("damage_threshold", damage_threshold, allowed)
        if not 0.0 < threshold <= clearance:
            raise ValueError(
                f"damage_threshold={damage_threshold!r} is out of range; allowed: {allowed}"
            )
    penalty = None
    if damage_penalty is not None:
        allowed = f"0 < damage_penalty ≤ {MAX_DAMAGE_PENALTY:g} (a reward of -damage_penalty)"
        penalty = check_real("damage_penalty", damage_penalty, allowed)
        if not 0.0 < penalty <= MAX_DAMAGE_PENALTY:
            raise ValueError(
                f"damage_penalty={damage_penalty!r} is out of range; allowed: {allowed}"
            )
    return ElasticPins(resolved, threshold, penalty)
