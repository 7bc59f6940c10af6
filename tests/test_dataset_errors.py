"""What goes wrong around a Minari dataset ends as one line and exit 2: a malformed
``--name``, a damaged file, data outside the env's spaces, a second writer of one dataset;
and a killed writer's leftovers are removed by the next one (tolins.datasets)."""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

minari = pytest.importorskip("minari")
h5py = pytest.importorskip("h5py")

from tolins.cli import main  # noqa: E402
from tolins.datasets import Source, load_demonstrations, write_dataset  # noqa: E402
from tolins.physics.kinematic import KinematicBatch  # noqa: E402
from tolins.policies import EXPERTS  # noqa: E402

ENV = "tolins/Circle2x2-v1"
NAME = "tolins/test/safe-v0"
KINEMATIC = ["--backend", "kinematic"]


def _no_episode(*args, **kwargs):
    raise AssertionError("an env was built before the dataset's lock was checked")


def _one_line(capsys) -> str:
    """The one line on stderr (no traceback, no progress bar)."""
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def _safe(root: Path, name: str = NAME, episodes: int = 3, **kwargs) -> Path:
    source = Source("safe", lambda _: EXPERTS["safe"]())
    return write_dataset(ENV, [source], episodes, root, name, backend="kinematic", **kwargs)


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> Path:
    """A real dataset of three safe-expert episodes (not to be changed: copy it)."""
    return _safe(tmp_path_factory.mktemp("written"))


@pytest.fixture
def dataset(written, tmp_path) -> Path:
    """A copy of :func:`written` to damage."""
    return Path(shutil.copytree(written, tmp_path / "dataset"))


def _train_bc(demos: Path, out: Path) -> int:
    argv = ["train", "bc", "--env", ENV, *KINEMATIC, "--epochs", "1", "--demos", str(demos)]
    return main([*argv, "--out", str(out)])


@pytest.mark.parametrize(
    "name", ["foo/bar", "foo/bar-v", "foo/bar-vx", "foo/bar-v-1", "foo/bar-v0/extra"]
)
def test_a_name_that_is_no_versioned_minari_id_is_one_line(tmp_path, capsys, name):
    argv = ["dataset", "--env", ENV, "--policy", "safe", "--name", name]
    assert main([*argv, "--out", str(tmp_path / "root")]) == 2
    line = _one_line(capsys)
    assert f"--name {name!r} is not a Minari dataset id" in line, line
    assert "allowed: (namespace/)name-vN" in line, line
    assert not (tmp_path / "root").exists()


def test_a_missing_policy_file_names_every_policy_form_and_no_module(tmp_path, capsys):
    argv = ["dataset", "--env", ENV, "--policy", "nope.zip", "--out", str(tmp_path / "root")]
    assert main(argv) == 2
    line = _one_line(capsys)
    assert "no such file 'nope.zip'; --policy takes a .zip/.pt file path" in line, line
    assert line.endswith("or one of: safe, efficient, random, bc"), line
    assert "module tolins" not in line, line


@pytest.mark.parametrize("size", [0, 3000], ids=["empty", "truncated"])
def test_a_damaged_dataset_file_is_one_line(dataset, tmp_path, capsys, size):
    hdf5 = dataset / "data" / "main_data.hdf5"
    with open(hdf5, "r+b") as file:
        file.truncate(size)
    assert _train_bc(dataset, tmp_path / "out") == 2
    line = _one_line(capsys)
    assert f"--demos {dataset}: its episodes are unreadable (OSError: " in line, line
    assert "allowed: a complete dataset file" in line, line
    assert not (tmp_path / "out").exists()


def _set(hdf5: Path, field: str, change) -> None:
    """Replace episode 1's ``field`` in the file ``hdf5`` by ``change(values)``."""
    with h5py.File(hdf5, "r+") as file:
        values = change(file[f"episode_1/{field}"][()])
        del file[f"episode_1/{field}"]
        file[f"episode_1/{field}"] = values


def _put(index, value):
    def change(values):
        values[index] = value
        return values

    return change


