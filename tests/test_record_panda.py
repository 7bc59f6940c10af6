"""A Panda episode's recording, read back: one 3-D scene of the arm, the part and the board."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from rerun.chunk import RrdReader
from rrd_tables import read_tables

import tolins  # noqa: F401  (registers the env ids)
from tolins.mjcf.model import scene_extent
from tolins.mjcf.panda import HANDLE, PREFIX
from tolins.policies.experts import SafeExpert
from tolins.record import RerunRecorder, record_episodes
from tolins.record.arm import arm_drawing

PANDA = "tolins/Circle2x2Panda-v3"
STEPS = 4


def _views(path: Path) -> list[dict]:
    """The views of ``path``'s blueprint: class, origin, contents and eye (if any)."""
    reader = RrdReader(path)
    (blueprint,) = reader.blueprints()
    views: dict[str, dict] = {}
    for chunk in reader.stream(store=blueprint):
        entity = chunk.entity_path
        if not entity.startswith("/view/"):
            continue
        view = views.setdefault(entity.split("/")[2], {})
        for column, values in chunk.to_record_batch().to_pydict().items():
            name = column.split(":")[-1]
            if name in ("class_identifier", "space_origin"):
                view[name] = values[-1][0]
            elif name in ("query", "position", "look_target"):
                view[name] = values[-1]
    return list(views.values())


@pytest.fixture(scope="module")
def panda(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    """A short Panda episode moving down, recorded; its infos and the env."""
    path = tmp_path_factory.mktemp("rrd") / "panda.rrd"
    env = gym.make(PANDA, horizon=STEPS)
    recorder = RerunRecorder(env, path, policy_name="down")
    _, info = recorder.reset(seed=0)
    infos = [info]
    for _ in range(STEPS):
        *_, info = recorder.step(np.array([0.0, 0.0, 0.0, -2.5]))
        infos.append(info)
    base = env.unwrapped
    recorder.close()
    return path, infos, base, read_tables(path)


def test_one_3d_view_holds_the_arm_the_part_and_the_board(panda: tuple) -> None:
    path, _, base, tables = panda
    spatial = [view for view in _views(path) if view["class_identifier"] == "3D"]
    assert len(spatial) == 1  # one scene, not a socket view beside an arm view
    (scene,) = spatial
    origin = scene["space_origin"]
    assert scene["query"] == ["$origin/**"]
    drawn = [entity.split("#")[0] for entity in tables]
    for part in (
        "/world/board/walls",
        "/world/board/holes",
        "/world/episode_000/workpiece/pins",
        "/world/episode_000/workpiece/handle",
        "/world/episode_000/arm/panda0_hand",
        "/world/episode_000/arm/panda0_leftfinger",
        "/world/episode_000/arm/panda0_link0",
        "/world/episode_000/wrist_force",
    ):
        assert part in drawn and part.startswith(f"{origin}/"), part
    # Its camera looks at the pins over their holes, from closer than the arm's reach.
    extent = scene_extent(base.nominal_socket)
    target, eye = np.array(scene["look_target"][0]), np.array(scene["position"][0])
    assert np.all(np.abs(target[:2]) <= extent) and 0.0 <= target[2] <= 10.0
    assert 3 * extent < np.linalg.norm(eye - target) < 150.0
    assert eye[0] > 0  # on the side away from the arm's base (x = -450 mm)
    handle = tables["/world/episode_000/workpiece/handle#static"]
    np.testing.assert_allclose(handle["Boxes3D:half_sizes"][0], [HANDLE])


def test_the_wrist_force_is_an_arrow_at_the_flange_every_step(panda: tuple) -> None:
    _, infos, _, tables = panda
    arrows = tables["/world/episode_000/wrist_force#temporal"]
    assert arrows["step"] == [info["step"] for info in infos] == list(range(STEPS + 1))
    hand = tables["/world/episode_000/arm/panda0_hand#temporal"]  # the flange is its origin
    origins = np.array([row[0] for row in arrows["Arrows3D:origins"]])
    np.testing.assert_allclose(origins, [row[0] for row in hand["Transform3D:translation"]])
    sensed = np.array([info["sensed_wrench"] for info in infos])
    vectors = np.array([row[0] for row in arrows["Arrows3D:vectors"]])
    np.testing.assert_allclose(vectors, 2.0 * sensed[:, [0, 1, 3]], rtol=1e-5, atol=1e-5)


def test_the_fingers_are_drawn_ending_at_their_pads_above_the_pins() -> None:
    """The model files stretch the finger mesh 1.75 times (a visual that touches nothing);
    drawn in its file's proportions, each finger ends where its pad ends, above the pins."""
    env = gym.make(PANDA).unwrapped
    _, info = env.reset(seed=0)
    model, data = env.backend.model, env.backend.data
    drawing = arm_drawing(model)
    tips = []
    for side in ("left", "right"):
        link = f"panda0_{side}finger"
        body = model.body(PREFIX + link).id
        rotation = data.xmat[body].reshape(3, 3)
        (piece,) = [piece for piece in drawing.pieces if piece.link == link]
        assert np.array_equal(piece.quaternion, [0.0, 0.0, 0.0, 1.0])
        world = (piece.vertices + piece.position) @ rotation.T + data.xpos[body]
        pad = model.geom(f"{PREFIX}{link}_pad").id
        pad_bottom = data.geom_xpos[pad][2] - model.geom_size[pad][2]
        assert world[:, 2].min() == pytest.approx(pad_bottom, abs=1.0)
        tips.append(world[:, 2].min())
    env.close()
    assert min(tips) > info["pose"][3] + 5.0  # stretched, 34 mm below them: through the board


def test_a_free_body_recording_keeps_its_socket_view(tmp_path: Path) -> None:
    path = tmp_path / "free.rrd"
    env = gym.make("tolins/Circle2x2-v1", backend="kinematic", horizon=2)
    record_episodes(env, SafeExpert(), 1, path, seed=0)
    views = _views(path)
    spatial = [view for view in views if view["class_identifier"] == "3D"]
    assert len(spatial) == 1 and spatial[0]["space_origin"] == "/world"
    assert "/sensed_wrench" not in [view["space_origin"] for view in views]
    tables = read_tables(path)
    assert not any("/arm" in entity or "wrist_force" in entity for entity in tables)
