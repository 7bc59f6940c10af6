"""Shared test set-up."""

from __future__ import annotations

import os
import pickle
import re
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

# tolins chooses headless OpenGL (MUJOCO_GL=egl) when mujoco is first imported; import it
# before any test module imports mujoco itself, so render tests run instead of skipping.
import tolins  # noqa: F401

if TYPE_CHECKING:
    from collections.abc import Callable

    from tolins.bench.pipeline.config import BenchRun

#: A stage folder's name: the stage's name, then its key (tolins.bench.store.cache).
_STAGE_FOLDER = re.compile(r"(?P<name>.+)-[0-9a-f]{12}")


@dataclass(frozen=True)
class TinyBench:
    """The whole tiny bench on the kinematic backend (every row, the study, the robustness
    table), run once for the whole test session: its folder (read-only: copy from it) and
    the :class:`BenchRun` that made it."""

    folder: Path
    run: BenchRun

    def copy_stages(self, out: Path, keep: Callable[[str], bool] = lambda _: True) -> None:
        """The finished stages whose names ``keep`` accepts into the stage cache of the bench
        folder ``out``: a run there takes them as its own where its plan has the same stage
        with the same config (its key), as when resumed."""
        stages = out / "stages"
        stages.mkdir(parents=True, exist_ok=True)
        for folder in sorted((self.folder / "stages").iterdir()):
            found = _STAGE_FOLDER.fullmatch(folder.name)
            if folder.is_dir() and found and keep(found["name"]):
                shutil.copytree(folder, stages / folder.name)


@pytest.fixture(autouse=True, scope="session")
def _sb3_logs_in_pytest_tmp(tmp_path_factory: pytest.TempPathFactory) -> None:
    """SB3's default logger makes an empty folder per training in the system's temporary
    directory, ``$SB3_LOGDIR`` if set: the suite's go under pytest's own (its processes
    inherit it)."""
    os.environ["SB3_LOGDIR"] = str(tmp_path_factory.mktemp("sb3_logs"))


@pytest.fixture(scope="session")
def tiny_bench(tmp_path_factory: pytest.TempPathFactory) -> TinyBench:
    """:class:`TinyBench`, made by the first test (of any pytest-xdist worker) that asks for
    it; the other workers wait for it behind a file lock and read what it left."""
    from filelock import FileLock

    from tolins.bench.pipeline.config import BenchConfig
    from tolins.bench.pipeline.runner import run_bench

    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # this session's folder, which every worker shares
    shared = root / "tiny-kinematic-bench"
    done = shared / "run.pickle"
    with FileLock(str(root / "tiny-kinematic-bench.lock")):
        if not done.exists():
            shutil.rmtree(shared, ignore_errors=True)  # a run that did not finish
            config = BenchConfig(profile="tiny", backend="kinematic", out=str(shared / "bench"))
            run = run_bench(config, progress=False, log=lambda _: None)
            part = done.with_suffix(".part")
            part.write_bytes(pickle.dumps(run))
            part.rename(done)
    return TinyBench(shared / "bench", pickle.loads(done.read_bytes()))
