"""Smoke test of ``benchmarks/vector_scaling.py --quick``: it runs and prints its tables.

About 11 s of CPU (N = 2, tiny blocks, 64 PPO env steps); Meta-World is left out
(``--no-metaworld``): its virtual environment is built only by a full run.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "vector_scaling.py"


@pytest.mark.slow
def test_quick_run_prints_the_tables() -> None:
    result = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--no-metaworld"],
        capture_output=True,
        text=True,
        timeout=300,  # ~11 s of CPU; 110 s of wall time measured on a 2-core machine at load 12
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    out = result.stdout
    for heading in ("**mujoco**", "**kinematic**", "**Threads model**", "**SB3 PPO**"):
        assert heading in out, out
    assert "| socket | regime | N | steps | vec t=1 |" in out
    rows = [line for line in out.splitlines() if line.startswith("| 2*2 |")]
    # mujoco and kinematic: free and contact at N = 2; the threads model: both regimes
    assert len(rows) == 6, out
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert cells[2] == "2"
        assert all(c.replace(",", "").replace(".", "").isdigit() for c in cells[3:]), row
    ppo_rows = [line for line in out.splitlines() if line.startswith(("| 1 | 32 |", "| 8 | 4 |"))]
    assert len(ppo_rows) == 2, out
