"""Pin materials and the beam formulas of a round pin (numpy-free, stdlib only).

A pin is a round cantilever of diameter ``d`` and free length ``L`` (mm), clamped in the
carrier at its root and loaded at its tip. A :class:`PinMaterial` holds the handbook values
in the units a data sheet gives them (GPa, MPa, g/cm³); the functions below return the
model's units (mm, kg, s), in which a force is kg·mm/s² = mN, a moment mN·mm
(= µN·m) and a stress mN/mm² (= kPa):

====================  ===========================  =========================
quantity              formula                      model unit
====================  ===========================  =========================
second moment         I = π d⁴ / 64                mm⁴
tip stiffness         3 E I / L³                   mN/mm
root stiffness k_θ    3 E I / L                    mN·mm/rad
yield moment M_y      σ_y π d³ / 32                mN·mm
yield tip load        M_y / L                      mN
Euler load            P_cr = π² E I / (4 L²)       mN (fixed–free column)
axial stiffness       E π d² / (4 L)               mN/mm
====================  ===========================  =========================

``k_θ = 3EI/L`` makes a rigid pin on a root hinge deflect at its tip by ``F L³ / 3EI``
under a tip load ``F``, as the cantilever does. The 0.6 mm, 4 mm phosphor-bronze pin:
k_θ ≈ 5.25e5 mN·mm/rad (32.8 N/mm at the tip), M_y ≈ 10.9 N·mm (2.73 N at the tip), Euler
load ≈ 108 N. :func:`pin_material` resolves a preset name or a mapping of user values.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from tolins.geometry.validation import check_positive, check_real

#: Model stress units (mN/mm²) per GPa and per MPa; model density (kg/mm³) per g/cm³.
PER_GPA = 1.0e6
PER_MPA = 1.0e3
PER_G_CM3 = 1.0e-6
#: Density (g/cm³) of a material given without one: the middle of the copper alloys'
#: 8.4–8.9 (a pin's mass hardly matters next to the stabilising inertia the simulator gives
#: it, ``benchmarks/pin_beam.py``).
DEFAULT_DENSITY = 8.5
#: Upper bounds that catch values in the wrong unit (Pa or psi for GPa or MPa): no metal
#: is stiffer than 1,000 GPa, stronger than 5,000 MPa or denser than 25 g/cm³.
MAX_MODULUS = 1000.0
MAX_YIELD = 5000.0
MAX_DENSITY = 25.0
#: The keys of a user material and their units.
MATERIAL_KEYS = {"youngs_modulus": "GPa", "yield_strength": "MPa", "density": "g/cm³"}
_LIMITS = {"youngs_modulus": MAX_MODULUS, "yield_strength": MAX_YIELD, "density": MAX_DENSITY}


def _check_property(field: str, value: object, key: str) -> float:
    """``value`` as a float if finite and in ``(0, limit]`` of ``key``'s unit."""
    unit, limit = MATERIAL_KEYS[key], _LIMITS[key]
    allowed = f"a finite number with 0 < value ≤ {limit:g} {unit}"
    number = check_real(field, value, allowed)
    if not 0.0 < number <= limit:
        raise ValueError(f"{field}={value!r} is out of range; allowed: {allowed}")
    return number


@dataclass(frozen=True)
class PinMaterial:
    """An isotropic, elastic–perfectly plastic pin material.

    Attributes:
        name: A preset's name (:data:`MATERIALS`) or ``"custom"``.
        youngs_modulus: Young's modulus E (GPa).
        yield_strength: Yield strength σ_y (MPa; the 0.2 % offset or 0.5 % extension
            proof stress a data sheet gives).
        density: Density (g/cm³); ``None``: :data:`DEFAULT_DENSITY`.
        source: Where the values come from (alloy, temper, standard, data sheet).
    """

    name: str
    youngs_modulus: float
    yield_strength: float
    density: float | None = None
    source: str = ""

    def __post_init__(self) -> None:
        for key in ("youngs_modulus", "yield_strength"):
            object.__setattr__(self, key, _check_property(key, getattr(self, key), key))
        if self.density is not None:
            object.__setattr__(self, "density", _check_property("density", self.density, "density"))

    @property
    def modulus(self) -> float:
        """E in model units (mN/mm²)."""
        return self.youngs_modulus * PER_GPA

    @property
    def yield_stress(self) -> float:
        """σ_y in model units (mN/mm²)."""
        return self.yield_strength * PER_MPA

    @property
    def mass_density(self) -> float:
        """Density in model units (kg/mm³); :data:`DEFAULT_DENSITY` when none is given."""
        return (DEFAULT_DENSITY if self.density is None else self.density) * PER_G_CM3


#: Preset materials of IC pins and connector contacts (typical values; tempers vary).
MATERIALS: dict[str, PinMaterial] = {
    "phosphor_bronze": PinMaterial(
        "phosphor_bronze",
        youngs_modulus=110.0,
        yield_strength=515.0,
        density=8.86,
        source=(
            "Phosphor bronze UNS C51000 (CuSn5, EN CW451K), strip to ASTM B103 in temper H04 "
            "(hard): E 110 GPa (16e6 psi), yield at 0.5 % extension under load 515 MPa "
            "(75 ksi) typical, density 8.86 g/cm³ (Copper Development Association alloy "
            "data for C51000; mill data sheets give 515–560 MPa for H04)."
        ),
    ),
    "brass": PinMaterial(
        "brass",
        youngs_modulus=110.0,
        yield_strength=350.0,
        density=8.53,
        source=(
            "Cartridge brass UNS C26000 (CuZn30, EN CW505L), strip to ASTM B36 in temper H02 "
            "(half hard): E 110 GPa (16e6 psi), yield 350 MPa (51 ksi) nominal, density "
            "8.53 g/cm³ (Copper Development Association alloy data for C26000; Olin Brass "
            "C26000 data sheet)."
        ),
    ),
    "alloy42": PinMaterial(
        "alloy42",
        youngs_modulus=148.0,
        yield_strength=276.0,
        density=8.12,
        source=(
            "Iron–nickel lead-frame alloy 42 (FeNi42, UNS K94100), to ASTM F30, annealed: "
            "E 148 GPa (21.4e6 psi), 0.2 % yield 276 MPa (40 ksi), density 8.12 g/cm³ "
            "(producers' data sheets for 'Glass Sealing 42' / 'Alloy 42'; cold-rolled "
            "lead-frame tempers reach 550–650 MPa: give them as a mapping)."
        ),
    ),
}


