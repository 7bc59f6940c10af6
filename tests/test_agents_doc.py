"""docs/agents.md: its PPO example is docs/examples/train_ppo.py and runs; its other Python
code runs as written."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "agents.md"
EXAMPLE = ROOT / "docs" / "examples" / "train_ppo.py"


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.DOTALL)


def test_the_doc_quotes_the_example_file_exactly() -> None:
    assert EXAMPLE.read_text() in _python_blocks()


@pytest.mark.slow
def test_the_ppo_example_trains_saves_and_scores_with_a_tiny_budget(tmp_path) -> None:
    out = tmp_path / "ppo.zip"
    command = [sys.executable, str(EXAMPLE), "--backend", "kinematic", "--steps", "256"]
    command += ["--n-steps", "128", "--episodes", "3", "--out", str(out)]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    assert out.is_file()
    assert re.search(r"ppo\.zip: reward -?\d+\.\d\d ± \d+\.\d\d, .* over 3 episodes", result.stdout)


def test_the_other_python_code_of_the_doc_runs() -> None:
    others = [block for block in _python_blocks() if block != EXAMPLE.read_text()]
    assert others
    for block in others:
        exec(compile(block, str(DOC), "exec"), {"__name__": "agents_doc"})
