"""A built wheel and sdist carry everything tolins reads at run time (package data).

The wheel is built offline from a copy of the checkout, installed into a folder outside
it and run from there: the embedding of both families and a command that needs it.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tolins import CircularSocket, PolygonSocket, embedding

ROOT = Path(__file__).resolve().parents[1]

#: What the package reads at run time besides its code, relative to the checkout.
PACKAGE_DATA = ("tolins/assets/*.pt", "tolins/bench/reference/README.md")
REFERENCE_DATA = "tolins/bench/reference/*/*.json"

#: Left out at the top of the copy the build starts from: git, outputs and caches.
TOP_LEVEL_OUTPUTS = {".git", ".hypothesis", "build", "dist", "runs", "results"}

_ENCODE_AND_CLONE = """
import json
import tolins
from tolins import CircularSocket, PolygonSocket, embedding
from tolins.cli import main
codes = {
    "circle": embedding.encode(CircularSocket(2, 2)).tolist(),
    "polygon": embedding.encode(PolygonSocket(4, 1.5, 1.575)).tolist(),
    "graded": embedding.encode(CircularSocket(2, 2), model="graded").tolist(),
}
main(["train", "bc", "--env", "tolins/Circle2x2-v1", "--out", "bc", "--backend", "kinematic",
      "--demonstrations", "2", "--epochs", "1"])
print(json.dumps({"file": tolins.__file__, "codes": codes}))
"""

_TOLERANCE_GUIDED = [
    "train", "tolerance-guided", "--env", "tolins/Circle2x2-v1,tolins/Circle2x4-v1",
    "--out", "tg", "--nominal", "bc/policy.pt", "--backend", "kinematic",
    "--demonstrations", "2", "--iterations", "1", "--popsize", "2", "--episodes", "1",
    "--eval-episodes", "1", "--discriminator-steps", "1", "--workers", "1",
]  # fmt: skip


def shipped_files() -> list[str]:
    """The package data of the checkout, as paths relative to it."""
    patterns = (*PACKAGE_DATA, REFERENCE_DATA)
    found = sorted({p.relative_to(ROOT).as_posix() for g in patterns for p in ROOT.glob(g)})
    assert len(found) >= 4 + 1 + 2, found
    return found


def not_sources(folder: str, names: list[str]) -> set[str]:
    """What the copy of the checkout leaves out of ``folder``: caches and environments
    anywhere, outputs at the top."""
    skipped = {
        name
        for name in names
        if name == "__pycache__"
        or name.endswith((".egg-info", "_cache"))
        or name.startswith(".venv")
    }
    return skipped | (TOP_LEVEL_OUTPUTS & set(names) if Path(folder) == ROOT else set())


def run(command: list[str], cwd: Path, env: dict[str, str] | None = None) -> str:
    """``command``'s stdout; fails the test with its output if it fails."""
    result = subprocess.run(
        command, cwd=cwd, env=env, capture_output=True, text=True, timeout=300, check=False
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return result.stdout


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The wheel and the sdist built offline from a copy of the checkout."""
    tmp = tmp_path_factory.mktemp("packaging")
    source, out = tmp / "source", tmp / "dist"
    shutil.copytree(ROOT, source, ignore=not_sources, symlinks=True)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    run([*pip, "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-w", out, "."], source)
    hook = f"from setuptools import build_meta; build_meta.build_sdist({str(out)!r})"
    run([sys.executable, "-c", hook], source)
    (wheel,), (sdist,) = out.glob("*.whl"), out.glob("*.tar.gz")
    return wheel, sdist


@pytest.mark.slow
def test_wheel_and_sdist_carry_the_package_data(built: tuple[Path, Path]) -> None:
    wheel, sdist = built
    with zipfile.ZipFile(wheel) as archive:
        in_wheel = set(archive.namelist())
    with tarfile.open(sdist) as archive:
        in_sdist = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    for name in shipped_files():
        assert name in in_wheel, f"{name} is not in {wheel.name}"
        assert name in in_sdist, f"{name} is not in {sdist.name}"


@pytest.mark.slow
def test_installed_wheel_encodes_and_trains_outside_the_checkout(
    built: tuple[Path, Path], tmp_path: Path
) -> None:
    site, work = tmp_path / "site", tmp_path / "work"
    work.mkdir()
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    run([*pip, "install", "--no-deps", "--no-index", "--target", site, built[0]], tmp_path)
    # The target comes first on sys.path, before the editable install's finder.
    env = {**os.environ, "PYTHONPATH": str(site), "PYTHONNOUSERSITE": "1"}
    report = json.loads(run([sys.executable, "-c", _ENCODE_AND_CLONE], work, env).splitlines()[-1])
    assert Path(report["file"]).is_relative_to(site)
    expected = {
        "circle": embedding.encode(CircularSocket(2, 2)),
        "polygon": embedding.encode(PolygonSocket(4, 1.5, 1.575)),
        "graded": embedding.encode(CircularSocket(2, 2), model="graded"),
    }
    for name, code in expected.items():
        np.testing.assert_allclose(report["codes"][name], code, rtol=1e-6, atol=1e-9)
    run([str(site / "bin" / "tolins"), *_TOLERANCE_GUIDED], work, env)
    assert (work / "tg" / "policy.pt").is_file()
