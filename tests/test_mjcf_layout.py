"""The model layout mjcf exports: the addresses simulators read, the fields a bend changes."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from tolins import CircularSocket, PolygonSocket, make_mjcf, sample_defects
from tolins.mjcf import BEND_FIELDS, bend_fields, model_layout

SPECS = [
    pytest.param(CircularSocket(2, 2), id="2x2"),
    pytest.param(CircularSocket(2, 8), id="2x8"),
    pytest.param(CircularSocket(1, 1), id="1x1"),
    pytest.param(CircularSocket(3, 3, row_pitch=1.3, col_pitch=1.3), id="3x3-tight"),
    pytest.param(sample_defects(CircularSocket(2, 4), 0.1, rng=2020), id="bent-2x4"),
    pytest.param(sample_defects(CircularSocket(2, 2), None, rng=1, kind="blocked"), id="blocked"),
    *[pytest.param(PolygonSocket(s, 1.5, 1.65), id=f"{s}-gon") for s in (3, 4, 6)],
]


def _compile(spec: CircularSocket | PolygonSocket) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(make_mjcf(spec))


@pytest.mark.parametrize("spec", SPECS)
def test_the_layout_names_the_sensors_geoms_and_joints_mjcf_writes(spec) -> None:
    model = _compile(spec)
    layout = model_layout(model)
    assert layout.n_pins == spec.n_pins
    touch = [model.sensor(f"pin{i}_touch").adr[0] for i in range(spec.n_pins)]
    assert list(range(layout.touch.start, layout.touch.stop)) == touch
    assert layout.force == slice(model.sensor("force").adr[0], model.sensor("force").adr[0] + 3)
    assert layout.torque_z == model.sensor("torque").adr[0] + 2
    assert layout.pin_geoms == tuple(model.geom(f"pin{i}").id for i in range(spec.n_pins))
    assert layout.pin_by_geom == {g: i for i, g in enumerate(layout.pin_geoms)}
    qpos = [model.joint(name).qposadr[0] for name in ("x", "y", "theta", "z")]
    assert layout.pose_joint.tolist() == qpos
    pose = np.array([1.0, 2.0, 3.0, 4.0])
    assert np.array_equal(pose[layout.joint_pose][layout.pose_joint], pose)
    # The servos drive the joints in qpos order: act = qpos re-anchors each on its joint.
    assert model.actuator_trnid[:, 0].tolist() == [
        model.jnt_qposadr.tolist().index(q) for q in range(4)
    ]


def test_a_model_not_made_by_mjcf_is_refused() -> None:
    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
    with pytest.raises(RuntimeError, match="touch sensors"):
        model_layout(model)


def _bent_probes(socket: CircularSocket) -> list[CircularSocket]:
    """Two bends of ``socket``: every pin moved by ± half its allowed offset."""
    limit = 0.5 * np.asarray(socket.offset_limit)
    signs = np.where(np.arange(socket.n_pins)[:, None] % 2 == 0, 1.0, -1.0) * [1.0, -1.0]
    return [
        dataclasses.replace(socket, pin_offsets=tuple(map(tuple, sign * signs * limit)))
        for sign in (1.0, -1.0)
    ]


def _array_fields(model: mujoco.MjModel) -> set[str]:
    return {
        n
        for n in dir(model)
        if not n.startswith("_") and isinstance(getattr(model, n, None), np.ndarray)
    }


@pytest.mark.parametrize(
    "socket",
    [
        CircularSocket(2, 2),
        CircularSocket(2, 8),
        CircularSocket(1, 1),
        CircularSocket(3, 3, row_pitch=1.3, col_pitch=1.3),
    ],
    ids=repr,
)
def test_a_bend_changes_only_the_bend_fields(socket: CircularSocket) -> None:
    nominal = _compile(socket)
    names = _array_fields(nominal)
    assert set(BEND_FIELDS) <= names
    changed: set[str] = set()
    for probe in _bent_probes(socket):
        bent = _compile(probe)
        changed |= {n for n in names if not np.array_equal(getattr(nominal, n), getattr(bent, n))}
    assert changed <= set(BEND_FIELDS)
    assert {"geom_pos", "site_pos", "geom_size"} <= changed
    assert bend_fields(socket) == BEND_FIELDS


def test_a_polygon_peg_has_no_bend_fields() -> None:
    assert bend_fields(PolygonSocket(6, 1.2, 1.26)) == ()
