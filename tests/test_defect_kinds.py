"""Defect kinds beyond bent pins: pitch error, burred, short pins, blocked holes.

Each kind's geometry is checked against a computation from the spec's numbers alone (not
through ``pin_centers`` or the tolerance module), then in MuJoCo: a pitch error moves
the pins, a burred pin blocks at a smaller offset, a short pin meets the board later, a
blocked hole never lets the workpiece in.
"""

from __future__ import annotations

import dataclasses
import json

import mujoco
import numpy as np
import pytest
from rollouts import push_down

from tolins import CircularSocket, sample_defects
from tolins.envs import InsertionEnv
from tolins.geometry.defects import DEFECT_KINDS
from tolins.geometry.specs import workpiece_dict
from tolins.geometry.tolerance import contains, extents, image, pins_inside_pose
from tolins.geometry.workspace import in_holes
from tolins.mjcf import make_mjcf

SOCKET = CircularSocket(2, 2)


def _pins_by_hand(rows, cols, row_pitch, col_pitch, scale=(1.0, 1.0)):
    """Pin centres of a grid, row-major, with the pins' spacing scaled."""
    return np.array(
        [
            [
                (c - (cols - 1) / 2) * col_pitch * scale[0],
                (r - (rows - 1) / 2) * row_pitch * scale[1],
            ]
            for r in range(rows)
            for c in range(cols)
        ]
    )


def _inside_by_hand(pins, holes, clearances, pose):
    """Every pin within its clearance of its hole, pins rotated about the origin."""
    x, y, theta = pose
    c, s = np.cos(theta), np.sin(theta)
    moved = np.column_stack(
        [c * pins[:, 0] - s * pins[:, 1] + x, s * pins[:, 0] + c * pins[:, 1] + y]
    )
    distance = np.hypot(*(moved - holes).T)
    return bool(np.all(distance <= clearances))


def _random_poses(n=400, seed=0):
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.3, 0.3, (n, 2)), rng.uniform(-0.06, 0.06, n)])


def test_pitch_error_scales_the_pins_spacing_in_the_tolerance() -> None:
    spec = dataclasses.replace(CircularSocket(2, 8), pin_pitch_scale=(1.004, 0.99))
    holes = _pins_by_hand(2, 8, 7.62, 2.54)
    pins = _pins_by_hand(2, 8, 7.62, 2.54, (1.004, 0.99))
    assert np.allclose(spec.pin_centers, pins, atol=1e-12)
    assert np.allclose(spec.hole_centers, holes, atol=1e-12)
    poses = _random_poses()
    expected = [_inside_by_hand(pins, holes, np.full(16, 0.2), p) for p in poses]
    assert np.array_equal(contains(spec, poses), expected)
    assert 0 < sum(expected) < len(expected)  # both outcomes occur
    # The outer pins sit 8.89 * 0.004 mm and 3.81 * 0.01 mm off: the x extent shrinks.
    low, high = extents(spec).x
    across = 3.81 * 0.01
    half = np.sqrt(0.2**2 - across**2)
    assert low == pytest.approx(8.89 * 0.004 - half) and high == pytest.approx(-8.89 * 0.004 + half)


def test_burred_pins_use_their_own_clearance() -> None:
    burrs = (0.0, 0.08, 0.0, 0.25)  # pin 3's radius 0.55 mm exceeds its 0.5 mm hole
    spec = dataclasses.replace(SOCKET, pin_burrs=(*burrs[:3], 0.0))
    holes = _pins_by_hand(2, 2, 7.62, 2.54)
    clearances = 0.5 - 0.3 - np.array((*burrs[:3], 0.0))
    poses = _random_poses()
    expected = [_inside_by_hand(holes, holes, clearances, p) for p in poses]
    assert np.array_equal(contains(spec, poses), expected)
    assert extents(spec).x == pytest.approx((-0.12, 0.12))
    never = dataclasses.replace(SOCKET, pin_burrs=burrs)
    assert not contains(never, poses).any() and not contains(never, [0.0, 0.0, 0.0])
    assert np.all(image(never, 16) < 0)
    assert never.pin_reach == pytest.approx(0.55)


