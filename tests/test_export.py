"""`tolins export`: a workpiece as a mesh a CAD tool or slicer opens, or its MJCF model.

Each file is loaded back with trimesh and measured: every body closed, the pins' radii,
places (bends included) and lengths, the holes' face distances, the board's size and
thickness, against the spec and the MJCF model's own geometry.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from tolins.cli import main
from tolins.geometry.spec_json import spec_from_json, spec_from_mapping
from tolins.geometry.specs import (
    CircularSocket,
    PolygonSocket,
    SocketSpec,
    inradius,
    workpiece_dict,
)
from tolins.geometry.workspace import PIN_LENGTH
from tolins.mjcf import make_mjcf
from tolins.mjcf.export import GLTF_FROM_TOLINS, export_bytes
from tolins.mjcf.mesh import PIN_SECTIONS, WORKPIECE_LIFT, socket_parts
from tolins.mjcf.model import BOARD_THICKNESS, board_filler_boxes, hole_shape

NOMINAL = CircularSocket(rows=2, cols=2)
BENT = CircularSocket(
    rows=2,
    cols=1,
    pin_offsets=((0.12, -0.05), (-0.08, 0.15)),
    pin_burrs=(0.0, 0.04),
    pin_shortenings=(0.6, 0.0),
    blocked_holes=(1,),
)
HEXAGON = PolygonSocket(sides=6, pin_circumradius=1.2, hole_circumradius=1.26)
#: mm: binary STL and glTF hold float32 (7 digits); 10 nm is 1/2000 of the finest clearance (20 µm)
TOL = 1e-5


def _export(tmp_path: Path, spec: SocketSpec, suffix: str, *extra: str) -> Path:
    out = tmp_path / f"part{suffix}"
    socket = json.dumps(workpiece_dict(spec))
    assert main(["export", "--socket", socket, "--out", str(out), *extra]) == 0
    return out


def _stl_bodies(path: Path) -> list[trimesh.Trimesh]:
    mesh = trimesh.load(path, file_type="stl")
    return mesh.split(only_watertight=False)


def _glb_bodies(path: Path) -> dict[str, trimesh.Trimesh]:
    """The scene's nodes, moved back from glTF's frame (m, y up) to tolins's (mm, z up)."""
    scene = trimesh.load(path, file_type="glb", force="scene")
    back = np.linalg.inv(GLTF_FROM_TOLINS)
    bodies = {}
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        mesh = scene.geometry[name].copy()
        mesh.apply_transform(back @ transform)
        bodies[node] = mesh
    return bodies


def _face_distances(mesh: trimesh.Trimesh, center: np.ndarray, within: float) -> np.ndarray:
    """Distances from the vertical axis through ``center`` (xy) to the planes of ``mesh``'s
    side faces whose centroids lie within ``within`` of it."""
    normals, centroids = mesh.face_normals, mesh.triangles_center
    side = np.abs(normals[:, 2]) < 1e-9
    near = np.linalg.norm(centroids[:, :2] - center, axis=1) < within
    pick = side & near
    return np.abs(np.einsum("ij,ij->i", normals[pick, :2], centroids[pick, :2] - center))


