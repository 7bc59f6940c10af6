"""docs/datasets.md: its example is docs/examples/minari_bc.py and runs; the recipes and the
per-step keys it lists are the code's."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("minari")

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "datasets.md"
EXAMPLE = ROOT / "docs" / "examples" / "minari_bc.py"


def test_the_doc_quotes_the_example_file_exactly() -> None:
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.DOTALL)
    assert EXAMPLE.read_text() in blocks


def test_the_doc_lists_the_recipes_and_step_keys_of_the_code() -> None:
    from tolins.datasets import RECIPES, STEP_INFO

    text = DOC.read_text()
    assert re.findall(r"^\| `([a-z-]+)` \|", text, flags=re.MULTILINE) == list(RECIPES)
    section = text.split("## What a dataset holds", 1)[1].split("Per episode", 1)[0]
    named = set(re.findall(r"`([a-z_]+)`", section))
    assert set(STEP_INFO) - {"reward_" + t for t in ("success", "collision", "approach",
        "height", "alignment", "depth", "offset")} <= named  # fmt: skip
    assert "reward_*" in section


@pytest.mark.slow
def test_the_example_writes_loads_clones_twice_and_evaluates(tmp_path) -> None:
    command = [sys.executable, str(EXAMPLE), "--backend", "kinematic", "--episodes", "6"]
    command += ["--epochs", "5", "--eval-episodes", "2", "--out", "datasets"]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    out = result.stdout
    assert "tolins/circle2x2/expert-safe-v0: 6 episodes" in out
    assert re.search(r"episode 0: \d+ steps, peak contact force \d+\.\d\d N", out)
    for label in ("tolins BC", "torch BC"):
        assert re.search(rf"{label}: reward -?\d+\.\d\d, success \d\.\d\d", out)
    assert (tmp_path / "datasets" / "tolins" / "circle2x2" / "expert-safe-v0" / "data").is_dir()
    assert (tmp_path / "datasets" / "bc_tolins" / "policy.pt").is_file()
