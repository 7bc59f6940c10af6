"""The bench and ``compare`` check what they read: stage digests, episodes, the lock on
``--out``, truncated files named, malformed results refused with one line (a tiny bench of
two expert rows on the kinematic backend)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tolins.bench.jobs.row_evaluation import EPISODES, RECORDING
from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.runner import run_bench
from tolins.bench.store.cache import MARKER
from tolins.cli import main

ROWS = "C1.1,C2.1"


def _config(out: Path) -> BenchConfig:
    return BenchConfig(
        profile="tiny", backend="kinematic", rows=ROWS, out=str(out), study=False, figures=False
    )


def _run(out: Path) -> tuple[object, list[str]]:
    lines: list[str] = []
    return run_bench(_config(out), progress=False, log=lines.append), lines


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished tiny bench: its folder and its run."""
    out = tmp_path_factory.mktemp("bench") / "run"
    return out, _run(out)[0]


def _copy(finished, tmp_path: Path) -> Path:
    out = tmp_path / "copy"
    shutil.copytree(finished[0], out)
    return out


def _stage(out: Path, name: str = "eval-C2.1-seed0") -> Path:
    (folder,) = (out / "stages").glob(f"{name}-*")
    return folder


def _rewrite_digests(folder: Path) -> None:
    """What an editor that knew the scheme would do: the digests made to fit the files."""
    from tolins.bench.store.integrity import folder_digests

    marker = json.loads((folder / MARKER).read_text())
    marker["files"] = folder_digests(folder, skip=(MARKER,))
    (folder / MARKER).write_text(json.dumps(marker))


def test_every_finished_stage_records_the_digest_of_each_file(finished):
    out, _ = finished
    for marker in (out / "stages").glob(f"*/{MARKER}"):
        files = json.loads(marker.read_text())["files"]
        assert files and all(len(d) == 64 for d in files.values()), marker
    assert {EPISODES, RECORDING} <= set(json.loads((_stage(out) / MARKER).read_text())["files"])


@pytest.mark.parametrize(
    "damage",
    ["edited episodes", "missing recording", "truncated stage.json", "no digests"],
)
def test_a_bad_stage_folder_is_named_moved_aside_and_recomputed(finished, tmp_path, damage):
    out = _copy(finished, tmp_path)
    folder = _stage(out)
    if damage == "edited episodes":
        rows = json.loads((folder / EPISODES).read_text())
        rows[0]["reward"] = 99.0
        (folder / EPISODES).write_text(json.dumps(rows))
    elif damage == "missing recording":
        (folder / RECORDING).unlink()
    elif damage == "truncated stage.json":
        (folder / MARKER).write_text((folder / MARKER).read_text()[:20])
    else:
        marker = json.loads((folder / MARKER).read_text())
        del marker["files"]
        (folder / MARKER).write_text(json.dumps(marker))
    run, lines = _run(out)
    (bad,) = [line for line in lines if "bad" in line]
    assert str(folder) in bad and "running the stage again" in bad, bad
    assert run.results == finished[1].results
    assert "eval-C2.1-seed0" not in run.cached and "eval-C1.1-seed0" in run.cached
    assert len(list((out / "stages" / ".bad").iterdir())) == 1


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda rows: rows[:1], "1 episodes; allowed: the stage's 2"),
        (lambda rows: [{**rows[0], "reward": 99.0}, rows[1]], "episode 0: reward 99.0"),
        (lambda rows: [rows[0], {**rows[1], "reward": float("nan")}], "episode 1: reward nan"),
        (lambda rows: [{**rows[0], "steps": "40"}, rows[1]], "episode 0: steps '40'"),
        (lambda rows: {"episodes": rows}, "dict episodes"),
    ],
)
def test_episodes_an_episode_cannot_be_are_refused_naming_the_file(finished, tmp_path, edit, match):
    out = _copy(finished, tmp_path)
    folder = _stage(out)
    rows = json.loads((folder / EPISODES).read_text())
    (folder / EPISODES).write_text(json.dumps(edit(rows)))
    _rewrite_digests(folder)
    with pytest.raises(ValueError, match=match) as error:
        _run(out)
    assert str(folder / EPISODES) in str(error.value)