def test_a_blocked_hole_is_never_inside_nor_a_success() -> None:
    spec = dataclasses.replace(SOCKET, blocked_holes=(2,))
    assert not contains(spec, _random_poses()).any()
    assert np.all(image(spec, 16) < 0) and np.isnan(extents(spec).x).all()
    assert pins_inside_pose(spec, [0.0, 0.0, 0.0]).tolist() == [True, True, False, True]
    assert not in_holes(spec, [0.0, 0.0, 0.0, -2.0], 1.0)
    assert in_holes(SOCKET, [0.0, 0.0, 0.0, -2.0], 1.0)


def test_short_pins_leave_the_tolerance_as_it_is() -> None:
    spec = dataclasses.replace(SOCKET, pin_shortenings=(0.5, 0.0, 0.0, 1.0))
    poses = _random_poses()
    assert np.array_equal(contains(spec, poses), contains(SOCKET, poses))


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("pin_pitch_scale", (1.2, 1.0), "out of range"),
        ("pin_pitch_scale", (1.0,), "shape"),
        ("pin_burrs", (0.1, 0.1, 0.1), "shape"),
        ("pin_burrs", (-0.1, 0.0, 0.0, 0.0), "out of range"),
        ("pin_shortenings", (0.0, 0.0, 0.0, 2.5), "out of range"),
        ("blocked_holes", (4,), "too large"),
        ("blocked_holes", (1, 1), "repeats"),
        ("blocked_holes", 1, "not a tuple"),
    ],
)
def test_defect_fields_are_validated(field, value, match) -> None:
    with pytest.raises(ValueError, match=match):
        dataclasses.replace(SOCKET, **{field: value})


def test_a_pin_pushed_out_of_its_cell_by_pitch_and_burr_is_refused() -> None:
    # 2*8: the outermost pin at x = 8.89 mm; pitch +10 % moves it 0.889 mm, its cell allows
    # 2.54 / 2 - 0.3 = 0.97 mm, less a 0.1 mm burr.
    dataclasses.replace(CircularSocket(2, 8), pin_pitch_scale=(1.1, 1.0))
    with pytest.raises(ValueError, match="out of its cell"):
        CircularSocket(2, 8, pin_pitch_scale=(1.1, 1.0), pin_burrs=(0.1,) * 16)


def test_bent_pin_draws_are_unchanged() -> None:
    rng = np.random.default_rng(5)
    expected = rng.normal(0.0, 0.1, size=(4, 2))
    assert np.array_equal(sample_defects(SOCKET, 0.1, 5).offsets, expected)
    assert sample_defects(SOCKET, 0.1, 5) == sample_defects(SOCKET, 0.1, 5, kind="bent")


@pytest.mark.parametrize("kind", DEFECT_KINDS[1:])
def test_each_kind_is_drawn_reproducibly_into_its_own_field(kind) -> None:
    sigma = {"pitch": 0.005, "burr": 0.05, "short": 0.5, "blocked": None}[kind]
    base = sample_defects(CircularSocket(2, 4), 0.05, 0)  # bends stay
    drawn = [sample_defects(base, sigma, seed, kind=kind) for seed in range(6)]
    assert drawn[0] == sample_defects(base, sigma, 0, kind=kind)
    assert len(set(drawn)) > 1 and all(d.is_defective for d in drawn)
    assert all(d.pin_offsets == base.pin_offsets for d in drawn)
    field = {
        "pitch": "pin_pitch_scale",
        "burr": "pin_burrs",
        "short": "pin_shortenings",
        "blocked": "blocked_holes",
    }[kind]
    assert all(getattr(d, field) for d in drawn)
    assert all(d.nominal() == CircularSocket(2, 4) for d in drawn)


def test_sample_defects_refuses_unknown_kinds_and_scales() -> None:
    with pytest.raises(ValueError, match="unknown"):
        sample_defects(SOCKET, 0.1, 0, kind="cracked")
    with pytest.raises(ValueError, match="None"):
        sample_defects(SOCKET, 0.1, 0, kind="blocked")
    with pytest.raises(ValueError, match="too large"):
        sample_defects(SOCKET, 0.5, 0, kind="pitch")


