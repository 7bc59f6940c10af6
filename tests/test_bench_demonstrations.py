"""The bench's demonstration stages: Minari datasets that its trainings read, and the
same policies as from demonstrations collected inline."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("minari")

from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.table.rows import CIRCLE_2X2, CIRCLE_2X8
from tolins.learning.imitation import runs
from tolins.learning.imitation.policy import load_policy


def _stage(out, prefix):
    (folder,) = (out / "stages").glob(f"{prefix}-*")
    return folder


@pytest.mark.slow
def test_bench_trainings_read_minari_datasets_and_equal_inline_demonstrations(tiny_bench, tmp_path):
    """The bench's stages: the shared tiny bench's (tests/conftest.py)."""
    import minari

    out = tmp_path / "bench"
    demos = {"demos-Circle2x2-safe-seed0-0", "demos-Circle2x8-safe-seed0-1"}
    assert demos <= set(tiny_bench.run.stage_wall_s)
    trainings = {"bc_safe-seed0", "pi_n_safe-seed0", "pi_phi_circle-seed0"}
    tiny_bench.copy_stages(out, keep=lambda name: name in demos | trainings)

    profile = PROFILES["tiny"]
    for name, env_id in zip(sorted(demos), (CIRCLE_2X2, CIRCLE_2X8), strict=True):
        dataset = minari.MinariDataset(_stage(out, name) / "demonstrations-v0" / "data")
        assert dataset.env_spec.id == env_id
        assert dataset.total_episodes == profile.demonstrations
        assert dataset.storage.metadata["algorithm_name"] == "safe"

    # the same trainings with the expert's episodes collected inline (tolins train)
    task = profile.task("kinematic", "safe", 0)
    inline = tmp_path / "inline"
    runs.run_bc(CIRCLE_2X2, task, profile.bc(), inline / "bc")
    runs.run_rs_gail(
        CIRCLE_2X2,
        task,
        profile.bc(),
        profile.rs_gail("rs-gail"),
        inline / "pi_n",
        init=str(inline / "bc" / "policy.pt"),
        progress=False,
    )
    runs.run_tolerance_guided(
        [CIRCLE_2X2, CIRCLE_2X8],
        task,
        profile.rs_gail("tolerance-guided"),
        profile.residual(),
        inline / "pi_phi",
        nominal=str(inline / "pi_n" / "policy.pt"),
        progress=False,
    )
    for stage, folder in (("bc_safe", "bc"), ("pi_n_safe", "pi_n"), ("pi_phi_circle", "pi_phi")):
        bench_folder = _stage(out, f"{stage}-seed0")
        ours, _ = load_policy(bench_folder / "policy.pt")
        theirs, _ = load_policy(inline / folder / "policy.pt")
        assert np.array_equal(ours.get_flat(), theirs.get_flat()), stage
        recorded = json.loads((bench_folder / "run.json").read_text())["configs"]["demos"]
        for path in recorded["dataset"].split(","):
            assert (bench_folder / path / "data" / "metadata.json").is_file()
    assert recorded["episodes"] == 2 * profile.demonstrations  # π_φ: both envs