def test_a_truncated_recording_is_not_copied_into_recordings(finished, tmp_path):
    out = _copy(finished, tmp_path)
    folder = _stage(out)
    shutil.rmtree(out / "recordings")
    data = (folder / RECORDING).read_bytes()
    (folder / RECORDING).write_bytes(data[: len(data) // 2])
    _rewrite_digests(folder)
    with pytest.raises(ValueError, match=r"episodes\.rrd.*delete"):
        _run(out)
    assert not (out / "recordings" / "C2.1.rrd").exists()


def test_a_truncated_json_or_npy_names_the_file(tmp_path):
    from tolins.bench.store.integrity import read_array, read_json

    (tmp_path / "a.json").write_text('{"rows": ')
    with pytest.raises(ValueError, match=r"a\.json: not JSON"):
        read_json(tmp_path / "a.json")
    np.save(tmp_path / "m.npy", np.arange(10.0))
    (tmp_path / "m.npy").write_bytes((tmp_path / "m.npy").read_bytes()[:100])
    with pytest.raises(ValueError, match=r"m\.npy: not a numeric \.npy array"):
        read_array(tmp_path / "m.npy")


def test_the_trajectories_stage_file_is_read_back_checked(tmp_path):
    from tolins.bench.jobs.trajectories import TRAJECTORIES, read_trajectories
    from tolins.bench.store.integrity import StageFileError

    path = tmp_path / TRAJECTORIES
    poses = [[1.0, 2.0, 0.0, 3.0], [0.5, 1.0, 0.0, 2.0]]
    path.write_text(json.dumps({"trajectories": [{"label": "expert (safe)", "poses": poses}]}))
    assert read_trajectories(tmp_path)["expert (safe)"].tolist() == poses
    for bad in (
        [poses],
        {"trajectories": {"expert (safe)": poses}},
        {"trajectories": [{"label": "expert (safe)", "poses": [[1.0, 2.0]]}]},
        {"trajectories": [{"label": 3, "poses": poses}]},
    ):
        path.write_text(json.dumps(bad))
        with pytest.raises(StageFileError, match=re.escape(str(path))):
            read_trajectories(tmp_path)


class Payload:
    """Unpickling this creates ``marker``."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


TRAINED = ["--profile", "tiny", "--backend", "kinematic", "--rows", "C2.3"]
TRAINED += ["--no-study", "--no-robustness", "--no-robot"]


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """A finished tiny bench of π_n (BC, then RS-GAIL) and its trajectories: its folder."""
    out = tmp_path_factory.mktemp("trained") / "run"
    assert main(["bench", *TRAINED, "--out", str(out)]) == 0
    return out


@pytest.mark.parametrize(
    ("name", "reader"),
    [
        ("policy.pt", "eval-C2.3-seed0"),
        ("policy.pt", "trajectories-pi_n_safe-seed0"),
        ("means.npy", "trajectories-pi_n_safe-seed0"),
        ("curves.csv", None),  # read by the reports
    ],
)
def test_a_planted_stage_file_stops_the_bench_naming_it_and_its_remedy(
    trained, tmp_path, capsys, name, reader
):
    import torch

    out = tmp_path / "copy"
    shutil.copytree(trained, out)
    folder, marker = _stage(out, "pi_n_safe-seed0"), tmp_path / "ran"
    if name == "policy.pt":
        torch.save({"format": "tolins.policy/1", "state_dict": Payload(marker)}, folder / name)
    elif name == "means.npy":
        np.save(folder / name, np.array([Payload(marker)], dtype=object), allow_pickle=True)
    else:
        (folder / name).write_text("env_steps,reward,success\n240,zero,0\n")
    _rewrite_digests(folder)  # the digest check cannot tell
    if reader is not None:
        shutil.rmtree(_stage(out, reader))  # a stage that reads the file runs again
    capsys.readouterr()
    assert main(["bench", *TRAINED, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("tolins bench:")]
    assert len(lines) == 1 and "Traceback" not in err, err  # besides the progress bar
    assert str(folder / name) in lines[0], lines
    assert f"delete its stage's folder {folder} and the same command runs" in lines[0], lines
    assert not marker.exists()
    assert (folder / MARKER).exists()  # nothing was moved or deleted


def test_a_second_bench_on_one_out_names_the_process_holding_it(tmp_path, capsys):
    out = tmp_path / "held"
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time; from tolins.bench.pipeline.lock import locked_folder\n"
            "with locked_folder(sys.argv[1]):\n    print('held', flush=True); time.sleep(60)",
            str(out),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        args = ["bench", "--profile", "tiny", "--backend", "kinematic", "--rows", "C2.1"]
        assert main([*args, "--no-study", "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"pid {holder.pid}" in err[0] and "in use" in err[0], err
        assert not (out / "stages").exists()  # nothing was run
    finally:
        holder.kill()
        holder.wait()
    time.sleep(0.1)
    from tolins.bench.pipeline.lock import locked_folder

    with locked_folder(out):  # released when its holder died
        pass


# --- tolins compare ---------------------------------------------------------------------


def _results(finished, tmp_path: Path, name: str, edit=None) -> Path:
    document = json.loads((finished[0] / "results.json").read_text())
    if edit is not None:
        edit(document)
    path = tmp_path / name
    path.write_text(json.dumps(document))
    return path


def _error(argv: list[str], capsys) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1, captured.err
    return captured.err


def _row(document: dict) -> dict:
    return document["rows"]["C2.1"]


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda d: _row(d).update(reward_per_seed=12.5), "row C2.1: reward_per_seed 12.5"),
        (lambda d: _row(d).pop("reward_mean"), "row C2.1: no reward_mean"),
        (lambda d: _row(d).update(reward_mean=1e9), "reward_mean 1000000000.0 is not the mean"),
        (lambda d: _row(d).update(success_mean=float("nan")), "success_mean nan"),
        (lambda d: _row(d).update(reward_per_seed=[1e9]), "are not the means of its"),
        (lambda d: d.pop("rows"), "no 'rows'; allowed: an object of row id"),
        (lambda d: d.update(rows=[1]), "list 'rows'"),
        (lambda d: d["rows"].update({"C2.1": "x"}), "row C2.1: a str"),
    ],
)
def test_compare_refuses_malformed_results_with_one_line(finished, tmp_path, capsys, edit, match):
    good = _results(finished, tmp_path, "good.json")
    bad = _results(finished, tmp_path, "bad.json", edit)
    err = _error(["compare", str(bad), str(good)], capsys)
    assert match in err and "bad.json" in err, err


def test_compare_json_to_a_folder_is_refused_before_any_work(finished, tmp_path, capsys):
    good = str(_results(finished, tmp_path, "good.json"))
    err = _error(["compare", good, good, "--json", str(tmp_path)], capsys)
    assert "--json" in err and "allowed: a path ending in .json" in err, err
    (tmp_path / "out.json").mkdir()
    err = _error(["compare", good, good, "--json", str(tmp_path / "out.json")], capsys)
    assert "--json" in err and "is a folder" in err, err


@pytest.mark.parametrize(
    ("edit", "why"),
    [
        (lambda d: _row(d).update(eval_env="tolins/Circle2x4-v1"), "eval env"),
        (lambda d: d.update(backend="mujoco"), "backend kinematic vs mujoco"),
        (lambda d: d.update(profile="quick"), "profile tiny vs quick"),
    ],
)
def test_rows_of_runs_that_measured_something_else_are_not_comparable(
    finished, tmp_path, capsys, edit, why
):
    from tolins.bench.table.compare import compare

    good = _results(finished, tmp_path, "good.json")
    other = _results(finished, tmp_path, "other.json", edit)
    statuses = {row.row: row.status for row in compare(str(good), str(other)).rows}
    assert statuses["C2.1"].startswith("not comparable") and why in statuses["C2.1"], statuses
    assert compare(str(good), str(good)).rows[0].status == "consistent"
    assert main(["compare", str(good), str(other)]) == 0
    assert "not comparable" in capsys.readouterr().out
