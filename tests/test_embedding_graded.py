"""The graded embedding: the warped window, its ranges and checkpoints, and the paper's
embedding left as it was."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from tolins import CircularSocket, PolygonSocket, embedding, tolerance
from tolins.envs.tasks import GRADE_TASKS, TASKS
from tolins.learning.embedding.checkpoint import load_checkpoint, save_checkpoint
from tolins.learning.embedding.config import EmbeddingTrainConfig
from tolins.learning.embedding.evaluation import held_out_specs, measure
from tolins.learning.embedding.ranges import GRADED_RANGES, RANGES
from tolins.learning.embedding.train import train_embedding

#: ``encode(task.socket)`` of the paper's presets with the shipped checkpoints (float.hex of
#: each value, computed on an Intel CPU): the paper's policies were trained on these.
PAPER_CODES = {
    "Circle2x1": "0x1.db58a2p+1 -0x1.624d44p+3 0x1.90e29cp+3 -0x1.aa9d8p+3 0x1.994276p+1",
    "Circle2x2": "0x1.dcee9ep+1 -0x1.564508p+3 0x1.85d63cp+3 -0x1.9f76f8p+3 0x1.9af2fp+1",
    "Circle2x4": "0x1.cf4e8ap+1 -0x1.43d0a4p+3 0x1.72ab0ap+3 -0x1.8b1972p+3 0x1.8ebfeep+1",
    "Circle2x8": "0x1.b62076p+1 -0x1.2e9162p+3 0x1.5b4c54p+3 -0x1.719c04p+3 0x1.7835dep+1",
    "Square": "0x1.5cf764p-1 -0x1.abfabp+1 0x1.88bcf2p+2 -0x1.6a3fcap+2 0x1.654498p-4",
    "Pentagon": "0x1.81b2c6p+1 -0x1.6c0a02p+2 0x1.bafabcp+1 -0x1.27b9a6p-2 -0x1.3efd1cp+0",
    "Hexagon": "0x1.310904p+3 -0x1.abf10ap+2 0x1.782b5p-1 -0x1.9c3346p+2 0x1.3b9d4p+3",
}


@pytest.mark.parametrize("name", sorted(PAPER_CODES))
def test_default_encode_of_the_paper_presets_is_unchanged(name: str) -> None:
    socket = next(task.socket for task in TASKS if task.name == name)
    expected = np.array([float.fromhex(value) for value in PAPER_CODES[name].split()])
    code = embedding.encode(socket)
    # The encoder runs float32 convolutions whose summation order follows the CPU's SIMD
    # width, so the code is not bit-stable across x86 CPUs: an AMD EPYC gives a relative
    # 3e-7 (a few float32 ulps) against these Intel values. 1e-5 of the code's scale is
    # ~80 ulps; a hole 1 µm wider moves the code by 4e-3 of its scale.
    np.testing.assert_allclose(code, expected, rtol=0, atol=1e-5 * np.abs(expected).max())
    assert np.array_equal(embedding.encode(socket, model="paper"), code)  # same process


def test_the_default_window_is_the_linear_grid_bit_for_bit() -> None:
    for family, window in tolerance.WINDOWS.items():
        assert window.warp == 1.0
        steps = np.arange(64) * (2.0 / 63) - 1.0
        assert np.array_equal(window.axis(64), window.half_width * steps)
        spec = CircularSocket(2, 2) if family == "circle" else PolygonSocket(4, 1.5, 1.575)
        explicit = tolerance.ImageWindow(window.half_width, window.theta_cap)
        assert np.array_equal(tolerance.image(spec), tolerance.image(spec, window=explicit))


def test_the_warped_grid_is_fine_at_the_origin_and_reaches_the_edge() -> None:
    window = tolerance.GRADED_WINDOWS["circle"]
    axis = window.axis(64)
    assert axis[0] == -0.4 and axis[-1] == 0.4
    np.testing.assert_allclose(axis, -axis[::-1], atol=1e-15)
    steps = np.diff(axis)
    assert steps[31] < 0.001 < 0.02 < steps[0]  # µm cells at the origin, coarse at the edge
    # A 20 µm fit spans more than 10 cells across (a linear grid: 2).
    spec = dataclasses.replace(CircularSocket(2, 2), hole_radius=0.32)
    region = tolerance.image(spec, window=window) >= 0
    assert region[32].sum() > 10 and (tolerance.image(spec) >= 0).sum() <= 9
    with pytest.raises(ValueError, match="warp=0"):
        tolerance.ImageWindow(0.4, 0.5, warp=0.0)


def test_graded_ranges_are_strict() -> None:
    fit20 = next(t.socket for t in GRADE_TASKS if t.name == "Circle2x2Fit20")
    with pytest.raises(ValueError, match="outside the circle embedding's training ranges"):
        embedding.encode(fit20)
    assert embedding.encode(fit20, model="graded").shape == (5,)
    tight = dataclasses.replace(fit20, hole_radius=0.31)  # 10 µm
    with pytest.raises(ValueError, match=r"graded embedding.*clearance=0\.01 outside"):
        embedding.encode(tight, model="graded")
    with pytest.raises(ValueError, match=r"gap=0\.01 outside \[0\.02, 0\.2\]"):
        embedding.encode(PolygonSocket(4, 1.5, 1.51), model="graded")
    with pytest.raises(ValueError, match="model='fine'; allowed: 'paper', 'graded'"):
        embedding.encode(fit20, model="fine")
    rng = np.random.default_rng(0)
    for family in ("circle", "polygon"):
        model = embedding.load_model(family, "graded")
        assert model.ranges == GRADED_RANGES[family] and model.window.warp == 2.0
        assert embedding.load_model(family).ranges == RANGES[family]
        for _ in range(50):
            assert not model.ranges.violations(GRADED_RANGES[family].sample(rng))
    clearances = [GRADED_RANGES["circle"].sample(rng).clearance for _ in range(400)]
    assert min(clearances) >= 0.015 and max(clearances) <= 0.35
    assert np.mean(np.array(clearances) < 0.05) > 0.3  # log-uniform: fine fits are frequent


# The graded checkpoints on the grades: one workpiece each (IoU per image).
MIN_GRADE_IOU = 0.9


@pytest.mark.parametrize("task", GRADE_TASKS, ids=lambda t: t.name)
def test_the_graded_model_reconstructs_the_grade_presets(task) -> None:
    model = embedding.load_model(task.socket.family, "graded")
    quality = measure(model, [task.socket])
    assert quality.iou >= MIN_GRADE_IOU, quality


@pytest.mark.parametrize("family", ["circle", "polygon"])
def test_the_graded_model_reconstructs_held_out_workpieces(family: str) -> None:
    model = embedding.load_model(family, "graded")
    quality = measure(model, held_out_specs(family, 60, model="graded"))
    assert quality.iou >= 0.95 and quality.worst_iou >= MIN_GRADE_IOU, quality


def test_graded_training_and_checkpoints_round_trip(tmp_path: Path) -> None:
    config = EmbeddingTrainConfig(
        family="circle", model="graded", workpieces=8, epochs=1, batch_size=4, threads=1
    )
    result = train_embedding(config)
    assert result.model.window == tolerance.GRADED_WINDOWS["circle"]
    path = save_checkpoint(tmp_path / "graded.pt", result.model)
    loaded = load_checkpoint(path, family="circle")
    assert loaded.ranges == GRADED_RANGES["circle"] and loaded.window.warp == 2.0
    # The paper's checkpoints (saved before ``warp`` and ``model`` existed) still load.
    paper = load_checkpoint(embedding.checkpoint_path("circle"))
    assert paper.window == tolerance.WINDOWS["circle"] and "model" not in paper.config
