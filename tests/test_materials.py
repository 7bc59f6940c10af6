"""Pin materials: presets, user values, every bad input, and the beam formulas against
values computed by hand for the phosphor-bronze pin (d = 0.6 mm, L = 4 mm)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from tolins.geometry import materials
from tolins.geometry.materials import (
    MATERIALS,
    PinMaterial,
    axial_stiffness,
    bending_stiffness,
    buckling_load,
    pin_mass,
    pin_material,
    root_inertia,
    root_stiffness,
    second_moment,
    tip_stiffness,
    yield_moment,
    yield_rotation,
    yield_tip_load,
)

D, L = 0.6, 4.0


def test_presets_are_documented_and_in_range() -> None:
    assert len(MATERIALS) >= 3
    for name, material in MATERIALS.items():
        assert material.name == name
        assert pin_material(name) is material
        assert 50.0 <= material.youngs_modulus <= 250.0
        assert 100.0 <= material.yield_strength <= 1000.0
        assert material.density is not None and 7.0 <= material.density <= 9.5
        assert "ASTM" in material.source and "GPa" in material.source


def test_phosphor_bronze_by_hand() -> None:
    # E = 110 GPa = 1.1e8 mN/mm²; σ_y = 515 MPa = 5.15e5 mN/mm²; ρ = 8.86e-6 kg/mm³.
    # I = π 0.6⁴ / 64 = π 0.1296 / 64 = 0.0063617 mm⁴; EI = 1.1e8 · 0.0063617 = 6.9979e5.
    bronze = "phosphor_bronze"
    assert second_moment(D) == pytest.approx(0.0063617, rel=1e-4)
    assert bending_stiffness(bronze, D) == pytest.approx(6.9979e5, rel=1e-4)
    # 3 EI / L³ = 2.09937e6 / 64 = 32,803 mN/mm (32.8 N/mm); 3 EI / L = 524,842 mN·mm/rad.
    assert tip_stiffness(bronze, D, L) == pytest.approx(32803.0, rel=1e-4)
    assert root_stiffness(bronze, D, L) == pytest.approx(524842.0, rel=1e-5)
    # M_y = 5.15e5 · π 0.216 / 32 = 5.15e5 · 0.0212058 = 10,921 mN·mm (10.9 N·mm).
    assert yield_moment(bronze, D) == pytest.approx(10921.0, rel=1e-4)
    assert yield_tip_load(bronze, D, L) == pytest.approx(2730.2, rel=1e-4)  # 2.73 N
    assert yield_rotation(bronze, D, L) == pytest.approx(10921.0 / 524842.0, rel=1e-4)
    # P_cr = π² EI / (4 L²) = 9.8696 · 6.9979e5 / 64 = 107,916 mN (108 N).
    assert buckling_load(bronze, D, L) == pytest.approx(107916.0, rel=1e-4)
    # EA / L = 1.1e8 · π 0.09 / 4 = 7.7754e6 mN/mm.
    assert axial_stiffness(bronze, D, L) == pytest.approx(7.7754e6, rel=1e-4)
    # m = 8.86e-6 · π 0.09 · 4 = 1.00204e-5 kg; J = m (16/3 + 0.36/16) = 5.3668e-5 kg·mm².
    assert pin_mass(bronze, D, L) == pytest.approx(1.00204e-5, rel=1e-4)
    assert root_inertia(bronze, D, L) == pytest.approx(5.3668e-5, rel=1e-4)


def test_hinge_reproduces_cantilever_tip_deflection() -> None:
    # A tip load F on a hinge of k_θ = 3EI/L turns it by FL/k_θ: tip offset FL²/k_θ = FL³/3EI.
    load = 1000.0  # 1 N
    k = root_stiffness("brass", D, L)
    assert load * L**2 / k == pytest.approx(load / tip_stiffness("brass", D, L), rel=1e-12)
    assert load * L**3 / (3 * bending_stiffness("brass", D)) == pytest.approx(load * L**2 / k)


def test_user_values() -> None:
    custom = pin_material({"youngs_modulus": 130, "yield_strength": 600.0})
    assert custom == PinMaterial("custom", 130.0, 600.0, None, "user values")
    assert isinstance(custom.youngs_modulus, float)
    assert custom.modulus == 1.3e8 and custom.yield_stress == 6.0e5
    assert custom.mass_density == pytest.approx(materials.DEFAULT_DENSITY * 1e-6)
    dense = pin_material({"youngs_modulus": 130, "yield_strength": 600, "density": 8.0})
    assert dense.mass_density == pytest.approx(8.0e-6)
    assert pin_material(dense) is dense
    with pytest.raises(dataclasses.FrozenInstanceError):
        dense.youngs_modulus = 1.0  # type: ignore[misc]


def _message(value: object) -> str:
    with pytest.raises(ValueError) as error:
        pin_material(value)
    message = str(error.value)
    assert "\n" not in message and "allowed" in message and "pin_material" in message
    return message


GOOD = {"youngs_modulus": 110.0, "yield_strength": 500.0}


@pytest.mark.parametrize(
    ("value", "shown"),
    [
        pytest.param("bronze", "'bronze'", id="unknown-name"),
        pytest.param("", "''", id="empty-name"),
        pytest.param("Brass", "'Brass'", id="case"),
        pytest.param(None, "None", id="none"),
        pytest.param(110.0, "110.0", id="number"),
        pytest.param(True, "True", id="bool"),
        pytest.param([110.0, 500.0], "[110.0, 500.0]", id="list"),
        pytest.param({"yield_strength": 500.0}, "'youngs_modulus'", id="missing-modulus"),
        pytest.param({"youngs_modulus": 110.0}, "'yield_strength'", id="missing-yield"),
        pytest.param({}, "missing", id="empty-mapping"),
        pytest.param({**GOOD, "E": 110.0}, "'E'", id="unknown-key"),
        pytest.param({**GOOD, "poisson": 0.3}, "'poisson'", id="unknown-key-2"),
        pytest.param({**GOOD, "youngs_modulus": 0.0}, "0.0", id="modulus-zero"),
        pytest.param({**GOOD, "youngs_modulus": -110.0}, "-110.0", id="modulus-negative"),
        pytest.param({**GOOD, "youngs_modulus": math.nan}, "nan", id="modulus-nan"),
        pytest.param({**GOOD, "youngs_modulus": math.inf}, "inf", id="modulus-inf"),
        pytest.param({**GOOD, "youngs_modulus": 110e9}, "110000000000.0", id="modulus-in-pa"),
        pytest.param({**GOOD, "youngs_modulus": True}, "True", id="modulus-bool"),
        pytest.param({**GOOD, "youngs_modulus": "110"}, "'110'", id="modulus-str"),
        pytest.param({**GOOD, "yield_strength": 0}, "0", id="yield-zero"),
        pytest.param({**GOOD, "yield_strength": -5.0}, "-5.0", id="yield-negative"),
        pytest.param({**GOOD, "yield_strength": math.nan}, "nan", id="yield-nan"),
        pytest.param({**GOOD, "yield_strength": -math.inf}, "-inf", id="yield-ninf"),
        pytest.param({**GOOD, "yield_strength": 5.0e8}, "500000000.0", id="yield-in-pa"),
        pytest.param({**GOOD, "yield_strength": False}, "False", id="yield-bool"),
        pytest.param({**GOOD, "yield_strength": None}, "None", id="yield-none"),
        pytest.param({**GOOD, "density": 0.0}, "0.0", id="density-zero"),
        pytest.param({**GOOD, "density": -8.5}, "-8.5", id="density-negative"),
        pytest.param({**GOOD, "density": math.nan}, "nan", id="density-nan"),
        pytest.param({**GOOD, "density": math.inf}, "inf", id="density-inf"),
        pytest.param({**GOOD, "density": 8500.0}, "8500.0", id="density-in-kg-m3"),
        pytest.param({**GOOD, "density": True}, "True", id="density-bool"),
        pytest.param({**GOOD, "density": None}, "None", id="density-none"),
        pytest.param({**GOOD, "youngs_modulus": 1 + 2j}, "(1+2j)", id="modulus-complex"),
    ],
)
def test_bad_values_are_refused(value: object, shown: str) -> None:
    assert shown in _message(value)


def test_messages_name_the_key_and_unit() -> None:
    assert "'phosphor_bronze'" in _message("copper")
    message = _message({**GOOD, "yield_strength": -1.0})
    assert "'yield_strength'" in message and "MPa" in message
    assert "GPa" in _message({**GOOD, "youngs_modulus": 0})
    assert "g/cm³" in _message({**GOOD, "density": -1})


@pytest.mark.parametrize(
    "kwargs",
    [
        {"youngs_modulus": 0.0, "yield_strength": 500.0},
        {"youngs_modulus": 110.0, "yield_strength": math.nan},
        {"youngs_modulus": 110.0, "yield_strength": 500.0, "density": -1.0},
        {"youngs_modulus": True, "yield_strength": 500.0},
    ],
)
def test_direct_construction_is_checked(kwargs: dict[str, object]) -> None:
    with pytest.raises(ValueError, match="allowed"):
        PinMaterial("x", **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("diameter", "length", "field"),
    [(0.0, L, "diameter"), (-0.6, L, "diameter"), (math.nan, L, "diameter"), (D, 0.0, "length")],
)
def test_bad_dimensions(diameter: float, length: float, field: str) -> None:
    with pytest.raises(ValueError, match=field):
        tip_stiffness("brass", diameter, length)


def test_formulas_take_mappings_and_refuse_bad_materials() -> None:
    user = {"youngs_modulus": 110.0, "yield_strength": 515.0}
    assert yield_moment(user, D) == yield_moment("phosphor_bronze", D)
    with pytest.raises(ValueError, match="pin_material"):
        yield_moment("steel", D)
