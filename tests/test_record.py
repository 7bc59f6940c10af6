"""Recording to rerun and replaying: real episodes written to .rrd, read back and compared."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from collections import defaultdict
from pathlib import Path
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from rrd_tables import read_tables

import tolins
from tolins.cli import main
from tolins.mjcf.model import PIN_LENGTH
from tolins.policies.experts import SafeExpert
from tolins.record import RerunRecorder, check_rrd, record_episodes, replay
from tolins.record.geometry import board_geometry, pin_geometry, prism_mesh
from tolins.record.metadata import spec_from_dict, spec_to_dict

ENVS = ["tolins/Square-v1", "tolins/Circle2x2-v1"]
EPISODES = 2
RERUN = Path(sys.executable).with_name("rerun")


def _record(env_id: str, path: Path) -> list[list[tuple[float, dict[str, Any]]]]:
    """Record EPISODES safe-expert episodes (seeds 0, 1); return each step's (reward, info)."""
    env = RerunRecorder(gym.make(env_id), path, policy_name="safe")
    policy = SafeExpert()
    episodes = []
    for seed in range(EPISODES):
        observation, info = env.reset(seed=seed)
        steps, done = [(0.0, info)], False
        while not done:
            observation, reward, terminated, truncated, info = env.step(policy(observation))
            steps.append((reward, info))
            done = terminated or truncated
        episodes.append(steps)
    env.close()
    return episodes


