"""Commands that need the Panda model, run without the ``robot`` extra: one line naming
``tolins[robot]`` and exit status 2, before any work (gymnasium-robotics' absence
simulated in a fresh interpreter, one for the file)."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

PANDA = "tolins/Circle2x2Panda-v3"
#: Runs ``tolins`` commands with gymnasium-robotics hidden (``find_spec`` then finds no
#: package), one fresh interpreter for the file (its imports cost about 2 CPU-s, which
#: one interpreter per command paid nine times): argv is a JSON list of ``[cwd, argv]``;
#: each command's exit status, stdout and stderr (its file descriptors redirected, so that
#: what C code or an earlier command's handlers write is caught too) are printed as JSON.
WITHOUT_ROBOT = """
import json, os, sys, tempfile
sys.modules['gymnasium_robotics'] = None
from tolins.cli import main

def run(cwd, argv):
    os.chdir(cwd)
    streams = [tempfile.TemporaryFile(mode="w+") for _ in range(2)]
    saved = [os.dup(1), os.dup(2)]
    sys.stdout.flush(), sys.stderr.flush()
    os.dup2(streams[0].fileno(), 1), os.dup2(streams[1].fileno(), 2)
    try:
        code = main(argv)
    except SystemExit as stop:
        code = stop.code
    finally:
        sys.stdout.flush(), sys.stderr.flush()
        os.dup2(saved[0], 1), os.dup2(saved[1], 2)
    out, err = (s.seek(0) or s.read() for s in streams)
    return {"returncode": code, "stdout": out, "stderr": err}

results = [run(cwd, argv) for cwd, argv in json.loads(sys.argv[1])]
print(json.dumps(results))
"""


@dataclass(frozen=True)
class Result:
    returncode: int
    stdout: str
    stderr: str


def _cases(tmp: Path) -> dict[str, list[str]]:
    return {
        "bench": ["bench", "--profile", "tiny", "--out", str(tmp / "bench")],
        "bench-dry-run": ["bench", "--dry-run", "--out", str(tmp / "bench")],
        "evaluate": ["evaluate", "--policy", "safe", "--env", PANDA, "--episodes", "1"],
        "record": ["record", "--env", PANDA, "--episodes", "1", "--out", str(tmp / "x.rrd")],
        "dataset": ["dataset", "--env", PANDA, "--policy", "safe", "--out", str(tmp / "d")],
        "train": ["train", "bc", "--env", PANDA, "--out", str(tmp / "bc")],
    }


@pytest.fixture(scope="module")
def without_robot(tmp_path_factory) -> dict[str, tuple[Path, Result]]:
    """Every command of this file run without the extra, each in a folder of its own (the
    folder it runs in, its result), in one fresh interpreter."""
    root = tmp_path_factory.mktemp("without-robot")
    commands = {}
    for name in _cases(Path()):
        (root / name).mkdir()
        commands[name] = (root / name, _cases(root / name)[name])
    b = root / "options"
    b.mkdir()
    commands["bench-dry-run-default-out"] = (b, ["bench", "--dry-run"])
    commands["bench-dry-run-no-robot"] = (
        b,
        ["bench", "--dry-run", "--no-robot", "--out", str(b / "b")],
    )
    (root / "export").mkdir()
    out = root / "export" / "model.xml"
    commands["export"] = (root / "export", ["export", "--env", PANDA, "--out", str(out)])
    listed = json.dumps([[str(cwd), argv] for cwd, argv in commands.values()])
    done = subprocess.run(
        [sys.executable, "-c", WITHOUT_ROBOT, listed], capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-3000:]
    results = json.loads(done.stdout.strip().splitlines()[-1])
    return {
        name: (cwd, Result(**result))
        for (name, (cwd, _)), result in zip(commands.items(), results, strict=True)
    }


@pytest.mark.parametrize("command", list(_cases(Path())))
def test_a_panda_command_without_the_robot_extra_is_one_line_naming_it(
    command: str, without_robot
) -> None:
    tmp_path, result = without_robot[command]
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "tolins[robot]" in lines[0] and "Traceback" not in result.stderr
    assert result.stdout == ""
    # Nothing was written: the check comes before any work.
    assert not list(tmp_path.iterdir())


def test_bench_without_the_robot_extra_names_the_option_that_leaves_the_panda_out(
    without_robot,
) -> None:
    _, result = without_robot["bench-dry-run-default-out"]
    assert "--no-robot" in result.stderr
    _, result = without_robot["bench-dry-run-no-robot"]
    assert result.returncode == 0, result.stderr
    assert "Nothing was run" in result.stdout


def test_export_of_a_panda_id_needs_no_robot_extra(without_robot) -> None:
    folder, result = without_robot["export"]
    out = folder / "model.xml"
    assert result.returncode == 0, result.stderr
    assert out.is_file()