@pytest.mark.parametrize(
    ("field", "change", "message"),
    [
        (
            "actions",
            _put((3, 1), 1e6),
            "episode 1: actions[3, 1] = 1e+06 is outside the action space; allowed: -2.5 … 2.5",
        ),
        ("actions", _put((0, 2), np.nan), "actions hold nan at [0, 2]; allowed: finite values"),
        ("observations", _put((5, 0), np.inf), "observations hold inf at [5, 0]; allowed: fin"),
        ("rewards", _put(4, -np.inf), "rewards hold -inf at [4]; allowed: finite values"),
        (
            "observations",
            lambda values: values[:, :7],
            "observations of shape (38, 7); allowed: rows of width 8 (the observation space's)",
        ),
        ("actions", lambda values: values[:-2], "38 observations for 35 actions; allowed: one"),
    ],
    ids=["action-1e6", "action-nan", "observation-inf", "reward-inf", "width-7", "short"],
)
def test_data_outside_the_env_spaces_is_refused_before_training(
    dataset, tmp_path, capsys, field, change, message
):
    _set(dataset / "data" / "main_data.hdf5", field, change)
    with pytest.raises(ValueError, match="episode 1: "):
        load_demonstrations(dataset, ENV)
    assert _train_bc(dataset, tmp_path / "out") == 2
    line = _one_line(capsys)
    assert line.startswith(f"tolins train bc: --demos {dataset}: episode 1: "), line
    assert message in line, line
    assert not (tmp_path / "out").exists()  # no policy trained or written


def test_the_untouched_dataset_passes_the_checks(written):
    assert len(load_demonstrations(written, ENV)) == 3


def _temporaries(root: Path, name: str = NAME) -> list[Path]:
    target = root / name
    return sorted(target.parent.glob(f".{target.name}.*.tmp"))


def test_a_second_writer_is_refused_at_once_and_a_killed_ones_leftovers_go(
    tmp_path, capsys, monkeypatch
):
    """A real ``tolins dataset`` holds the dataset; a second one with the same --out and
    name ends with one line before any episode. Killed (SIGKILL), the first leaves its
    temporary folder, which the next writer removes."""
    root = tmp_path / "root"
    argv = ["dataset", "--env", ENV, "--policy", "safe", *KINEMATIC, "--out", str(root)]
    argv += ["--name", NAME]
    first = subprocess.Popen(
        [sys.executable, "-m", "tolins.cli", *argv, "--episodes", "100000"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 120
        while not any(p.name.startswith(f".safe-v0.{first.pid}.") for p in _temporaries(root)):
            assert first.poll() is None and time.monotonic() < deadline, "no writer started"
            time.sleep(0.05)
        with monkeypatch.context() as refused:  # before any episode: no env is built
            refused.setattr(KinematicBatch, "__init__", _no_episode)
            assert main([*argv, "--episodes", "2"]) == 2
        line = _one_line(capsys)
        assert f"{root / NAME} is being written by process {first.pid}; allowed: wait" in line
    finally:
        first.send_signal(signal.SIGKILL)
        first.wait()
    assert [p.name.split(".")[2] for p in _temporaries(root)] == [str(first.pid)]
    assert main([*argv, "--episodes", "2"]) == 0
    assert _temporaries(root) == []
    assert sorted(p.name for p in (root / NAME).parent.iterdir()) == ["safe-v0"]  # no lock
    assert minari.MinariDataset(root / NAME / "data").total_episodes == 2


def test_only_the_temporaries_of_dead_processes_are_removed(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    alive = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    folder = tmp_path / "tolins" / "test"
    try:
        stale = folder / f".safe-v0.{dead.pid}.k3j_x9ab.tmp"
        running = folder / f".safe-v0.{alive.pid}.q1w2e3r4.tmp"
        other = folder / f".other-v0.{dead.pid}.k3j_x9ab.tmp"  # another dataset's
        for path in (stale, running, other):
            (path / "data").mkdir(parents=True)
            (path / "data" / "main_data.hdf5").write_bytes(b"partial")
        _safe(tmp_path, episodes=1)
        assert not stale.exists()
        assert running.exists() and other.exists()
    finally:
        alive.kill()
        alive.wait()


def test_a_dataset_that_appears_at_the_rename_is_one_clear_error(tmp_path):
    """Another writer that holds no claim finishes first: the error says so, its dataset is
    kept and this one's temporary is removed."""
    target = tmp_path / NAME

    def other_writer(record) -> None:
        (target / "data").mkdir(parents=True, exist_ok=True)
        (target / "data" / "metadata.json").write_text("{}")

    with pytest.raises(ValueError, match="was written by another process meanwhile; allowed"):
        _safe(tmp_path, episodes=1, on_episode=other_writer)
    assert (target / "data" / "metadata.json").read_text() == "{}"
    assert _temporaries(tmp_path) == []


def test_another_thread_cannot_claim_a_dataset_being_written(tmp_path):
    from tolins.datasets.target import claim_target

    errors: list[Exception] = []

    def second() -> None:
        try:
            with claim_target(tmp_path, NAME):
                pass
        except ValueError as error:
            errors.append(error)

    with claim_target(tmp_path, NAME), claim_target(tmp_path, NAME):  # one thread nests
        thread = threading.Thread(target=second)
        thread.start()
        thread.join()
    assert len(errors) == 1 and "is being written by process" in str(errors[0])
    with claim_target(tmp_path, NAME):  # released: free again
        pass