@pytest.fixture(scope="module", params=ENVS)
def recording(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> tuple:
    env_id = request.param
    path = tmp_path_factory.mktemp("rrd") / f"{env_id.split('/')[1]}.rrd"
    episodes = _record(env_id, path)
    return env_id, path, episodes, read_tables(path)


def test_logged_poses_equal_info_pose_step_by_step(recording: tuple) -> None:
    _, _, episodes, tables = recording
    for k, steps in enumerate(episodes):
        pose_table = tables[f"/pose/episode_{k:03d}#temporal"]
        expected = np.array([info["pose"] for _, info in steps])
        assert pose_table["step"] == [info["step"] for _, info in steps]
        np.testing.assert_array_equal(np.array(pose_table["Scalars:scalars"]), expected)
        workpiece = tables[f"/world/episode_{k:03d}/workpiece#temporal"]
        translation = np.array([row[0] for row in workpiece["Transform3D:translation"]])
        np.testing.assert_array_equal(translation, expected[:, [0, 1, 3]].astype(np.float32))
        quaternion = np.array([row[0] for row in workpiece["Transform3D:quaternion"]])
        np.testing.assert_allclose(2 * np.arcsin(quaternion[:, 2]), expected[:, 2], atol=1e-6)
        sim_time = [t.total_seconds() for t in workpiece["sim_time"]]
        np.testing.assert_allclose(sim_time, 0.25 * np.arange(len(steps)))
        force = tables[f"/world/episode_{k:03d}/force#temporal"]
        wrench = np.array([info["wrench"] for _, info in steps])
        vectors = np.array([row[0] for row in force["Arrows3D:vectors"]])
        np.testing.assert_allclose(vectors, 2.0 * wrench[:, [0, 1, 3]], rtol=1e-6, atol=1e-6)


def test_rewards_collisions_success_and_events(recording: tuple) -> None:
    _, _, episodes, tables = recording
    for k, steps in enumerate(episodes):
        later = steps[1:]
        outcome = tables[f"/outcome/episode_{k:03d}#temporal"]
        assert outcome["step"] == [i["step"] for _, i in later]
        expected = [[r, float(i["collision"]), float(i["success"])] for r, i in later]
        assert outcome["Scalars:scalars"] == expected
        contact = tables[f"/contact/episode_{k:03d}#temporal"]
        assert contact["step"] == [i["step"] for _, i in later]
        assert contact["Scalars:scalars"] == [[i["peak_force"], 0.5] for _, i in later]
        events = tables[f"/events/episode_{k:03d}#temporal"]
        texts = [t[0] for t in events["TextLog:text"]]
        assert texts[0].startswith("start:") and f"seed {k}" in texts[0]
        collisions = [i["step"] for _, i in later if i["collision"]]
        logged = [s for s, t in zip(events["step"], texts, strict=True) if "collision" in t]
        assert logged[: len(collisions)] == collisions
        final = steps[-1][1]
        outcome = "success at step" if final["success"] else "truncated without success"
        assert outcome in texts[-1] and events["step"][-1] == final["step"]


def test_geometry_is_logged_once_and_matches_the_model(recording: tuple) -> None:
    env_id, _, _, tables = recording
    socket = gym.spec(env_id).kwargs["socket"]
    board = board_geometry(socket)
    walls = tables["/world/board/walls#static"]
    assert len(walls["Mesh3D:vertex_positions"]) == 1  # once per file
    logged = np.array(walls["Mesh3D:vertex_positions"][0])
    assert len(logged) == 3 * len(board.walls.triangles)  # flat shaded: vertices per face
    np.testing.assert_array_equal(_rounded(logged), _rounded(board.walls.vertices))
    holes = tables["/world/board/holes#static"]["LineStrips3D:strips"][0]
    assert len(holes) == socket.n_pins
    boxes = tables["/world/board/boxes#static"]
    model = mujoco.MjModel.from_xml_string(tolins.make_mjcf(socket))
    names = [model.geom(i).name for i in range(model.ngeom)]
    box_ids = [i for i, name in enumerate(names) if name.startswith("board_box")]
    np.testing.assert_allclose(boxes["Boxes3D:half_sizes"][0], model.geom_size[box_ids], atol=1e-6)
    np.testing.assert_allclose(boxes["Boxes3D:centers"][0], model.geom_pos[box_ids], atol=1e-6)
    np.testing.assert_array_equal(_wall_vertices(model), _rounded(board.walls.vertices))
    for k in range(EPISODES):
        pins = tables[f"/world/episode_{k:03d}/workpiece/pins#static"]
        if pin_geometry(socket).cylinders is not None:
            centers = np.array(pins["Cylinders3D:centers"][0])
            pin_ids = [i for i, name in enumerate(names) if name.startswith("pin")]
            np.testing.assert_allclose(centers, model.geom_pos[pin_ids], atol=1e-6)
        else:
            assert "Boxes3D:half_sizes" in pins or "Mesh3D:vertex_positions" in pins


def _rounded(points: np.ndarray) -> np.ndarray:
    """Distinct points rounded to 0.1 µm, sorted."""
    return np.unique(np.round(points, 4) + 0.0, axis=0)


def _wall_vertices(model: mujoco.MjModel) -> np.ndarray:
    """World vertices of every ``hole*_wall*`` mesh geom of the compiled model."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    points = []
    for i in range(model.ngeom):
        if model.geom(i).name.startswith("hole"):
            mesh = model.geom_dataid[i]
            start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
            local = model.mesh_vert[start : start + count]
            points.append(local @ data.geom_xmat[i].reshape(3, 3).T + data.geom_xpos[i])
    return _rounded(np.concatenate(points))


def test_episodes_are_separable_with_their_metadata(recording: tuple) -> None:
    env_id, _, episodes, tables = recording
    for k, steps in enumerate(episodes):
        meta = tables[f"/metadata/episode_{k:03d}#static"]
        assert meta["env_id"] == [[env_id]] and meta["policy"] == [["safe"]]
        assert meta["seed"] == [[k]]
        spec = spec_from_dict(json.loads(meta["spec"][0][0]))
        assert spec == gym.spec(env_id).kwargs["socket"]
        assert len(tables[f"/pose/episode_{k:03d}#temporal"]["step"]) == len(steps)
    assert not any("episode_002" in entity for entity in tables)
    properties = tables["/__properties/tolins#static"]
    assert properties["env_id"] == [[env_id]]


def test_bent_pins_are_logged_per_episode(tmp_path: Path) -> None:
    path = tmp_path / "bent.rrd"
    env = gym.make("tolins/Circle2x1Defective-v1")
    record_episodes(env, SafeExpert(), 2, path, seed=0)
    tables = read_tables(path)
    centers = []
    for k in range(2):
        spec = spec_from_dict(json.loads(tables[f"/metadata/episode_{k:03d}#static"]["spec"][0][0]))
        assert spec.is_defective
        pins = np.array(
            tables[f"/world/episode_{k:03d}/workpiece/pins#static"]["Cylinders3D:centers"][0]
        )
        np.testing.assert_allclose(pins[:, :2], spec.pin_centers, atol=1e-6)
        centers.append(pins)
    assert not np.allclose(centers[0], centers[1])


def test_defects_are_drawn_with_their_geometry(tmp_path: Path) -> None:
    """A burred pin has its own radius and colour, a short pin its length, a pitch error
    the scaled places, a blocked hole a plug: as the MJCF model builds them."""
    socket = tolins.CircularSocket(
        2,
        2,
        pin_burrs=(0.05, 0.0, 0.0, 0.0),
        pin_shortenings=(0.0, 0.3, 0.0, 0.0),
        blocked_holes=(3,),
        pin_pitch_scale=(1.004, 0.998),
    )
    path = tmp_path / "defects.rrd"
    env = gym.make("tolins/Insert-v1", socket=socket, backend="kinematic", horizon=3)
    record_episodes(env, SafeExpert(), 1, path, seed=0)
    drawn = gym.make("tolins/Circle2x2-v1", backend="kinematic", horizon=2, defects=("burr", 0.05))
    record_episodes(drawn, SafeExpert(), 2, tmp_path / "burrs.rrd", seed=0)
    tables = read_tables(path)
    pins = tables["/world/episode_000/workpiece/pins#static"]
    model = mujoco.MjModel.from_xml_string(tolins.make_mjcf(socket))
    ids = [model.geom(f"pin{i}").id for i in range(4)]
    np.testing.assert_allclose(pins["Cylinders3D:centers"][0], model.geom_pos[ids], atol=1e-6)
    np.testing.assert_allclose(pins["Cylinders3D:radii"][0], [0.35, 0.3, 0.3, 0.3], atol=1e-6)
    np.testing.assert_allclose(pins["Cylinders3D:radii"][0], model.geom_size[ids, 0], atol=1e-6)
    np.testing.assert_allclose(pins["Cylinders3D:lengths"][0], 2 * model.geom_size[ids, 1])
    assert pins["Cylinders3D:lengths"][0][1] == pytest.approx(PIN_LENGTH - 0.3)
    np.testing.assert_allclose(
        np.array(pins["Cylinders3D:centers"][0])[:, :2], socket.pin_centers, atol=1e-6
    )
    colors = pins["Cylinders3D:colors"][0]
    assert colors[0] != colors[2] and colors[1] not in (colors[0], colors[2])
    assert colors[2] == colors[3]
    plugs = tables["/world/episode_000/plugs#static"]
    plug = model.geom("plug3").id
    np.testing.assert_allclose(plugs["Boxes3D:centers"][0], model.geom_pos[[plug]], atol=1e-6)
    np.testing.assert_allclose(plugs["Boxes3D:half_sizes"][0], model.geom_size[[plug]], atol=1e-6)
    burrs = read_tables(tmp_path / "burrs.rrd")
    radii = []
    for k in range(2):
        meta = burrs[f"/metadata/episode_{k:03d}#static"]["spec"][0][0]
        spec = spec_from_dict(json.loads(meta))
        logged = burrs[f"/world/episode_{k:03d}/workpiece/pins#static"]["Cylinders3D:radii"][0]
        np.testing.assert_allclose(logged, spec.pin_radii, atol=1e-6)
        radii.append(logged)
        assert f"/world/episode_{k:03d}/plugs#static" not in burrs
    assert spec.pin_burrs is not None and radii[0] != radii[1]


def test_rerun_rrd_verify_accepts_the_file(recording: tuple) -> None:
    _, path, _, _ = recording
    result = subprocess.run(
        [str(RERUN), "rrd", "verify", str(path)], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert check_rrd(path) > 0


def _vulkan_driver() -> bool:
    folders = [Path("/usr/share/vulkan/icd.d"), Path("/etc/vulkan/icd.d")]
    return any(f.is_dir() and any(f.glob("*.json")) for f in folders)


@pytest.mark.skipif(
    not _vulkan_driver(),
    reason="no Vulkan driver for the headless viewer (install Debian's mesa-vulkan-drivers: "
    "scripts/setup.sh as root)",
)
def test_headless_screenshot_shows_the_parts(tmp_path: Path) -> None:
    from PIL import Image

    path = tmp_path / "circle.rrd"
    record_episodes(gym.make("tolins/Circle2x2-v1"), SafeExpert(), 1, path, seed=0)
    shot = tmp_path / "shot.png"
    assert replay(path, screenshot=shot) == 0
    image = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    height, width, _ = image.shape
    view = image[height // 10 : height * 3 // 4, : width * 3 // 5]  # the 3-D view
    r, g, b = view[..., 0], view[..., 1], view[..., 2]
    board = (g > r + 25) & (g > b + 15)  # the green board
    pins = (r > 120) & (g > 90) & (b < 0.6 * g)  # the golden pins
    assert board.mean() > 0.02, f"board covers {board.mean():.3%} of the 3-D view"
    assert pins.sum() > 100, f"{pins.sum()} golden pixels"
    assert view.std() > 10
    assert not list(tmp_path.glob(".*tmp*"))


def test_replay_rejects_missing_and_corrupt_files(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    junk = tmp_path / "junk.rrd"
    junk.write_text("not a recording")
    truncated = tmp_path / "truncated.rrd"
    record_episodes(gym.make("tolins/Square-v1"), SafeExpert(), 1, truncated)
    truncated.write_bytes(truncated.read_bytes()[:3000])
    for path, what, status in (
        (tmp_path / "missing.rrd", "does not exist; allowed: an existing file", 2),
        (tmp_path, "is a folder", 2),
        (junk, "not a readable .rrd", 2),  # a file the user named: a user error
        (truncated, ".rrd recording", 2),
    ):
        assert main(["replay", str(path)]) == status
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and str(path) in err and what in err, err
        assert "Traceback" not in err


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_web_replay_serves_on_loopback_and_prints_the_address(recording: tuple) -> None:
    _, path, _, _ = recording
    web, grpc = _free_port(), _free_port()
    command = [sys.executable, "-m", "tolins.cli", "replay", str(path), "--web"]
    process = subprocess.Popen(
        [*command, "--port", str(web), "--grpc-port", str(grpc)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        start_new_session=True,  # its own process group: the viewer server ends with it
    )
    try:
        line = process.stdout.readline()
        assert f"http://127.0.0.1:{web}/?url=" in line, line
        for _ in range(100):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{web}/", timeout=2) as reply:
                    assert reply.status == 200
                    break
            except OSError:
                time.sleep(0.1)
        else:
            pytest.fail(f"nothing served on 127.0.0.1:{web}")
    finally:
        os.killpg(process.pid, signal.SIGTERM)
        process.wait(timeout=10)


def test_native_replay_without_a_display_says_so(
    recording: tuple, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    _, path, _, _ = recording
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    assert main(["replay", str(path)]) == 1
    assert "no display" in capsys.readouterr().err


def test_record_cli_writes_a_verified_file(tmp_path: Path, capsys) -> None:
    out = tmp_path / "new" / "cli.rrd"  # the folder is created
    argv = ["record", "--env", "tolins/Circle2x1-v1", "--policy", "efficient"]
    assert main([*argv, "--episodes", "2", "--out", str(out), "--seed", "3"]) == 0
    assert "2 episodes" in capsys.readouterr().out
    assert check_rrd(out) > 0
    tables = read_tables(out)
    assert [tables[f"/metadata/episode_{k:03d}#static"]["seed"] for k in (0, 1)] == [[[3]], [[4]]]
    assert sorted(p.name for p in out.parent.iterdir()) == ["cli.rrd"]  # no temporary left
    assert main(["record", "--env", "tolins/Nope-v1", "--out", str(out)]) == 2
    assert main(["record", "--env", "tolins/Square-v1", "--out", str(tmp_path / "x.txt")]) == 2


def test_a_failed_recording_leaves_no_file(tmp_path: Path) -> None:
    calls = 0

    def failing(observation: np.ndarray) -> np.ndarray:
        nonlocal calls
        calls += 1
        if calls > 3:
            raise RuntimeError("policy failed")
        return np.zeros(4)

    with pytest.raises(RuntimeError, match="policy failed"):
        record_episodes(gym.make("tolins/Square-v1"), failing, 1, tmp_path / "x.rrd")
    assert list(tmp_path.iterdir()) == []


def test_prism_mesh_is_closed_and_outward() -> None:
    outline = tolins.geometry.specs.polygon_vertices(6, 1.0)
    mesh = prism_mesh(outline, -1.0, 2.0)
    edges = defaultdict(int)
    for a, b, c in mesh.triangles:
        for edge in ((a, b), (b, c), (c, a)):
            edges[edge] += 1
    assert all(edges[(b, a)] == 1 for a, b in edges)  # every edge met once each way
    v = mesh.vertices[mesh.triangles]
    normals = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    outward = np.einsum("ij,ij->i", normals, v.mean(axis=1) - mesh.vertices.mean(axis=0))
    assert np.all(outward > 0)
    with pytest.raises(ValueError, match="z_bottom"):
        prism_mesh(outline, 1.0, 1.0)


def test_spec_round_trip_and_recorder_validation(tmp_path: Path) -> None:
    bent = tolins.sample_defects(tolins.CircularSocket(2, 2), 0.05, rng=0)
    assert spec_from_dict(json.loads(json.dumps(spec_to_dict(bent)))) == bent
    with pytest.raises(ValueError, match="not an InsertionEnv"):
        RerunRecorder(gym.make("CartPole-v1"), tmp_path / "x.rrd")
    with pytest.raises(ValueError, match=r"\.rrd"):
        RerunRecorder(gym.make("tolins/Square-v1"), tmp_path / "x.txt")


def test_nothing_in_tolins_imports_record() -> None:
    code = (
        "import sys, tolins, tolins.cli\n"
        "print(any(name.startswith('tolins.record') for name in sys.modules))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.stdout.strip() == "False", result.stderr


def test_pins_that_bend_are_drawn_bent_step_by_step_with_their_yield(tmp_path: Path) -> None:
    """Pins that bend: each step's pins as strips from root to the tip offset the env gave
    (a yielded pin in its own colour), an event where a pin yielded and where the part was
    damaged, and no straight static pins."""
    path = tmp_path / "delicate.rrd"
    socket = tolins.CircularSocket(2, 1)
    env = RerunRecorder(
        gym.make("tolins/Insert-v2", socket=socket, pins="elastic-plastic", pin_material="alloy42"),
        path,
        policy_name="push",
    )
    _, info = env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, -0.6]})
    infos = [info]
    for _ in range(3):  # pins in their holes dragged into the walls: they yield
        infos.append(env.step([1.0, 0.0, 0.0, 0.0])[-1])
    env.close()
    assert infos[-1]["damaged"]
    tables = read_tables(path)
    assert "/world/episode_000/workpiece/pins#static" not in tables
    pins = tables["/world/episode_000/workpiece/pins#temporal"]
    assert pins["step"] == [0, 1, 2, 3]
    for row, info in zip(pins["LineStrips3D:strips"], infos, strict=True):
        strips = np.array(row)  # (pins, 2 points, xyz), float32 as rerun keeps them
        np.testing.assert_allclose(strips[:, 0, :2], socket.pin_centers, atol=1e-6)
        offsets = strips[:, 1, :2] - strips[:, 0, :2]
        np.testing.assert_allclose(offsets, info["pin_deflection"], atol=1e-6)
        lengths = np.linalg.norm(strips[:, 1] - strips[:, 0], axis=1)
        np.testing.assert_allclose(lengths, PIN_LENGTH, rtol=1e-6)
    colors = pins["LineStrips3D:colors"]
    assert colors[0][0] != colors[-1][0]  # straight, then bent for good
    events = tables["/events/episode_000#temporal"]["TextLog:text"]
    texts = [text[0] for text in events]
    assert any(text.startswith("yielded: permanent tip offsets pin 0") for text in texts)
    assert any(text.startswith("part damaged") for text in texts)