def _board_of(bodies: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    (board,) = [b for b in bodies if b.bounds[0, 2] < -TOL]
    return board


def _pins_of(bodies: list[trimesh.Trimesh], lift: float) -> list[trimesh.Trimesh]:
    pins = [b for b in bodies if b.bounds[1, 2] <= lift + PIN_LENGTH + TOL and b.bounds[0, 2] >= 0]
    return sorted(pins, key=lambda b: (round(b.centroid[1], 3), round(b.centroid[0], 3)))


def _check_board(board: trimesh.Trimesh, spec: SocketSpec, open_holes: list[int]) -> None:
    """The board's size, thickness and holes, measured on its mesh."""
    assert board.is_watertight and board.is_winding_consistent
    boxes = board_filler_boxes(spec)  # the MJCF model's boxes reach the board's edges
    low = np.min([c - h for c, h in boxes], axis=0)
    high = np.max([c + h for c, h in boxes], axis=0)
    np.testing.assert_allclose(board.bounds[:, :2], [low, high], atol=TOL)
    np.testing.assert_allclose(board.bounds[:, 2], [-BOARD_THICKNESS, 0.0], atol=TOL)
    assert math.isclose(np.ptp(board.bounds[:, 2]), BOARD_THICKNESS, abs_tol=TOL)
    sides, circumradius = hole_shape(spec)
    face = inradius(sides, circumradius)  # a round hole's: its hole_radius
    hole_area = 0.5 * sides * circumradius**2 * math.sin(2 * math.pi / sides)
    plate = float(np.prod(high - low))
    expected = (plate - len(open_holes) * hole_area) * BOARD_THICKNESS
    assert math.isclose(board.volume, expected, rel_tol=1e-6)
    for h, center in enumerate(spec.hole_centers):
        distances = _face_distances(board, center, 1.5 * circumradius)
        if h in open_holes:
            assert len(distances) == 2 * sides  # two triangles per face of the hole
            np.testing.assert_allclose(distances, face, atol=TOL)
        else:
            assert len(distances) == 0  # plugged: solid board


def _check_round_pins(pins: list[trimesh.Trimesh], spec: CircularSocket, lift: float) -> None:
    assert len(pins) == spec.n_pins
    for i, pin in enumerate(pins):
        assert pin.is_watertight and pin.is_winding_consistent
        axis = pin.vertices[:, :2].mean(axis=0)
        np.testing.assert_allclose(axis, spec.pin_centers[i], atol=TOL)  # bends included
        radii = np.linalg.norm(pin.vertices[:, :2] - axis, axis=1)
        np.testing.assert_allclose(radii, spec.pin_radii[i], atol=TOL)  # burrs included
        faces = _face_distances(pin, axis, 2 * spec.pin_radii[i])
        np.testing.assert_allclose(
            faces, spec.pin_radii[i] * math.cos(math.pi / PIN_SECTIONS), atol=TOL
        )
        tip = lift + spec.shortenings[i]
        np.testing.assert_allclose(pin.bounds[:, 2], [tip, lift + PIN_LENGTH], atol=TOL)


def test_a_nominal_2x2_as_stl_measures_as_its_spec(tmp_path: Path) -> None:
    bodies = _stl_bodies(_export(tmp_path, NOMINAL, ".stl"))
    assert len(bodies) == 1 + NOMINAL.n_pins + 1  # board, pins, carrier
    assert all(b.is_watertight for b in bodies)
    _check_board(_board_of(bodies), NOMINAL, open_holes=[0, 1, 2, 3])
    _check_round_pins(_pins_of(bodies, WORKPIECE_LIFT), NOMINAL, WORKPIECE_LIFT)
    assert NOMINAL.pin_radius == 0.3 and NOMINAL.hole_radius == 0.5  # what was measured


def test_a_bent_socket_as_stl_keeps_its_defects(tmp_path: Path) -> None:
    bodies = _stl_bodies(_export(tmp_path, BENT, ".stl"))
    assert all(b.is_watertight for b in bodies)
    _check_board(_board_of(bodies), BENT, open_holes=[0])  # hole 1 blocked
    pins = _pins_of(bodies, WORKPIECE_LIFT)
    _check_round_pins(pins, BENT, WORKPIECE_LIFT)
    bend = pins[0].vertices[:, :2].mean(axis=0) - BENT.hole_centers[0]
    np.testing.assert_allclose(bend, BENT.pin_offsets[0], atol=TOL)


def test_a_bent_socket_as_glb_has_named_closed_bodies_and_its_plug(tmp_path: Path) -> None:
    bodies = _glb_bodies(_export(tmp_path, BENT, ".glb"))
    assert sorted(bodies) == ["board", "carrier", "pin0", "pin1", "plug1"]
    assert all(b.is_watertight for b in bodies.values())
    _check_board(bodies["board"], BENT, open_holes=[0, 1])  # the plug is its own body
    plug = bodies["plug1"]
    np.testing.assert_allclose(plug.bounds[:, 2], [-BOARD_THICKNESS, 0.0], atol=TOL)
    faces = _face_distances(plug, BENT.hole_centers[1], 1.0)
    np.testing.assert_allclose(faces, BENT.hole_radius, atol=TOL)  # fills the 16-gon
    _check_round_pins([bodies["pin0"], bodies["pin1"]], BENT, WORKPIECE_LIFT)
    scene = trimesh.load(tmp_path / "part.glb", file_type="glb", force="scene")
    assert np.ptp(scene.bounds[:, 1]) < 0.02  # metres, y up: 11 mm tall
    colour = scene.geometry["pin1"].visual.material.baseColorFactor
    assert tuple(colour[:3]) != tuple(scene.geometry["pin0"].visual.material.baseColorFactor[:3])


def test_a_polygon_peg_measures_as_its_spec(tmp_path: Path) -> None:
    bodies = _stl_bodies(_export(tmp_path, HEXAGON, ".stl"))
    assert len(bodies) == 3 and all(b.is_watertight for b in bodies)
    _check_board(_board_of(bodies), HEXAGON, open_holes=[0])
    (peg,) = _pins_of(bodies, WORKPIECE_LIFT)
    radii = np.linalg.norm(peg.vertices[:, :2], axis=1)
    np.testing.assert_allclose(radii, HEXAGON.pin_circumradius, atol=TOL)
    faces = _face_distances(peg, np.zeros(2), 2.0)
    np.testing.assert_allclose(faces, inradius(6, HEXAGON.pin_circumradius), atol=TOL)
    clearance = inradius(6, HEXAGON.hole_circumradius) - faces.max()
    assert math.isclose(clearance, HEXAGON.clearance, abs_tol=TOL)
    np.testing.assert_allclose(
        peg.bounds[:, 2], [WORKPIECE_LIFT, WORKPIECE_LIFT + PIN_LENGTH], atol=TOL
    )


def test_parts_apart_keep_the_workpiece_in_its_frame(tmp_path: Path) -> None:
    board = _stl_bodies(_export(tmp_path, NOMINAL, ".stl", "--part", "board"))
    assert len(board) == 1
    workpiece = _stl_bodies(_export(tmp_path, NOMINAL, ".stl", "--part", "workpiece"))
    assert len(workpiece) == NOMINAL.n_pins + 1
    _check_round_pins(_pins_of(workpiece, 0.0), NOMINAL, 0.0)  # tips at z = 0


def test_the_xml_export_is_make_mjcf_unchanged(tmp_path: Path) -> None:
    for spec in (NOMINAL, BENT, HEXAGON):
        assert _export(tmp_path, spec, ".xml").read_bytes() == make_mjcf(spec).encode()
    out = tmp_path / "preset.xml"
    assert main(["export", "--env", "tolins/Circle2x2Fit20-v1", "--out", str(out)]) == 0
    from tolins.envs.tasks import PRESETS

    (task,) = [t for t in PRESETS if t.gym_id == "tolins/Circle2x2Fit20-v1"]
    assert out.read_bytes() == make_mjcf(task.socket).encode()


def test_the_socket_option_takes_a_file_and_the_short_form(tmp_path: Path) -> None:
    spec_file = tmp_path / "spec.json"
    spec_file.write_text(json.dumps(workpiece_dict(BENT)))
    out = tmp_path / "a.stl"
    assert main(["export", "--socket", str(spec_file), "--out", str(out)]) == 0
    assert out.read_bytes() == export_bytes(BENT, ".stl")
    assert spec_from_json('{"rows": 2, "cols": 2}') == NOMINAL
    assert spec_from_mapping({"sides": 6, "pin_circumradius": 1.2, "hole_circumradius": 1.26})
    assert spec_from_mapping(workpiece_dict(HEXAGON)) == HEXAGON


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--env", "tolins/Circle2x2-v1", "--out", "x.obj"], "allowed: a path ending in .stl"),
        (["--env", "tolins/Nope-v1", "--out", "x.stl"], "'tolins/Nope-v1' is not supported"),
        (["--env", "tolins/Insert-v1", "--out", "x.stl"], "with --socket"),
        (["--socket", "nope", "--out", "x.stl"], "no such file, nor inline JSON"),
        (["--socket", '{"rows": 2,', "--out", "x.stl"], "(inline JSON): not JSON"),
        (["--socket", "[" * 5000, "--out", "x.stl"], "(inline JSON): nested deeper than"),
        (["--socket", "[1, 2]", "--out", "x.stl"], "is not an object"),
        (["--socket", '{"rows": 2, "pins": 3}', "--out", "x.stl"], "no field pins"),
        (["--socket", '{"rows": 2, "cols": 1, "pin_radius": 0.6}', "--out", "x.stl"], "smaller"),
        (
            [
                "--socket",
                '{"sides": 4, "pin_circumradius": 1e6, "hole_circumradius": 1000000.1}',
                "--out",
                "x.stl",
            ],
            "allowed: every hole within 100 mm",
        ),
        (["--env", "tolins/Square-v1", "--part", "pins", "--out", "x.stl"], "allowed: all"),
        (["--env", "tolins/Square-v1", "--part", "board", "--out", "x.xml"], "with .xml"),
        (["--out", "x.stl"], "one of the arguments --env --socket is required"),
    ],
)
def test_bad_options_end_in_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], says: str
) -> None:
    args = [str(tmp_path / a) if a.startswith("x.") else a for a in args]
    assert main(["export", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err and "Traceback" not in err, err
    assert not list(tmp_path.iterdir())  # nothing written


def test_every_part_is_closed_for_every_preset_family() -> None:
    for spec in (CircularSocket(rows=3, cols=5, blocked_holes=(0, 7)), PolygonSocket(4, 1.5, 1.65)):
        for plugs_apart in (False, True):
            parts = socket_parts(spec, plugs_apart=plugs_apart)
            assert all(p.mesh.is_watertight and p.mesh.volume > 0 for p in parts)


@pytest.mark.parametrize(
    ("content", "says"),
    [(b"\x80\x81", "(a file): not UTF-8 text"), (b"[" * 5000, "(a file): nested deeper than")],
)
def test_an_unreadable_socket_file_is_one_line_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: bytes, says: str
) -> None:
    path = tmp_path / "spec.json"
    path.write_bytes(content)
    assert main(["export", "--socket", str(path), "--out", str(tmp_path / "x.stl")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"--socket {path} {says}" in err, err
    assert "allowed: a JSON object" in err, err


@pytest.mark.parametrize("value", ["[" * 20_000, "x" * 20_000, "[" + "1, " * 7000 + "1]"])
def test_a_long_socket_value_is_echoed_shortened(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], value: str
) -> None:
    assert main(["export", "--socket", value, "--out", str(tmp_path / "x.stl")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "…" in err and len(err) < 400, err
