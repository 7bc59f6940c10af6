"""make_mjcf: determinism, compilation, naming, kinematics and the board surface."""

from __future__ import annotations

import math
import re

import mujoco
import numpy as np
import pytest
from spec_variants import one_field_variants

from tolins import CircularSocket, PolygonSocket, make_mjcf, sample_defects
from tolins.geometry import inradius

OBJ = mujoco.mjtObj

CIRCULAR = [
    *[pytest.param(CircularSocket(2, cols), id=f"2x{cols}") for cols in (1, 2, 4, 8, 20)],
    pytest.param(CircularSocket(1, 1), id="1x1"),
    pytest.param(CircularSocket(3, 5), id="3x5"),
    pytest.param(CircularSocket(2, 2, row_pitch=2.0, col_pitch=5.0), id="2x2-odd-pitches"),
]
DEFECTIVE = sample_defects(CircularSocket(2, 4), 0.1, rng=2020)
POLYGONS = [pytest.param(PolygonSocket(s, 1.5, 1.65), id=f"{s}-gon") for s in range(3, 9)]
ALL_SPECS = [*CIRCULAR, pytest.param(DEFECTIVE, id="defective-2x4"), *POLYGONS]


def _compile(spec: CircularSocket | PolygonSocket) -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_string(make_mjcf(spec))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def _id(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> int:
    index = mujoco.mj_name2id(model, kind, name)
    assert index >= 0, f"no {kind.name} named {name!r}"
    return index


def _names(model: mujoco.MjModel, kind: mujoco.mjtObj, count: int) -> list[str | None]:
    return [mujoco.mj_id2name(model, kind, i) for i in range(count)]


# --- determinism -------------------------------------------------------------------------


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_same_spec_gives_same_bytes(spec: CircularSocket | PolygonSocket) -> None:
    first, second = make_mjcf(spec), make_mjcf(spec)
    assert isinstance(first, str) and first
    assert first.encode() == second.encode()


def test_equal_specs_built_separately_give_same_bytes() -> None:
    offsets = sample_defects(CircularSocket(2, 3), 0.1, rng=4).offsets
    a = CircularSocket(2, 3, pin_offsets=offsets)
    b = CircularSocket(np.int64(2), 3, 0.3, 0.5, 7.62, 2.54, pin_offsets=offsets.tolist())
    assert a is not b and a == b
    assert make_mjcf(a).encode() == make_mjcf(b).encode()
    assert make_mjcf(CircularSocket(3, 5)) == make_mjcf(CircularSocket(3, 5))
    assert make_mjcf(PolygonSocket(6, 1.5, 1.65)) == make_mjcf(PolygonSocket(6, 1.5, 1.65))


def test_different_specs_give_different_models() -> None:
    specs = one_field_variants()
    assert len({make_mjcf(spec) for spec in specs}) == len(specs)


@pytest.mark.parametrize(
    "bad",
    [None, "CircularSocket(2, 2)", {"rows": 2, "cols": 2}, (2, 2), 4, CircularSocket],
    ids=["none", "str", "dict", "tuple", "int", "class"],
)
def test_rejects_non_spec(bad: object) -> None:
    with pytest.raises(ValueError, match="spec"):
        make_mjcf(bad)


# --- structure -------------------------------------------------------------------------------


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_every_element_has_a_unique_name(spec: CircularSocket | PolygonSocket) -> None:
    model, _ = _compile(spec)
    for kind, count in [
        (OBJ.mjOBJ_BODY, model.nbody),
        (OBJ.mjOBJ_JOINT, model.njnt),
        (OBJ.mjOBJ_GEOM, model.ngeom),
        (OBJ.mjOBJ_SITE, model.nsite),
        (OBJ.mjOBJ_ACTUATOR, model.nu),
        (OBJ.mjOBJ_SENSOR, model.nsensor),
        (OBJ.mjOBJ_MESH, model.nmesh),
    ]:
        names = _names(model, kind, count)
        assert all(names), f"unnamed {kind.name}: {names}"
        assert len(set(names)) == len(names), f"duplicate {kind.name} names"
    assert mujoco.mj_id2name(model, OBJ.mjOBJ_BODY, 0) == "world"


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_joints_actuators_and_sensors(spec: CircularSocket | PolygonSocket) -> None:
    model, _ = _compile(spec)
    workpiece = _id(model, OBJ.mjOBJ_BODY, "workpiece")
    assert _names(model, OBJ.mjOBJ_JOINT, model.njnt) == ["x", "y", "z", "theta"]
    expected_joints = {
        "x": (mujoco.mjtJoint.mjJNT_SLIDE, [1, 0, 0]),
        "y": (mujoco.mjtJoint.mjJNT_SLIDE, [0, 1, 0]),
        "z": (mujoco.mjtJoint.mjJNT_SLIDE, [0, 0, 1]),
        "theta": (mujoco.mjtJoint.mjJNT_HINGE, [0, 0, 1]),
    }
    for name, (joint_type, axis) in expected_joints.items():
        j = _id(model, OBJ.mjOBJ_JOINT, name)
        assert model.jnt_type[j] == joint_type
        np.testing.assert_array_equal(model.jnt_axis[j], axis)
        assert model.jnt_bodyid[j] == workpiece
    assert model.nq == 4 and model.nv == 4

    assert _names(model, OBJ.mjOBJ_ACTUATOR, model.nu) == ["ux", "uy", "uz", "utheta"]
    for actuator, joint in [("ux", "x"), ("uy", "y"), ("uz", "z"), ("utheta", "theta")]:
        a = _id(model, OBJ.mjOBJ_ACTUATOR, actuator)
        # intvelocity: an integrator activation driving a position servo.
        assert model.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_INTEGRATOR
        assert model.actuator_gaintype[a] == mujoco.mjtGain.mjGAIN_FIXED
        assert model.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_AFFINE
        assert model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
        assert model.actuator_trnid[a, 0] == _id(model, OBJ.mjOBJ_JOINT, joint)
        assert model.actuator_actlimited[a] and model.actuator_forcelimited[a]
        assert model.actuator_ctrllimited[a]
        low, high = model.actuator_ctrlrange[a]
        assert low == -high and high > 0
    assert model.na == 4

    sensors = _names(model, OBJ.mjOBJ_SENSOR, model.nsensor)
    assert sensors[:2] == ["force", "torque"]
    ft_site = _id(model, OBJ.mjOBJ_SITE, "ft_site")
    assert model.site_bodyid[ft_site] == _id(model, OBJ.mjOBJ_BODY, "pins")
    for name, sensor_type in [
        ("force", mujoco.mjtSensor.mjSENS_FORCE),
        ("torque", mujoco.mjtSensor.mjSENS_TORQUE),
    ]:
        s = _id(model, OBJ.mjOBJ_SENSOR, name)
        assert model.sensor_type[s] == sensor_type
        assert model.sensor_dim[s] == 3
        assert model.sensor_objtype[s] == OBJ.mjOBJ_SITE
        assert model.sensor_objid[s] == ft_site
    # The rest: one touch sensor per pin, on that pin's zone site (documented in make_mjcf).
    assert sensors[2:] == [f"pin{i}_touch" for i in range(spec.n_pins)]
    for i in range(spec.n_pins):
        s = _id(model, OBJ.mjOBJ_SENSOR, f"pin{i}_touch")
        assert model.sensor_type[s] == mujoco.mjtSensor.mjSENS_TOUCH
        assert model.sensor_objid[s] == _id(model, OBJ.mjOBJ_SITE, f"pin{i}_zone")


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_one_pin_geom_and_tip_site_per_pin(spec: CircularSocket | PolygonSocket) -> None:
    model, _ = _compile(spec)
    pins_body = _id(model, OBJ.mjOBJ_BODY, "pins")
    board = _id(model, OBJ.mjOBJ_BODY, "board")
    geom_names = _names(model, OBJ.mjOBJ_GEOM, model.ngeom)
    pin_geoms = [i for i, name in enumerate(geom_names) if re.fullmatch(r"pin\d+", name)]
    assert [geom_names[i] for i in pin_geoms] == [f"pin{i}" for i in range(spec.n_pins)]
    site_names = _names(model, OBJ.mjOBJ_SITE, model.nsite)
    tips = [name for name in site_names if re.fullmatch(r"pin\d+_tip", name)]
    assert tips == [f"pin{i}_tip" for i in range(spec.n_pins)]
    for g in pin_geoms:
        assert model.geom_bodyid[g] == pins_body
    # The pins and the carrier above them collide with the board and the board with them,
    # nothing else does.
    carrier = _id(model, OBJ.mjOBJ_GEOM, "carrier")
    colliding = [
        g for g in range(model.ngeom) if model.geom_contype[g] or model.geom_conaffinity[g]
    ]
    assert set(colliding) == {*pin_geoms, carrier} | set(_board_geoms(model))
    for g in [*pin_geoms, carrier]:
        for b in _board_geoms(model):
            assert model.geom_contype[g] & model.geom_conaffinity[b]
            assert not model.geom_contype[g] & model.geom_conaffinity[g]
            assert not model.geom_contype[b] & model.geom_conaffinity[b]
    assert model.body_parentid[pins_body] == _id(model, OBJ.mjOBJ_BODY, "workpiece")
    assert model.body_jntnum[pins_body] == 0
    assert model.body_jntnum[board] == 0 and model.body_parentid[board] == 0


# --- kinematics ------------------------------------------------------------------------------


def _tips(model: mujoco.MjModel, data: mujoco.MjData, n: int) -> np.ndarray:
    return np.array([data.site_xpos[_id(model, OBJ.mjOBJ_SITE, f"pin{i}_tip")] for i in range(n)])


def _lowest_point(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> float:
    return float(_geom_world_points(model, data, g)[:, 2].min())


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_pin_tips_sit_at_pin_centers_on_the_board_surface(
    spec: CircularSocket | PolygonSocket,
) -> None:
    model, data = _compile(spec)
    np.testing.assert_array_equal(data.qpos, np.zeros(4))
    tips = _tips(model, data, spec.n_pins)
    np.testing.assert_allclose(tips[:, :2], spec.pin_centers, atol=1e-9)
    np.testing.assert_allclose(tips[:, 2], 0.0, atol=1e-9)
    # The pin geoms end at their tips.
    for i, (x, y) in enumerate(spec.pin_centers):
        g = _id(model, OBJ.mjOBJ_GEOM, f"pin{i}")
        # (Mesh vertices are stored in float32, hence the looser tolerance.)
        assert _lowest_point(model, data, g) == pytest.approx(0.0, abs=1e-6)
        points = _geom_world_points(model, data, g)
        np.testing.assert_allclose(points[:, :2].mean(axis=0), (x, y), atol=1e-6)


def test_defective_pin_tips_are_displaced_from_the_holes() -> None:
    model, data = _compile(DEFECTIVE)
    tips = _tips(model, data, DEFECTIVE.n_pins)
    np.testing.assert_allclose(tips[:, :2] - DEFECTIVE.hole_centers, DEFECTIVE.offsets, atol=1e-9)
    assert np.all(np.linalg.norm(DEFECTIVE.offsets, axis=1) > 1e-6)


@pytest.mark.parametrize(
    "spec",
    [
        pytest.param(CircularSocket(3, 5), id="3x5"),
        pytest.param(DEFECTIVE, id="defective"),
        pytest.param(PolygonSocket(5, 1.5, 1.65), id="5-gon"),
    ],
)
@pytest.mark.parametrize(
    "pose",
    [(1.0, 0.0, 0.0, 0.0), (0.0, -2.0, 0.0, 3.0), (0.0, 0.0, 0.3, 0.0), (1.5, -0.7, -0.8, 2.5)],
)
def test_moving_the_joints_rotates_about_the_origin_then_translates(
    spec: CircularSocket | PolygonSocket, pose: tuple[float, float, float, float]
) -> None:
    model, data = _compile(spec)
    x, y, theta, z = pose
    for name, value in {"x": x, "y": y, "z": z, "theta": theta}.items():
        data.qpos[model.jnt_qposadr[_id(model, OBJ.mjOBJ_JOINT, name)]] = value
    mujoco.mj_forward(model, data)
    c, s = math.cos(theta), math.sin(theta)
    rotation = np.array([[c, -s], [s, c]])
    expected_xy = spec.pin_centers @ rotation.T + np.array([x, y])
    tips = _tips(model, data, spec.n_pins)
    np.testing.assert_allclose(tips[:, :2], expected_xy, atol=1e-9)
    np.testing.assert_allclose(tips[:, 2], z, atol=1e-9)
    # The board does not move.
    for g in _board_geoms(model)[:3]:
        assert model.geom_bodyid[g] == _id(model, OBJ.mjOBJ_BODY, "board")
    np.testing.assert_allclose(data.xpos[_id(model, OBJ.mjOBJ_BODY, "board")], 0.0)


# --- the board ---------------------------------------------------------------------------------


def _board_geoms(model: mujoco.MjModel) -> list[int]:
    board = _id(model, OBJ.mjOBJ_BODY, "board")
    return [g for g in range(model.ngeom) if model.geom_bodyid[g] == board]


def _geom_world_points(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> np.ndarray:
    """World coordinates of a box's corners, a cylinder's rim points or a mesh's vertices."""
    kind = model.geom_type[g]
    size = model.geom_size[g]
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        mesh = model.geom_dataid[g]
        start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        local = model.mesh_vert[start : start + count].astype(float)
    elif kind == mujoco.mjtGeom.mjGEOM_BOX:
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        local = signs * size
    elif kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
        ring = np.stack([np.cos(angles), np.sin(angles)], axis=1) * size[0]
        local = np.concatenate(
            [np.column_stack([ring, np.full(16, h)]) for h in (-size[1], size[1])]
        )
    else:
        raise AssertionError(f"unexpected geom type {kind}")
    return data.geom_xpos[g] + local @ data.geom_xmat[g].reshape(3, 3).T


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_board_geoms_have_their_top_at_zero(spec: CircularSocket | PolygonSocket) -> None:
    model, data = _compile(spec)
    board_geoms = _board_geoms(model)
    names = [mujoco.mj_id2name(model, OBJ.mjOBJ_GEOM, g) for g in board_geoms]
    sides = 16 if isinstance(spec, CircularSocket) else spec.sides
    walls = [n for n in names if re.fullmatch(r"hole\d+_wall\d+", n)]
    assert len(walls) == spec.n_pins * sides
    assert any(n.startswith("board_box") for n in names)
    tops, bottoms = [], []
    for g in board_geoms:
        points = _geom_world_points(model, data, g)
        tops.append(points[:, 2].max())
        bottoms.append(points[:, 2].min())
    # (Mesh vertices are stored in float32; the ray tests below check z = 0 to 1e-9.)
    np.testing.assert_allclose(tops, 0.0, atol=1e-6)
    # A plate of one thickness.
    assert max(bottoms) < -0.5
    np.testing.assert_allclose(bottoms, bottoms[0], atol=1e-6)


def _board_only_model(spec: CircularSocket | PolygonSocket) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The compiled model with every geom but the board's moved out of geom group 0."""
    model, data = _compile(spec)
    board = set(_board_geoms(model))
    for g in range(model.ngeom):
        model.geom_group[g] = 0 if g in board else 5
    return model, data


_GROUP0 = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
_DOWN = np.array([0.0, 0.0, -1.0])
_START_Z = 10.0


def _ray_down(model: mujoco.MjModel, data: mujoco.MjData, xy: np.ndarray) -> tuple[float, int]:
    geomid = np.array([-1], dtype=np.int32)
    point = np.array([xy[0], xy[1], _START_Z])
    distance = mujoco.mj_ray(model, data, point, _DOWN, _GROUP0, 1, -1, geomid)
    return distance, int(geomid[0])


def _hole_shape(spec: CircularSocket | PolygonSocket) -> tuple[float, float]:
    """Inradius and circumradius of a hole."""
    if isinstance(spec, CircularSocket):
        return spec.hole_radius, spec.hole_circumradius
    return inradius(spec.sides, spec.hole_circumradius), spec.hole_circumradius


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_rays_pass_through_the_holes(spec: CircularSocket | PolygonSocket) -> None:
    model, data = _board_only_model(spec)
    hole_in, _ = _hole_shape(spec)
    angles = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    for center in spec.hole_centers:
        points = [center] + [
            center + 0.95 * hole_in * np.array([np.cos(a), np.sin(a)]) for a in angles
        ]
        for point in points:
            distance, geomid = _ray_down(model, data, point)
            assert geomid == -1 and distance == -1, (
                f"ray at {point} inside a hole hit geom "
                f"{mujoco.mj_id2name(model, OBJ.mjOBJ_GEOM, geomid)} at z={_START_Z - distance}"
            )


@pytest.mark.parametrize("spec", ALL_SPECS)
def test_rays_between_holes_hit_the_board_top_at_zero(spec: CircularSocket | PolygonSocket) -> None:
    model, data = _board_only_model(spec)
    _, hole_out = _hole_shape(spec)
    centers = spec.hole_centers
    points = []
    # Just outside each hole, all around it (inside the thinnest wall allowed, 0.2 mm).
    angles = np.linspace(0, 2 * np.pi, 24, endpoint=False) + 0.01
    for center in centers:
        points += [center + (hole_out + 0.05) * np.array([np.cos(a), np.sin(a)]) for a in angles]
    if isinstance(spec, CircularSocket):
        nominal = spec.nominal()
        grid = nominal.hole_centers.reshape(spec.rows, spec.cols, 2)
        # Between neighbours in a row and between rows (a little off the seam between cells).
        points += list(((grid[:, 1:] + grid[:, :-1]) / 2 + [0.03, 0.01]).reshape(-1, 2))
        points += list(((grid[1:] + grid[:-1]) / 2 + [0.01, 0.03]).reshape(-1, 2))
    # Beyond the outermost holes.
    reach = np.abs(centers).max(axis=0) + hole_out + 1.5
    points += [np.array([sx * reach[0], sy * reach[1]]) for sx in (-1, 1) for sy in (-1, 1)]
    points += [np.array([reach[0], 0.01]), np.array([0.01, -reach[1]])]
    board = set(_board_geoms(model))
    for point in points:
        distance, geomid = _ray_down(model, data, point)
        assert geomid in board, f"ray at {point} missed the board"
        assert _START_Z - distance == pytest.approx(0.0, abs=1e-9), f"board top at {point}"


def test_touch_zones_of_strongly_bent_neighbours_do_not_overlap() -> None:
    spec = CircularSocket(1, 2, pin_offsets=[[0.9, 0.0], [-0.9, 0.0]])
    model = mujoco.MjModel.from_xml_string(make_mjcf(spec))
    zones = [model.site(f"pin{i}_zone") for i in range(2)]
    gap = abs(zones[0].pos[0] - zones[1].pos[0])
    assert zones[0].size[0] + zones[1].size[0] <= gap + 1e-12
    assert zones[0].size[0] >= spec.pin_radius