def test_mjcf_places_each_defect() -> None:
    spec = CircularSocket(
        2,
        2,
        pin_pitch_scale=(1.01, 0.995),
        pin_burrs=(0.0, 0.05, 0.0, 0.0),
        pin_shortenings=(0.0, 0.0, 0.7, 0.0),
        blocked_holes=(1,),
    )
    model = mujoco.MjModel.from_xml_string(make_mjcf(spec))
    pins = _pins_by_hand(2, 2, 7.62, 2.54, (1.01, 0.995))
    for i in range(4):
        geom = model.geom(f"pin{i}")
        assert np.allclose(geom.pos[:2], pins[i])
        assert geom.size[0] == pytest.approx(0.3 + spec.burrs[i])
        assert geom.pos[2] - geom.size[1] == pytest.approx(spec.shortenings[i])  # tip
    plug = model.geom("plug1")
    assert np.allclose(plug.pos[:2], spec.hole_centers[1]) and plug.pos[2] + plug.size[2] == 0
    assert make_mjcf(spec, contact_pairs=True).count('geom1="plug1"') == 4  # every pin
    assert "plug" not in make_mjcf(SOCKET)


def _depth(spec, pose, backend="mujoco", steps=6):
    infos = push_down(spec, pose, steps=steps, backend=backend)
    return infos[-1]


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_a_blocked_hole_never_succeeds(backend) -> None:
    spec = dataclasses.replace(SOCKET, blocked_holes=(3,))
    info = _depth(spec, [0.0, 0.0, 0.0, 0.05], backend, steps=12)
    assert not info["success"] and info["pose"][3] > -0.01
    assert _depth(SOCKET, [0.0, 0.0, 0.0, 0.05], backend)["success"]


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_a_short_pin_meets_the_board_later(backend) -> None:
    outside = [0.3, 0.0, 0.0, 0.05]  # every pin 0.1 mm beyond its clearance
    assert _depth(SOCKET, outside, backend)["pose"][3] == pytest.approx(0.0, abs=2e-3)
    short = dataclasses.replace(SOCKET, pin_shortenings=(0.6,) * 4)
    assert _depth(short, outside, backend)["pose"][3] == pytest.approx(-0.6, abs=2e-3)
    # One short pin: the full-length ones meet the board first.
    one = dataclasses.replace(SOCKET, pin_shortenings=(0.6, 0.0, 0.0, 0.0))
    assert _depth(one, outside, backend)["pose"][3] == pytest.approx(0.0, abs=2e-3)
    # Pins 1-3 in their holes, pin 0 (short) outside: it stops the workpiece 0.6 mm down.
    bent = dataclasses.replace(one, pin_offsets=((0.4, 0.0), (0.0, 0.0), (0.0, 0.0), (0.0, 0.0)))
    info = _depth(bent, [0.0, 0.0, 0.0, 0.05], backend)
    assert info["pose"][3] == pytest.approx(-0.6, abs=2e-3) and not info["success"]


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_a_burred_pin_blocks_at_a_smaller_offset(backend) -> None:
    burred = dataclasses.replace(SOCKET, pin_burrs=(0.0, 0.0, 0.1, 0.0))  # clearance 0.1
    assert _depth(SOCKET, [0.15, 0.0, 0.0, 0.05], backend)["success"]
    assert not _depth(burred, [0.15, 0.0, 0.0, 0.05], backend)["success"]
    assert _depth(burred, [0.08, 0.0, 0.0, 0.05], backend)["success"]


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_pitch_error_moves_the_pins(backend) -> None:
    # Columns 2.54 * 1.1 mm apart: each pin 0.127 mm off its hole along x.
    pitched = dataclasses.replace(SOCKET, pin_pitch_scale=(1.1, 1.0))
    assert _depth(pitched, [0.0, 0.0, 0.0, 0.05], backend)["success"]
    # 0.1 mm to the right: the right-hand pins are 0.227 mm off, beyond the clearance.
    assert not _depth(pitched, [0.1, 0.0, 0.0, 0.05], backend)["success"]
    assert _depth(SOCKET, [0.1, 0.0, 0.0, 0.05], backend)["success"]


def test_reset_info_carries_the_workpiece() -> None:
    spec = CircularSocket(2, 1, pin_burrs=(0.0, 0.02), blocked_holes=(0,))
    env = InsertionEnv(spec, backend="kinematic")
    _, info = env.reset(seed=0)
    workpiece = json.loads(json.dumps(info["workpiece"]))
    fields = {k: v for k, v in workpiece.items() if k not in ("type", "defective")}
    assert workpiece["type"] == "CircularSocket" and workpiece["defective"]
    assert CircularSocket(**fields) == spec
    _, _, _, _, step_info = env.step([0.0, 0.0, 0.0, 0.0])
    assert "workpiece" not in step_info
    assert workpiece_dict(SOCKET)["defective"] is False


