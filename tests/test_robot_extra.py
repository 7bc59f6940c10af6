"""Commands that need the Panda model, run without the ``robot`` extra: one line naming
``tolins[robot]`` and exit status 2, before any work (gymnasium-robotics' absence
simulated in a fresh interpreter)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

#: Each test starts a fresh interpreter (about 8 s of imports).
pytestmark = pytest.mark.slow

PANDA = "tolins/Circle2x2Panda-v3"
#: Runs ``tolins`` with gymnasium-robotics hidden: ``find_spec`` then finds no package.
WITHOUT_ROBOT = (
    "import sys; sys.modules['gymnasium_robotics'] = None; "
    "from tolins.cli import main; sys.exit(main(sys.argv[1:]))"
)


def _tolins_without_robot(*argv: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", WITHOUT_ROBOT, *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


def _cases(tmp: Path) -> dict[str, list[str]]:
    return {
        "bench": ["bench", "--profile", "tiny", "--out", str(tmp / "bench")],
        "bench-dry-run": ["bench", "--dry-run", "--out", str(tmp / "bench")],
        "evaluate": ["evaluate", "--policy", "safe", "--env", PANDA, "--episodes", "1"],
        "record": ["record", "--env", PANDA, "--episodes", "1", "--out", str(tmp / "x.rrd")],
        "dataset": ["dataset", "--env", PANDA, "--policy", "safe", "--out", str(tmp / "d")],
        "train": ["train", "bc", "--env", PANDA, "--out", str(tmp / "bc")],
    }


@pytest.mark.parametrize("command", list(_cases(Path())))
def test_a_panda_command_without_the_robot_extra_is_one_line_naming_it(
    command: str, tmp_path: Path
) -> None:
    argv = _cases(tmp_path)[command]
    result = _tolins_without_robot(*argv, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "tolins[robot]" in lines[0] and "Traceback" not in result.stderr
    assert result.stdout == ""
    # Nothing was written: the check comes before any work.
    assert not list(tmp_path.iterdir())


def test_bench_without_the_robot_extra_names_the_option_that_leaves_the_panda_out(
    tmp_path: Path,
) -> None:
    result = _tolins_without_robot("bench", "--dry-run", cwd=tmp_path)
    assert "--no-robot" in result.stderr
    result = _tolins_without_robot(
        "bench", "--dry-run", "--no-robot", "--out", str(tmp_path / "b"), cwd=tmp_path
    )
    assert result.returncode == 0, result.stderr
    assert "Nothing was run" in result.stdout


def test_export_of_a_panda_id_needs_no_robot_extra(tmp_path: Path) -> None:
    out = tmp_path / "model.xml"
    result = _tolins_without_robot("export", "--env", PANDA, "--out", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert out.is_file()
