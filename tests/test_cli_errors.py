"""Bad options of every ``tolins`` command: exit status 2, one line on stderr naming the
option and what is allowed, no traceback, and nothing run or written first."""

from __future__ import annotations

import subprocess
from pathlib import Path

import mujoco
import pytest

from tolins.cli import build_parser, main
from tolins.cli import checks as cli_checks
from tolins.envs.tasks import GENERIC_ID, TASKS
from tolins.physics.kinematic import KinematicBatch

ENV = TASKS[1].gym_id
PROC = Path("/proc/self").is_dir()  # a folder in which nothing can be created (Linux)


def _cases(tmp: Path) -> list[tuple[list[str], str]]:
    """(argv, the option its one-line error names)."""
    file = tmp / "file"
    run = tmp / "run"
    kinematic = ["--backend", "kinematic"]
    new = ["--out", str(tmp / "new")]
    cases = [
        (["train", "rs-gail", "--env", ENV, "--out", str(file)], "--out"),
        (["train", "bc", "--env", ENV, "--out", str(file / "sub")], "--out"),
        (["train", "rs-gail", "--env", ENV, "--out", str(run)], "--resume"),
        (["train", "rs-gail", "--env", ENV, *new, "--init", str(tmp / "no.pt")], "--init"),
        (["train", "tolerance-guided", "--env", ENV, *new, "--nominal", str(run)], "--nominal"),
        (["record", "--env", GENERIC_ID, "--out", str(tmp / "x.rrd")], "--env"),
        (["record", "--env", ENV, "--out", str(tmp / "x.txt")], "--out"),
        (["record", "--env", ENV, "--out", str(run)], "--out"),
        (["record", "--env", ENV, "--out", str(tmp / "x.rrd"), "--seed", "-5"], "--seed"),
        (["demo", "--seed", str(cli_checks.SEED_MAX + 1)], "--seed"),
        (["infer-study", "--seed", "-1"], "--seed"),
        (["infer-study", "--seed", "one"], "--seed"),
        (["infer-study", "--json", str(file / "x.json")], "--json"),
        (["infer-study", "--plot", str(tmp / "x.pdf")], "--plot"),
        (["train", "bc", "--env", ENV, "--out", str(tmp / "new"), "--seed", "-1"], "--seed"),
        (["train", "rs-gail", "--env", ENV, "--out", str(tmp / "new"), "--seed", "-1"], "--seed"),
        (["embed", "train", "--seed", "-1"], "--seed"),
        (["embed", "train", "--out", str(run)], "--out"),
        (["bench", "--out", str(file), "--profile", "tiny", *kinematic], "--out"),
        (["bench", "--seeds", "0", "--out", str(tmp / "new")], "--seeds"),
        (["train", "bc", "--env", "CartPole-v1", "--out", str(tmp / "new")], "--env"),
        (["train", "tolerance-guided", "--env", f"{ENV},tolins/Nope-v1", *new], "--env"),
        (["replay", str(file), "--web", "--port", "-1"], "--port"),
        (["replay", str(file), "--web", "--grpc-port", "65536"], "--grpc-port"),
        (["replay", str(file), "--web", "--port", "7000", "--grpc-port", "7000"], "--port"),
        (["replay", str(file), "--screenshot", str(tmp / "shot.jpg")], "--screenshot"),
        (["evaluate", "--policy", "safe", "--env", ENV, "--out", str(file)], "--out"),
        (["evaluate", "--policy", "safe", "--env", ENV, "--episodes", "0"], "--episodes"),
    ]
    if PROC:
        cases += [
            (["infer-study", "--json", "/proc/x.json"], "--json"),
            (["record", "--env", ENV, "--out", "/proc/x.rrd"], "--out"),
            (["bench", "--out", "/proc/x", "--profile", "tiny"], "--out"),
            (["train", "bc", "--env", ENV, "--out", "/proc/x"], "--out"),
            (["embed", "train", "--out", "/proc/x.pt"], "--out"),
            (["evaluate", "--policy", "safe", "--env", ENV, "--out", "/proc/x"], "--out"),
        ]
    return cases


def _ids() -> list[str]:
    return [" ".join(argv[:2]) + f" {option}" for argv, option in _cases(Path("/t"))]


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    build_parser()
    (tmp_path / "file").write_text("not a folder")
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "checkpoint.pt").write_bytes(b"an earlier run")
    return tmp_path