def test_the_inference_counts_pitch_error_burrs_and_blocked_holes() -> None:
    from tolins.geometry.tolerance import pins_inside
    from tolins.inference.goal import inside_matrix

    spec = CircularSocket(2, 2, pin_pitch_scale=(1.03, 1.0), pin_burrs=(0.0, 0.06, 0.0, 0.0))
    rng = np.random.default_rng(4)
    offsets = rng.normal(0.0, 0.05, (300, 4, 2))
    goals = np.column_stack([rng.uniform(-0.1, 0.1, (40, 2)), rng.uniform(-0.02, 0.02, 40)])
    expected = pins_inside(spec, offsets[:, None], goals[None]).all(-1)
    assert np.array_equal(inside_matrix(spec, offsets, goals), expected)
    assert 0 < expected.mean() < 1
    blocked = dataclasses.replace(spec, blocked_holes=(0,))
    assert not inside_matrix(blocked, offsets, goals).any()


def test_dataset_metadata_keeps_every_kind() -> None:
    from tolins.datasets.envspec import decode, encode

    spec = CircularSocket(
        2,
        2,
        pin_offsets=((0.01, 0.0),) * 4,
        pin_pitch_scale=(1.01, 1.0),
        pin_burrs=(0.0, 0.1, 0.0, 0.0),
        pin_shortenings=(0.0, 0.0, 0.3, 0.0),
        blocked_holes=(1,),
    )
    assert decode(json.loads(json.dumps(encode(spec)))) == spec


@pytest.mark.parametrize(
    ("defects", "field"),
    [
        (("pitch", 0.005), "pin_pitch_scale"),
        (("burr", 0.05), "pin_burrs"),
        (("short", 0.3), "pin_shortenings"),
        (("blocked", None), "blocked_holes"),
    ],
)
def test_the_env_draws_a_kind_per_reset(defects, field) -> None:
    env = InsertionEnv(CircularSocket(2, 4), backend="kinematic", defects=defects)
    drawn = [env.reset(seed=s)[1]["workpiece"][field] for s in (0, 1, 2, 0)]
    assert all(drawn) and drawn[0] == drawn[3] and len({json.dumps(d) for d in drawn}) > 1
    assert env.socket == CircularSocket(2, 4, **{field: tuple(drawn[3])})
    # With defect_sigma the bend is drawn first, as without defects.
    both = InsertionEnv(SOCKET, backend="kinematic", defect_sigma=0.05, defects=defects)
    bent = InsertionEnv(SOCKET, backend="kinematic", defect_sigma=0.05)
    assert (
        both.reset(seed=3)[1]["workpiece"]["pin_offsets"]
        == (bent.reset(seed=3)[1]["workpiece"]["pin_offsets"])
    )


@pytest.mark.parametrize(
    ("defects", "match"),
    [
        (("cracked", 0.1), "unknown"),
        (("blocked", 0.1), "None"),
        (("burr", 0.9), "too large"),
        ("burr", "allowed"),
    ],
)
def test_the_env_refuses_bad_defects(defects, match) -> None:
    with pytest.raises(ValueError, match=match):
        InsertionEnv(SOCKET, backend="kinematic", defects=defects)


def test_the_vector_env_draws_kinds_as_the_single_env() -> None:
    from tolins.envs.vector import InsertionVectorEnv

    vector = InsertionVectorEnv(3, SOCKET, backend="kinematic", defects=("short", 0.4))
    _, info = vector.reset(seed=7)
    for i in range(3):
        single = InsertionEnv(SOCKET, backend="kinematic", defects=("short", 0.4))
        expected = single.reset(seed=7 + i)[1]["workpiece"]["pin_shortenings"]
        assert list(info["workpiece"]["pin_shortenings"][i]) == expected
    with pytest.raises(ValueError, match="not supported"):
        InsertionVectorEnv(2, SOCKET, backend="mujoco", defects=("blocked", None))
