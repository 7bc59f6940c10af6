"""The tolerance model against hand-computed limits, an independent polygon test, and its image."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

import tolins
from tolins import CircularSocket, PolygonSocket
from tolins.geometry import polygon_vertices
from tolins.tolerance import NO_TOLERANCE, WINDOWS, contains, extents, image

EPS = 1e-9
CIRCLE = CircularSocket(2, 2)  # pins 0.3 in holes 0.5: radial clearance 0.2 mm
#: Distance of the 2*2 socket's pins from the board origin.
LEVER = math.hypot(1.27, 3.81)
POLYGONS = [PolygonSocket(n, 1.5, 1.55) for n in range(3, 9)]


def _at(x: float = 0.0, y: float = 0.0, theta: float = 0.0) -> bool:
    return bool(contains(CIRCLE, [x, y, theta]))


def test_tolins_tolerance_is_there_after_import_tolins() -> None:
    assert tolins.tolerance.contains is contains


@pytest.mark.parametrize("axis", ["x", "y"])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_circle_translation_limit_is_the_radial_clearance(axis: str, sign: float) -> None:
    assert _at(**{axis: sign * (0.2 - EPS)})
    assert not _at(**{axis: sign * (0.2 + EPS)})
    diagonal = sign * 0.2 / math.sqrt(2)
    assert _at(diagonal * (1 - EPS), diagonal * (1 - EPS))
    assert not _at(diagonal * (1 + EPS), diagonal * (1 + EPS))


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_circle_rotation_limit_is_the_chord_equal_to_the_clearance(sign: float) -> None:
    # A pin at distance d turned by theta moves by the chord 2 d sin(theta / 2).
    limit = 2 * math.asin(0.2 / (2 * LEVER))
    assert _at(theta=sign * limit * (1 - EPS))
    assert not _at(theta=sign * limit * (1 + EPS))
    assert extents(CIRCLE).theta == pytest.approx((-limit, limit), rel=1e-12)
    assert extents(CIRCLE).x == pytest.approx((-0.2, 0.2), rel=1e-12)
    assert extents(CIRCLE).y == pytest.approx((-0.2, 0.2), rel=1e-12)


def test_circle_contains_matches_a_loop_over_the_pins() -> None:
    spec = tolins.sample_defects(CircularSocket(2, 3), 0.03, rng=3)
    poses = np.random.default_rng(0).normal(0.0, [0.1, 0.1, 0.01], (2000, 3))
    expected = []
    for x, y, theta in poses:
        rotation = np.array(
            [[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]]
        )
        moved = spec.pin_centers @ rotation.T + [x, y]
        distance = np.linalg.norm(moved - spec.hole_centers, axis=1)
        expected.append(bool(np.all(distance <= spec.hole_radius - spec.pin_radius)))
    assert contains(spec, poses).tolist() == expected
    assert 0.1 < np.mean(expected) < 0.9


@pytest.mark.parametrize("spec", POLYGONS, ids=lambda s: f"{s.sides}-gon")
def test_polygon_limits_by_hand(spec: PolygonSocket) -> None:
    n, big, small = spec.sides, spec.hole_circumradius, spec.pin_circumradius
    face_gap = (big - small) * math.cos(math.pi / n)  # along the face normal +x
    # -x points at a vertex for odd n (vertices at (2k+1)π/n), at a face for even n.
    back_gap = big - small if n % 2 else face_gap
    assert contains(spec, [face_gap - EPS, 0, 0]) and not contains(spec, [face_gap + EPS, 0, 0])
    assert contains(spec, [-back_gap + EPS, 0, 0])
    assert not contains(spec, [-back_gap - EPS, 0, 0])
    # Turning: the peg's corner (at R_pin) meets the hole's face (at r_hole) when
    # R_pin cos(π/n - theta) = r_hole.
    turn = math.pi / n - math.acos(big * math.cos(math.pi / n) / small)
    for sign in (1, -1):
        assert contains(spec, [0, 0, sign * turn * (1 - EPS)])
        assert not contains(spec, [0, 0, sign * turn * (1 + EPS)])
    result = extents(spec)
    assert result.x == pytest.approx((-back_gap, face_gap), rel=1e-9)
    assert result.theta == pytest.approx((-turn, turn), rel=1e-9)


def _shapely_contains(spec: PolygonSocket, pose: np.ndarray) -> bool:
    x, y, theta = pose
    peg = polygon_vertices(spec.sides, spec.pin_circumradius)
    rotation = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    moved = shapely.Polygon(peg @ rotation.T + [x, y])
    hole = shapely.Polygon(polygon_vertices(spec.sides, spec.hole_circumradius))
    return bool(hole.covers(moved))


@pytest.mark.parametrize("spec", [*POLYGONS, PolygonSocket(4, 1.5, 1.65)], ids=repr)
def test_polygon_contains_agrees_with_shapely(spec: PolygonSocket) -> None:
    gap, turn = spec.hole_circumradius - spec.pin_circumradius, extents(spec).theta[1]
    scale = [gap, gap, turn]
    poses = np.random.default_rng(spec.sides).uniform(-1, 1, (600, 3)) * scale
    ours = contains(spec, poses)
    assert ours.tolist() == [_shapely_contains(spec, pose) for pose in poses]
    assert 20 <= ours.sum() <= len(ours) - 20


def test_a_peg_that_fits_inside_the_hole_inradius_turns_freely() -> None:
    spec = PolygonSocket(6, 1.2, 1.65)
    assert extents(spec).theta == (-math.inf, math.inf)
    assert contains(spec, [[0, 0, t] for t in np.linspace(-4, 4, 41)]).all()
    values, cap = image(spec, 65), WINDOWS["polygon"].theta_cap
    assert values[32, 32] == cap and values.max() == cap
    assert 0 < values[32, 63] < cap  # off-centre the corners meet the faces again


def test_bent_pins_shift_the_tolerance() -> None:
    one_bent = CircularSocket(2, 1, pin_offsets=[[0.1, 0.0], [0.0, 0.0]])
    result = extents(one_bent)
    assert result.x == pytest.approx((-0.2, 0.1), abs=1e-12)  # [-0.3, 0.1] ∩ [-0.2, 0.2]
    assert result.y == pytest.approx((-math.sqrt(0.03), math.sqrt(0.03)), abs=1e-12)
    all_bent = CircularSocket(2, 1, pin_offsets=[[0.3, 0.0], [0.3, 0.0]])
    assert extents(all_bent).x == pytest.approx((-0.5, -0.1), abs=1e-12)
    assert not contains(all_bent, [0, 0, 0]) and contains(all_bent, [-0.3, 0, 0])
    assert all(math.isnan(v) for v in extents(all_bent).theta)
    # At theta = 0 a common bend d is a translation by d.
    shift = np.array([0.07, -0.04])
    bent = CircularSocket(2, 3, pin_offsets=np.tile(shift, (6, 1)))
    poses = np.random.default_rng(1).uniform(-0.3, 0.3, (1000, 3)) * [1, 1, 0]
    moved = poses + np.append(shift, 0.0)
    assert np.array_equal(contains(bent, poses), contains(CircularSocket(2, 3), moved))


def test_contains_keeps_the_batch_shape() -> None:
    poses = np.zeros((2, 5, 3))
    assert contains(CIRCLE, poses).shape == (2, 5)
    assert contains(POLYGONS[0], poses).shape == (2, 5)
    assert contains(CIRCLE, [0.0, 0.0, 0.0]).shape == ()


@pytest.mark.parametrize(
    ("poses", "match"),
    [
        ([0.0, 0.0], r"shape \(2,\).*\[\.\.\., 3\]"),
        (np.zeros((4, 4)), r"shape \(4, 4\)"),
        (1.0, r"shape \(\)"),
        ("abc", "not numeric"),
        ([[0.0, 0.0, np.nan]], r"poses\[0, 2\] = nan is not finite"),
        ([0.0, np.inf, 0.0], "not finite"),
    ],
)
def test_bad_poses_raise_a_clear_error(poses, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        contains(CIRCLE, poses)


def test_bad_spec_and_resolution_raise() -> None:
    with pytest.raises(ValueError, match="spec="):
        contains("2*2", [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="resolution"):
        image(CIRCLE, 1)
    with pytest.raises(ValueError, match="resolution"):
        image(CIRCLE, 16.0)


@pytest.mark.parametrize("spec", [CIRCLE, CircularSocket(2, 20), *POLYGONS[:4]], ids=repr)
def test_image_is_the_largest_theta_in_the_tolerance(spec) -> None:
    values = image(spec, 33)
    axis = WINDOWS[spec.family].axis(33)
    x, y = np.meshgrid(axis, axis)
    inside = values >= 0
    assert values.shape == (33, 33) and 5 <= inside.sum() < 0.9 * inside.size
    assert np.all(values[~inside] == NO_TOLERANCE)
    assert np.array_equal(inside, contains(spec, np.stack([x, y, 0 * x], axis=-1)))
    theta = np.where(inside, values, 0.0)
    below = contains(spec, np.stack([x, y, theta * (1 - EPS)], axis=-1))
    above = contains(spec, np.stack([x, y, theta * (1 + EPS) + 1e-12], axis=-1))
    assert below[inside].all() and not above[inside].any()


def test_image_centre_cell_is_the_theta_extent() -> None:
    for spec in (CIRCLE, CircularSocket(2, 20), POLYGONS[1]):
        assert image(spec, 65)[32, 32] == extents(spec).theta[1]
        assert WINDOWS[spec.family].axis(65)[32] == 0.0


@pytest.mark.parametrize(
    ("tight", "loose"),
    [
        (CircularSocket(2, 2), CircularSocket(2, 2, hole_radius=0.55)),
        (CircularSocket(2, 8), CircularSocket(2, 8, pin_radius=0.25)),
        (PolygonSocket(4, 1.5, 1.6), PolygonSocket(4, 1.5, 1.65)),
        (PolygonSocket(5, 1.5, 1.65), PolygonSocket(5, 1.45, 1.65)),
    ],
    ids=["circle-hole", "circle-pin", "square-hole", "pentagon-pin"],
)
def test_more_clearance_gives_pointwise_more_theta(tight, loose) -> None:
    small, large = image(tight), image(loose)
    assert np.all(large >= small)
    assert np.sum(large >= 0) > np.sum(small >= 0)


def test_more_pins_never_widen_the_image() -> None:
    """More pins, more constraints: the pins of 2*1 are among those of 2*3, and those of
    2*5 include both (same pitches, centred grids)."""
    images = [image(CircularSocket(2, cols)) for cols in (1, 3, 5)]
    assert np.all(images[0] >= images[1]) and np.all(images[1] >= images[2])