@pytest.fixture
def no_work(monkeypatch):
    """Every way a command starts its work — building a MuJoCo model, a kinematic batch,
    a viewer or any other process — fails the test instead."""

    def started(*args, **kwargs):
        raise AssertionError("the command started its work before checking its options")

    monkeypatch.setattr(mujoco.MjSpec, "compile", started)
    for build in ("from_xml_string", "from_xml_path", "from_binary_path"):
        monkeypatch.setattr(mujoco.MjModel, build, staticmethod(started))
    monkeypatch.setattr(KinematicBatch, "__init__", started)
    monkeypatch.setattr(subprocess.Popen, "__init__", started)


@pytest.mark.parametrize("index", range(len(_ids())), ids=_ids())
def test_a_bad_option_exits_2_with_one_line_before_any_work(index, folder, capsys, no_work):
    argv, option = _cases(folder)[index]
    before = sorted(folder.rglob("*"))
    status = main(argv)
    out, err = capsys.readouterr()
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err  # no traceback, no progress bar: nothing started
    assert option in lines[0] and "allowed" in lines[0], lines[0]
    assert lines[0].startswith("tolins "), lines[0]
    assert out == ""
    assert sorted(folder.rglob("*")) == before  # nothing written, not even a folder


def test_record_names_the_ids_it_supports(folder, capsys):
    assert main(["record", "--env", GENERIC_ID, "--out", str(folder / "x.rrd")]) == 2
    err = capsys.readouterr().err
    assert "socket" in err
    assert all(task.gym_id in err for task in TASKS)


def test_the_checkpoint_name_is_rs_gails():
    from tolins.cli import train as train_cli
    from tolins.learning.imitation import rs_gail

    assert train_cli.CHECKPOINT == rs_gail.CHECKPOINT


def test_good_paths_pass_and_nothing_is_created(tmp_path):
    new = tmp_path / "a" / "b"
    assert cli_checks.output_folder("--out", new) == new
    assert cli_checks.output_file("--out", new / "x.rrd", suffixes=(".rrd",)) == new / "x.rrd"
    assert cli_checks.output_folder("--out", tmp_path) == tmp_path
    assert list(tmp_path.iterdir()) == []  # the probe file is gone, no folder made


@pytest.mark.parametrize(
    ("check", "good", "bad"),
    [
        (cli_checks.seed, ["0", str(cli_checks.SEED_MAX)], ["-1", str(2**32), "1.5", ""]),
        (cli_checks.port, ["1", "65535"], ["0", "-1", "65536", "http"]),
        (cli_checks.positive_int, ["1", "40"], ["0", "-3", "two"]),
    ],
)
def test_option_types_accept_their_range_only(check, good, bad):
    import argparse

    assert [check(text) for text in good] == [int(text) for text in good]
    for text in bad:
        with pytest.raises(argparse.ArgumentTypeError, match="allowed"):
            check(text)


def test_an_interrupted_command_exits_130_without_a_traceback(folder, capsys, monkeypatch):
    from tolins.inference import study

    def interrupt(*_, **__):
        raise KeyboardInterrupt

    monkeypatch.setattr(study, "run_study", interrupt)
    assert main(["infer-study", "--samples", "1"]) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "tolins infer-study: interrupted"


@pytest.mark.parametrize("seed", [-1, 2**32, 1.5, True, "0"])
def test_configs_refuse_the_seeds_the_cli_refuses(seed):
    from tolins.inference.study import StudyConfig
    from tolins.learning.agents.sb3_config import Sb3Config
    from tolins.learning.embedding.config import EmbeddingTrainConfig
    from tolins.learning.imitation.config import TaskConfig

    makers = [
        lambda s: TaskConfig(seed=s),
        lambda s: StudyConfig(seed=s),
        lambda s: EmbeddingTrainConfig(seed=s),
        lambda s: Sb3Config("sac", ENV, seed=s),
    ]
    for make in makers:
        assert make(cli_checks.SEED_MAX).seed == cli_checks.SEED_MAX
        with pytest.raises(ValueError, match=r"seed=.*allowed: 0 ≤ an integer ≤ 4294967295"):
            make(seed)