def _allowed() -> str:
    names = ", ".join(map(repr, MATERIALS))
    return (
        f"one of {names} or a mapping {{'youngs_modulus': GPa, 'yield_strength': MPa"
        "[, 'density': g/cm³]}"
    )


def pin_material(value: object, field: str = "pin_material") -> PinMaterial:
    """The material that ``value`` names: a :class:`PinMaterial`, a preset's name in
    :data:`MATERIALS`, or a mapping of user values ``{"youngs_modulus": GPa,
    "yield_strength": MPa}`` with an optional ``"density"`` (g/cm³). ``ValueError`` naming
    ``field`` and what is allowed otherwise."""
    if isinstance(value, PinMaterial):
        return value
    if isinstance(value, str):
        if value not in MATERIALS:
            raise ValueError(f"{field}={value!r} is not a known material; allowed: {_allowed()}")
        return MATERIALS[value]
    if not isinstance(value, Mapping):
        raise ValueError(
            f"{field}={value!r} is not a material name or mapping; allowed: {_allowed()}"
        )
    unknown = [key for key in value if key not in MATERIAL_KEYS]
    if unknown:
        raise ValueError(
            f"{field} has unknown key {unknown[0]!r}; allowed keys: "
            f"{', '.join(map(repr, MATERIAL_KEYS))} ({_allowed()})"
        )
    for key in ("youngs_modulus", "yield_strength"):
        if key not in value:
            raise ValueError(f"{field} is missing {key!r}; allowed: {_allowed()}")
    checked = {key: _check_property(f"{field}[{key!r}]", value[key], key) for key in value}
    return PinMaterial(
        "custom",
        youngs_modulus=checked["youngs_modulus"],
        yield_strength=checked["yield_strength"],
        density=checked.get("density"),
        source="user values",
    )


def _dims(diameter: object, length: object | None = None) -> tuple[float, float]:
    d = check_positive("diameter", diameter)
    return d, (math.nan if length is None else check_positive("length", length))


def second_moment(diameter: float) -> float:
    """Second moment of area I = π d⁴ / 64 (mm⁴) of a round section of ``diameter`` mm."""
    d, _ = _dims(diameter)
    return math.pi * d**4 / 64.0


def bending_stiffness(material: object, diameter: float) -> float:
    """Flexural rigidity E I (mN·mm²)."""
    return pin_material(material).modulus * second_moment(diameter)


def tip_stiffness(material: object, diameter: float, length: float) -> float:
    """Tip stiffness 3 E I / L³ (mN/mm) of a cantilever of free ``length`` mm."""
    _, L = _dims(diameter, length)
    return 3.0 * bending_stiffness(material, diameter) / L**3


def root_stiffness(material: object, diameter: float, length: float) -> float:
    """Rotational stiffness k_θ = 3 E I / L (mN·mm/rad) of a rigid pin on a root hinge that
    deflects at its tip as the cantilever does under a tip load."""
    _, L = _dims(diameter, length)
    return 3.0 * bending_stiffness(material, diameter) / L


def yield_moment(material: object, diameter: float) -> float:
    """Moment at first yield M_y = σ_y π d³ / 32 (mN·mm) of a round section."""
    d, _ = _dims(diameter)
    return pin_material(material).yield_stress * math.pi * d**3 / 32.0


def yield_tip_load(material: object, diameter: float, length: float) -> float:
    """Tip load (mN) that brings the root to its yield moment: M_y / L."""
    _, L = _dims(diameter, length)
    return yield_moment(material, diameter) / L


def yield_rotation(material: object, diameter: float, length: float) -> float:
    """Root rotation (rad) of the hinge model at first yield: M_y / k_θ."""
    return yield_moment(material, diameter) / root_stiffness(material, diameter, length)


def buckling_load(material: object, diameter: float, length: float) -> float:
    """Euler load (mN) of a fixed–free column: P_cr = π² E I / (4 L²)."""
    _, L = _dims(diameter, length)
    return math.pi**2 * bending_stiffness(material, diameter) / (4.0 * L**2)


def axial_stiffness(material: object, diameter: float, length: float) -> float:
    """Axial stiffness E A / L (mN/mm) with A = π d² / 4."""
    d, L = _dims(diameter, length)
    return pin_material(material).modulus * math.pi * d**2 / (4.0 * L)


def pin_mass(material: object, diameter: float, length: float) -> float:
    """Mass (kg) of the free length of the pin."""
    d, L = _dims(diameter, length)
    return pin_material(material).mass_density * math.pi * d**2 / 4.0 * L


def root_inertia(material: object, diameter: float, length: float) -> float:
    """Moment of inertia (kg·mm²) of the pin as a rigid rod about a transverse axis through
    its root: m (L²/3 + d²/16)."""
    d, L = _dims(diameter, length)
    return pin_mass(material, d, L) * (L**2 / 3.0 + d**2 / 16.0)
