"""Socket specs: validation, value semantics, grid layout and bent-pin sampling."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from spec_variants import one_field_variants

import tolins
from tolins import CircularSocket, PolygonSocket, sample_defects
from tolins.geometry import CIRCLE_HOLE_SIDES, MIN_WALL

NAN = float("nan")
INF = float("inf")

#: Pitch that just fits two default holes (r = 0.5) and the minimum wall between them.
DEFAULT_WALL_SPAN = 2 * 0.5 / math.cos(math.pi / CIRCLE_HOLE_SIDES) + MIN_WALL


def _check_message(error: pytest.ExceptionInfo[ValueError], field: str, shown: str) -> None:
    """The message names the field, shows the bad value and says what is allowed."""
    message = str(error.value)
    assert field in message
    assert shown in message, f"{shown!r} not in {message!r}"
    assert "allowed" in message


# --- CircularSocket validation -----------------------------------------------------------

BAD_CIRCULAR = [
    # (kwargs, field named, text showing the bad value)
    pytest.param({"rows": 0, "cols": 2}, "rows", "rows=0", id="rows-zero"),
    pytest.param({"rows": -3, "cols": 2}, "rows", "rows=-3", id="rows-negative"),
    pytest.param({"rows": 2.0, "cols": 2}, "rows", "rows=2.0", id="rows-float"),
    pytest.param({"rows": 1.5, "cols": 2}, "rows", "rows=1.5", id="rows-fraction"),
    pytest.param({"rows": "2", "cols": 2}, "rows", "rows='2'", id="rows-str"),
    pytest.param({"rows": None, "cols": 2}, "rows", "rows=None", id="rows-none"),
    pytest.param({"rows": True, "cols": 2}, "rows", "rows=True", id="rows-bool"),
    pytest.param({"rows": 2, "cols": 0}, "cols", "cols=0", id="cols-zero"),
    pytest.param({"rows": 2, "cols": -1}, "cols", "cols=-1", id="cols-negative"),
    pytest.param({"rows": 2, "cols": 3.0}, "cols", "cols=3.0", id="cols-float"),
    pytest.param({"rows": 2, "cols": True}, "cols", "cols=True", id="cols-bool"),
    pytest.param({"rows": 2, "cols": False}, "cols", "cols=False", id="cols-bool-false"),
    pytest.param({"rows": 2, "cols": 2, "pin_radius": 0.0}, "pin_radius", "0.0", id="pin-zero"),
    pytest.param({"rows": 2, "cols": 2, "pin_radius": -0.1}, "pin_radius", "-0.1", id="pin-neg"),
    pytest.param({"rows": 2, "cols": 2, "pin_radius": NAN}, "pin_radius", "nan", id="pin-nan"),
    pytest.param({"rows": 2, "cols": 2, "pin_radius": INF}, "pin_radius", "inf", id="pin-inf"),
    pytest.param({"rows": 2, "cols": 2, "pin_radius": "a"}, "pin_radius", "'a'", id="pin-str"),
    pytest.param({"rows": 2, "cols": 2, "pin_radius": True}, "pin_radius", "True", id="pin-bool"),
    pytest.param({"rows": 2, "cols": 2, "hole_radius": 0}, "hole_radius", "0", id="hole-zero"),
    pytest.param({"rows": 2, "cols": 2, "hole_radius": NAN}, "hole_radius", "nan", id="hole-nan"),
    pytest.param(
        {"rows": 2, "cols": 2, "hole_radius": -INF}, "hole_radius", "-inf", id="hole-ninf"
    ),
    pytest.param({"rows": 2, "cols": 2, "row_pitch": 0.0}, "row_pitch", "0.0", id="rowp-zero"),
    pytest.param({"rows": 2, "cols": 2, "row_pitch": -7.62}, "row_pitch", "-7.62", id="rowp-neg"),
    pytest.param({"rows": 2, "cols": 2, "row_pitch": NAN}, "row_pitch", "nan", id="rowp-nan"),
    pytest.param({"rows": 2, "cols": 2, "row_pitch": INF}, "row_pitch", "inf", id="rowp-inf"),
    pytest.param({"rows": 2, "cols": 2, "col_pitch": 0.0}, "col_pitch", "0.0", id="colp-zero"),
    pytest.param({"rows": 2, "cols": 2, "col_pitch": -1.0}, "col_pitch", "-1.0", id="colp-neg"),
    pytest.param({"rows": 2, "cols": 2, "col_pitch": NAN}, "col_pitch", "nan", id="colp-nan"),
    pytest.param({"rows": 2, "cols": 2, "col_pitch": INF}, "col_pitch", "inf", id="colp-inf"),
    # A single row or column does not make a non-positive pitch acceptable.
    pytest.param({"rows": 1, "cols": 1, "row_pitch": NAN}, "row_pitch", "nan", id="rowp-nan-1x1"),
    pytest.param({"rows": 1, "cols": 1, "col_pitch": -2.0}, "col_pitch", "-2.0", id="colp-neg-1x1"),
    pytest.param(
        {"rows": 2, "cols": 2, "pin_radius": 0.5, "hole_radius": 0.5},
        "pin_radius",
        "0.5",
        id="pin-equals-hole",
    ),
    pytest.param(
        {"rows": 2, "cols": 2, "pin_radius": 0.6, "hole_radius": 0.5},
        "pin_radius",
        "0.6",
        id="pin-larger-than-hole",
    ),
    pytest.param({"rows": 1, "cols": 2, "col_pitch": 1.0}, "col_pitch", "1.0", id="colp-no-wall"),
    pytest.param({"rows": 2, "cols": 1, "row_pitch": 1.0}, "row_pitch", "1.0", id="rowp-no-wall"),
    pytest.param(
        {"rows": 3, "cols": 3, "row_pitch": 7.62, "col_pitch": DEFAULT_WALL_SPAN - 1e-6},
        "col_pitch",
        repr(DEFAULT_WALL_SPAN - 1e-6),
        id="colp-just-below-wall-span",
    ),
    pytest.param(
        {"rows": 2, "cols": 2, "hole_radius": 2.0, "pin_radius": 1.0},  # default col_pitch 2.54
        "col_pitch",
        "2.54",
        id="colp-too-small-for-big-holes",
    ),
]


@pytest.mark.parametrize(("kwargs", "field", "shown"), BAD_CIRCULAR)
def test_circular_socket_rejects_invalid_fields(kwargs: dict, field: str, shown: str) -> None:
    with pytest.raises(ValueError, match=field) as error:
        CircularSocket(**kwargs)
    _check_message(error, field, shown)


def test_pitch_error_states_the_minimum_pitch() -> None:
    with pytest.raises(ValueError, match="col_pitch") as error:
        CircularSocket(1, 2, col_pitch=1.0)
    assert f"{DEFAULT_WALL_SPAN:.4g}" in str(error.value)


@pytest.mark.parametrize(
    "kwargs",
    [
        pytest.param({"rows": 2, "cols": 1, "col_pitch": 1.0}, id="one-col-small-col-pitch"),
        pytest.param({"rows": 1, "cols": 2, "row_pitch": 1.0}, id="one-row-small-row-pitch"),
        pytest.param({"rows": 1, "cols": 1, "row_pitch": 0.1, "col_pitch": 0.1}, id="1x1-small"),
        pytest.param({"rows": 2, "cols": 2, "col_pitch": DEFAULT_WALL_SPAN}, id="exact-wall-span"),
        pytest.param({"rows": np.int64(2), "cols": np.int32(3)}, id="numpy-ints"),
        pytest.param({"rows": 2, "cols": 2, "pin_radius": np.float32(0.25)}, id="numpy-float"),
        pytest.param({"rows": 2, "cols": 2, "pin_radius": 0.49, "hole_radius": 0.5}, id="tight"),
    ],
)
def test_circular_socket_accepts_valid_fields(kwargs: dict) -> None:
    spec = CircularSocket(**kwargs)
    assert spec.n_pins == int(kwargs["rows"]) * int(kwargs["cols"])
    assert type(spec.rows) is int and type(spec.cols) is int
    for name in ("pin_radius", "hole_radius", "row_pitch", "col_pitch"):
        assert type(getattr(spec, name)) is float


def _offsets(n: int, value: object = 0.0) -> np.ndarray:
    array = np.zeros((n, 2))
    array[-1, 0] = value
    return array


BAD_OFFSETS = [
    pytest.param(np.zeros((3, 2)), "(3, 2)", id="too-few-pins"),
    pytest.param(np.zeros((5, 2)), "(5, 2)", id="too-many-pins"),
    pytest.param(np.zeros((4, 3)), "(4, 3)", id="three-columns"),
    pytest.param(np.zeros((4,)), "(4,)", id="flat"),
    pytest.param(np.zeros((2, 2, 2)), "(2, 2, 2)", id="three-dims"),
    pytest.param(np.zeros((2, 4)), "(2, 4)", id="transposed"),
    pytest.param([], "(0,)", id="empty"),
    pytest.param(_offsets(4, NAN), "nan", id="nan"),
    pytest.param(_offsets(4, INF), "inf", id="inf"),
    pytest.param(_offsets(4, -INF), "-inf", id="neg-inf"),
    pytest.param("bent", "'bent'", id="string"),
    pytest.param([[0.0, 0.0], [0.0], [0.0, 0.0], [0.0, 0.0]], "[0.0]", id="ragged"),
    # Cell half-widths of the default 2*2 socket: 2.54 / 2 - 0.3 = 0.97 (x), 7.62 / 2 - 0.3 = 3.51.
    pytest.param(_offsets(4, 1.0), "pin_offsets[3]", id="out-of-cell-x"),
    pytest.param(_offsets(4, -1.0), "pin_offsets[3]", id="out-of-cell-neg-x"),
    pytest.param([[0, 0], [0, 3.6], [0, 0], [0, 0]], "pin_offsets[1]", id="out-of-cell-y"),
    pytest.param([[0, 0], [0, 0], [0, -3.6], [0, 0]], "pin_offsets[2]", id="out-of-cell-neg-y"),
]


@pytest.mark.parametrize(("offsets", "shown"), BAD_OFFSETS)
def test_circular_socket_rejects_invalid_pin_offsets(offsets: object, shown: str) -> None:
    with pytest.raises(ValueError, match="pin_offsets") as error:
        CircularSocket(2, 2, pin_offsets=offsets)
    _check_message(error, "pin_offsets", shown)


@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_pin_offsets_limit_is_the_pin_staying_in_its_cell(axis: int, sign: float) -> None:
    """A pin may bend until its side reaches the edge of its cell (half a pitch away)."""
    spec = CircularSocket(3, 3, pin_radius=0.3, hole_radius=0.5, row_pitch=4.0, col_pitch=3.0)
    half_cell = (spec.col_pitch, spec.row_pitch)[axis] / 2 - spec.pin_radius
    inside = np.zeros((9, 2))
    inside[4, axis] = sign * (half_cell - 1e-6)
    assert CircularSocket(**{**_fields(spec), "pin_offsets": inside}).is_defective
    outside = inside.copy()
    outside[4, axis] = sign * (half_cell + 1e-6)
    with pytest.raises(ValueError, match=r"pin_offsets\[4\]"):
        CircularSocket(**{**_fields(spec), "pin_offsets": outside})


def _fields(spec: CircularSocket) -> dict:
    return {f.name: getattr(spec, f.name) for f in dataclasses.fields(spec)}


def test_single_row_accepts_nominal_offsets_whatever_the_unused_row_pitch() -> None:
    spec = CircularSocket(1, 2, row_pitch=0.5)  # accepted: row_pitch unused with one row
    bent = CircularSocket(1, 2, row_pitch=0.5, pin_offsets=[[0.1, 2.0], [-0.1, -2.0]])
    assert bent.is_defective
    assert sample_defects(spec, 0.01, rng=0).offsets.shape == (2, 2)
    with pytest.raises(ValueError, match="pin_offsets"):
        CircularSocket(1, 2, row_pitch=0.5, pin_offsets=[[1.0, 0.0], [0.0, 0.0]])


# --- PolygonSocket validation -------------------------------------------------------------

BAD_POLYGON = [
    pytest.param({"sides": 2}, "sides", "sides=2", id="sides-two"),
    pytest.param({"sides": 0}, "sides", "sides=0", id="sides-zero"),
    pytest.param({"sides": -4}, "sides", "sides=-4", id="sides-negative"),
    pytest.param({"sides": 4.0}, "sides", "sides=4.0", id="sides-float"),
    pytest.param({"sides": True}, "sides", "sides=True", id="sides-bool"),
    pytest.param({"sides": "6"}, "sides", "sides='6'", id="sides-str"),
    pytest.param({"pin_circumradius": 0.0}, "pin_circumradius", "0.0", id="pin-zero"),
    pytest.param({"pin_circumradius": -1.5}, "pin_circumradius", "-1.5", id="pin-neg"),
    pytest.param({"pin_circumradius": NAN}, "pin_circumradius", "nan", id="pin-nan"),
    pytest.param({"pin_circumradius": INF}, "pin_circumradius", "inf", id="pin-inf"),
    pytest.param({"hole_circumradius": 0}, "hole_circumradius", "0", id="hole-zero"),
    pytest.param({"hole_circumradius": NAN}, "hole_circumradius", "nan", id="hole-nan"),
    pytest.param({"hole_circumradius": INF}, "hole_circumradius", "inf", id="hole-inf"),
    pytest.param({"hole_circumradius": False}, "hole_circumradius", "False", id="hole-bool"),
    pytest.param({"hole_circumradius": 1.5}, "pin_circumradius", "1.5", id="pin-equals-hole"),
    pytest.param({"hole_circumradius": 1.4}, "pin_circumradius", "1.4", id="pin-above-hole"),
]


@pytest.mark.parametrize(("kwargs", "field", "shown"), BAD_POLYGON)
def test_polygon_socket_rejects_invalid_fields(kwargs: dict, field: str, shown: str) -> None:
    full = {"sides": 4, "pin_circumradius": 1.5, "hole_circumradius": 1.65, **kwargs}
    with pytest.raises(ValueError, match=field) as error:
        PolygonSocket(**full)
    _check_message(error, field, shown)


@pytest.mark.parametrize("sides", [3, 4, 5, 8, 64])
def test_polygon_socket_accepts_valid_fields(sides: int) -> None:
    spec = PolygonSocket(np.int64(sides), 1.5, 1.65)
    assert type(spec.sides) is int and spec.sides == sides
    assert spec.n_pins == 1
    np.testing.assert_array_equal(spec.hole_centers, np.zeros((1, 2)))
    np.testing.assert_array_equal(spec.pin_centers, np.zeros((1, 2)))
    cos = math.cos(math.pi / sides)
    assert spec.clearance == pytest.approx((1.65 - 1.5) * cos)
    assert not spec.is_defective


# --- value semantics ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "field", "value"),
    [
        (CircularSocket(2, 2), "rows", 3),
        (CircularSocket(2, 2), "pin_radius", 0.1),
        (CircularSocket(2, 2), "pin_offsets", None),
        (PolygonSocket(4, 1.5, 1.65), "sides", 5),
        (PolygonSocket(4, 1.5, 1.65), "hole_circumradius", 2.0),
    ],
)
def test_specs_are_frozen(spec: object, field: str, value: object) -> None:
    before = getattr(spec, field)
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(spec, field, value)
    assert getattr(spec, field) == before


def test_specs_are_hashable_and_equal_when_equal() -> None:
    offsets = np.array([[0.1, -0.2], [0.0, 0.05], [-0.3, 0.0], [0.0, 0.0]])
    a = CircularSocket(2, 2, pin_offsets=offsets)
    b = CircularSocket(2, 2, pin_offsets=[tuple(row) for row in offsets.tolist()])
    c = CircularSocket(np.int64(2), 2, 0.3, 0.5, 7.62, 2.54, pin_offsets=offsets.copy())
    assert a == b == c
    assert hash(a) == hash(b) == hash(c)
    assert len({a, b, c}) == 1
    assert CircularSocket(2, 2) == CircularSocket(2, 2)
    assert hash(CircularSocket(2, 2)) == hash(CircularSocket(2, 2))
    p, q = PolygonSocket(6, 1.5, 1.65), PolygonSocket(6, 1.5, 1.65)
    assert p == q and hash(p) == hash(q)

    different = {a, *one_field_variants()}
    assert len(different) == 14
    assert a != CircularSocket(2, 2)
    assert p != PolygonSocket(7, 1.5, 1.65)
    # A dict keyed by specs finds an equal spec built separately.
    cache = {a: "defective", CircularSocket(2, 2): "nominal"}
    assert cache[CircularSocket(2, 2, pin_offsets=offsets.tolist())] == "defective"


def test_pin_offsets_array_is_stored_as_tuples() -> None:
    offsets = np.array([[0.1, -0.2], [0.0, 0.05], [-0.3, 0.0], [0.25, 0.125]])
    spec = CircularSocket(2, 2, pin_offsets=offsets)
    assert isinstance(spec.pin_offsets, tuple)
    assert len(spec.pin_offsets) == 4
    for stored, row in zip(spec.pin_offsets, offsets, strict=True):
        assert isinstance(stored, tuple) and len(stored) == 2
        assert all(type(v) is float for v in stored)
        assert stored == tuple(row.tolist())
    assert isinstance(spec.offsets, np.ndarray)
    assert spec.offsets.shape == (4, 2) and spec.offsets.dtype == float
    np.testing.assert_array_equal(spec.offsets, offsets)
    # The spec does not alias the caller's array, nor does .offsets alias the spec.
    offsets[0, 0] = 0.5
    assert spec.pin_offsets[0][0] == 0.1
    spec.offsets[1, 1] = 0.9
    assert spec.offsets[1, 1] == 0.05
    assert spec.is_defective


def test_nominal_spec_has_zero_offsets() -> None:
    spec = CircularSocket(3, 4)
    assert spec.pin_offsets is None
    np.testing.assert_array_equal(spec.offsets, np.zeros((12, 2)))
    assert not spec.is_defective
    assert not CircularSocket(3, 4, pin_offsets=np.zeros((12, 2))).is_defective
    bent = CircularSocket(3, 4, pin_offsets=_offsets(12, 0.1))
    assert bent.is_defective
    assert bent.nominal() == spec
    assert bent.nominal().pin_offsets is None


# --- grid layout ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("rows", "cols", "row_pitch", "col_pitch"),
    [(1, 1, 7.62, 2.54), (2, 1, 7.62, 2.54), (1, 5, 7.62, 2.54), (2, 3, 7.62, 2.54), (4, 3, 5, 3)],
)
def test_hole_centers_are_row_major_centred_grid(
    rows: int, cols: int, row_pitch: float, col_pitch: float
) -> None:
    spec = CircularSocket(rows, cols, row_pitch=row_pitch, col_pitch=col_pitch)
    centers = spec.hole_centers
    assert centers.shape == (rows * cols, 2)
    np.testing.assert_allclose(centers.mean(axis=0), 0.0, atol=1e-12)
    for r in range(rows):
        for c in range(cols):
            x, y = centers[r * cols + c]
            assert x == pytest.approx((c - (cols - 1) / 2) * col_pitch, abs=1e-12)
            assert y == pytest.approx((r - (rows - 1) / 2) * row_pitch, abs=1e-12)
    grid = centers.reshape(rows, cols, 2)
    if cols > 1:  # x grows along a row, y is constant
        np.testing.assert_allclose(np.diff(grid[..., 0], axis=1), col_pitch)
        np.testing.assert_allclose(np.diff(grid[..., 1], axis=1), 0.0)
    if rows > 1:
        np.testing.assert_allclose(np.diff(grid[..., 1], axis=0), row_pitch)
        np.testing.assert_allclose(np.diff(grid[..., 0], axis=0), 0.0)
    # Nominal pins are at the holes.
    np.testing.assert_array_equal(spec.pin_centers, centers)


def test_pin_centers_are_hole_centers_plus_offsets() -> None:
    rng = np.random.default_rng(7)
    offsets = rng.uniform(-0.5, 0.5, size=(6, 2))
    spec = CircularSocket(2, 3, pin_offsets=offsets)
    np.testing.assert_allclose(spec.pin_centers, spec.hole_centers + offsets, atol=0)
    # Holes stay nominal.
    np.testing.assert_array_equal(spec.hole_centers, CircularSocket(2, 3).hole_centers)


def test_clearance_and_circumradius() -> None:
    spec = CircularSocket(1, 1, pin_radius=0.3, hole_radius=0.5)
    assert spec.clearance == pytest.approx(0.2)
    # The 16-gon modelling the hole has its faces (not its corners) at the hole radius.
    assert spec.hole_circumradius * math.cos(math.pi / CIRCLE_HOLE_SIDES) == pytest.approx(0.5)
    assert spec.hole_circumradius > spec.hole_radius


# --- sample_defects --------------------------------------------------------------------------

WIDE = CircularSocket(20, 20, row_pitch=10.0, col_pitch=10.0)


def test_sample_defects_returns_a_new_spec_and_leaves_the_input_untouched() -> None:
    spec = CircularSocket(2, 3)
    before = dataclasses.replace(spec)
    bent = sample_defects(spec, 0.1, rng=0)
    assert isinstance(bent, CircularSocket)
    assert bent is not spec
    assert spec == before and spec.pin_offsets is None
    assert bent.offsets.shape == (6, 2)
    assert isinstance(bent.pin_offsets, tuple) and len(bent.pin_offsets) == 6
    assert bent.is_defective
    assert bent.nominal() == spec
    # Only the offsets change.
    for name in ("rows", "cols", "pin_radius", "hole_radius", "row_pitch", "col_pitch"):
        assert getattr(bent, name) == getattr(spec, name)
    np.testing.assert_allclose(bent.pin_centers, spec.hole_centers + bent.offsets)


def test_sample_defects_replaces_existing_offsets() -> None:
    spec = CircularSocket(2, 2, pin_offsets=np.full((4, 2), 0.2))
    bent = sample_defects(spec, 0.05, rng=1)
    assert spec.pin_offsets == ((0.2, 0.2),) * 4
    assert not np.any(bent.offsets == 0.2)
    np.testing.assert_array_equal(bent.offsets, sample_defects(spec.nominal(), 0.05, rng=1).offsets)


def test_sample_defects_is_reproducible() -> None:
    spec = CircularSocket(3, 4)
    assert sample_defects(spec, 0.1, rng=42) == sample_defects(spec, 0.1, rng=42)
    a = sample_defects(spec, 0.1, rng=np.random.default_rng(42))
    b = sample_defects(spec, 0.1, rng=np.random.default_rng(42))
    assert a == b
    assert a == sample_defects(spec, 0.1, rng=42)
    # The same Generator advances: a second draw differs, like a second fresh generator's.
    rng, twin = np.random.default_rng(5), np.random.default_rng(5)
    first, second = sample_defects(spec, 0.1, rng=rng), sample_defects(spec, 0.1, rng=rng)
    assert first != second
    assert first == sample_defects(spec, 0.1, rng=twin)
    assert second == sample_defects(spec, 0.1, rng=twin)


def test_sample_defects_differs_between_seeds() -> None:
    spec = CircularSocket(3, 4)
    draws = {sample_defects(spec, 0.1, rng=seed) for seed in range(10)}
    assert len(draws) == 10
    # Unseeded draws come from fresh entropy.
    assert sample_defects(spec, 0.1) != sample_defects(spec, 0.1)


@pytest.mark.parametrize("sigma", [0.02, 0.1, 0.5])
def test_sample_defects_has_the_requested_spread(sigma: float) -> None:
    offsets = np.concatenate([sample_defects(WIDE, sigma, rng=s).offsets for s in range(5)])
    n = offsets.size  # 4000 draws; std of the std estimate ≈ sigma / sqrt(2 n) ≈ 1.1 %
    assert offsets.std() == pytest.approx(sigma, rel=0.06)
    for axis in (0, 1):
        assert offsets[:, axis].std() == pytest.approx(sigma, rel=0.08)
        assert abs(offsets[:, axis].mean()) < 5 * sigma / math.sqrt(n / 2)
    assert abs(np.corrcoef(offsets[:, 0], offsets[:, 1])[0, 1]) < 0.1
    # Scaling sigma scales the same draw.
    np.testing.assert_allclose(
        sample_defects(WIDE, 2 * sigma, rng=3).offsets,
        2 * sample_defects(WIDE, sigma, rng=3).offsets,
        rtol=1e-12,
    )


def test_sample_defects_rejects_polygon_socket() -> None:
    spec = PolygonSocket(4, 1.5, 1.65)
    with pytest.raises(ValueError, match="spec") as error:
        sample_defects(spec, 0.1, rng=0)
    _check_message(error, "spec", "PolygonSocket")


@pytest.mark.parametrize(
    ("sigma", "shown"),
    [(0.0, "0.0"), (-0.1, "-0.1"), (NAN, "nan"), (INF, "inf"), ("0.1", "'0.1'"), (True, "True")],
)
def test_sample_defects_rejects_bad_sigma(sigma: object, shown: str) -> None:
    with pytest.raises(ValueError, match="sigma") as error:
        sample_defects(CircularSocket(2, 2), sigma, rng=0)
    _check_message(error, "sigma", shown)


def test_sample_defects_rejects_non_specs() -> None:
    with pytest.raises(ValueError, match="spec"):
        sample_defects("2x2", 0.1, rng=0)


def test_public_api_is_exported() -> None:
    assert tolins.CircularSocket is CircularSocket
    assert tolins.PolygonSocket is PolygonSocket
    assert tolins.sample_defects is sample_defects
    assert {"CircularSocket", "PolygonSocket", "sample_defects", "make_mjcf"} <= set(tolins.__all__)
