"""CLI edge cases: a user policy's exceptions reported as the policy's, replay's step
and time checked, diverged training refused, sizes and seeds bounded, repeated options
added up, torch's advice replaced by one line, dead processes' temporaries removed."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest
import torch

from tolins.cli import build_parser, main

ENV = "tolins/Circle2x2-v1"
EVALUATE = ["evaluate", "--env", ENV, "--backend", "kinematic", "--episodes", "2"]


def _one_line(capsys) -> str:
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1, captured.err
    return captured.err


@pytest.fixture
def user_module(tmp_path, monkeypatch):
    (tmp_path / "mypolicies.py").write_text(
        textwrap.dedent(
            """
            import sys

            def buggy(observation):
                raise ValueError("my own bug in policy")

            def leaves(observation):
                sys.exit(0)

            def words(observation):
                return "four numbers"
            """
        )
    )
    monkeypatch.chdir(tmp_path)
    sys.modules.pop("mypolicies", None)
    yield tmp_path
    sys.modules.pop("mypolicies", None)


def test_a_policys_exception_is_reported_as_the_policys_with_its_traceback(user_module, capsys):
    assert main([*EVALUATE, "--policy", "mypolicies:buggy"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0] == "Traceback (most recent call last):"
    assert any("mypolicies.py" in line and "buggy" in line for line in err), err
    assert err[-1] == (
        "tolins evaluate: policy 'mypolicies:buggy' raised ValueError: my own bug in policy "
        "(its traceback above)"
    )


def test_a_policys_system_exit_is_no_success(user_module, capsys):
    out = user_module / "out"
    assert main([*EVALUATE, "--policy", "mypolicies:leaves", "--out", str(out)]) == 1
    assert "raised SystemExit" in capsys.readouterr().err
    assert not (out / "results.json").exists()


def test_a_policys_malformed_action_is_one_line(user_module, capsys):
    assert main([*EVALUATE, "--policy", "mypolicies:words"]) == 2
    assert "returned 'four numbers'; allowed: 4 finite numbers" in _one_line(capsys)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec") / "c.rrd"
    argv = ["record", "--env", ENV, "--backend", "kinematic", "--episodes", "1"]
    assert main([*argv, "--out", str(out)]) == 0
    return out


@pytest.mark.parametrize(
    ("when", "message"),
    [
        (["--time", "nan"], "'nan'; allowed: a finite number ≥ 0"),
        (["--time", "inf"], "'inf'; allowed: a finite number ≥ 0"),
        (["--time", "1e9"], "time 1e+09 s is past its end; allowed: 0 …"),
        (["--time", "1e300"], "time 1e+300 s is past its end"),
        (["--step", "9999"], "step 9999 is past its last step; allowed: 0 …"),
    ],
)
def test_replay_outside_the_recording_exits_2_with_one_line(
    recording, tmp_path, capsys, when, message
):
    capsys.readouterr()
    shot = tmp_path / "s.png"
    assert main(["replay", str(recording), "--screenshot", str(shot), *when]) == 2
    assert message in _one_line(capsys)
    assert not shot.exists() and not list(tmp_path.glob(".*"))


def test_a_diverged_embedding_training_is_refused_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "e.pt"
    argv = ["embed", "train", "--family", "circle", "--workpieces", "32", "--epochs", "1"]
    assert main([*argv, "--learning-rate", "1e9", "--out", str(out)]) == 3  # refused
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "embedding training diverged: loss nan" in err and "--learning-rate" in err, err
    assert not out.exists()


def test_hidden_sizes_are_bounded(tmp_path, capsys):
    from tolins.learning.imitation.config import HIDDEN_MAX, ResidualConfig, RSGailConfig

    argv = ["train", "bc", "--env", ENV, "--backend", "kinematic", "--hidden", "1000000000"]
    assert main([*argv, "--out", str(tmp_path / "bc")]) == 2
    assert f"hidden=1000000000; allowed: an integer 1 … {HIDDEN_MAX}" in _one_line(capsys)
    with pytest.raises(ValueError, match="residual_hidden"):
        ResidualConfig(residual_hidden=HIDDEN_MAX + 1)
    with pytest.raises(ValueError, match="discriminator_hidden"):
        RSGailConfig(discriminator_hidden=10**9)


def test_bench_seeds_are_bounded(tmp_path, capsys):
    from tolins.bench.pipeline.config import SEEDS_MAX

    out = tmp_path / "b"
    assert main(["bench", "--seeds", str(SEEDS_MAX + 1), "--out", str(out)]) == 2
    assert f"allowed: an integer 1 … {SEEDS_MAX}" in _one_line(capsys)
    assert not out.exists()


def test_repeated_list_options_add_up():
    parser = build_parser()
    assert parser.parse_args(["bench", "--rows", "C2.1", "--rows", "C1.1,C2.2"]).rows == (
        "C2.1,C1.1,C2.2"
    )
    study = parser.parse_args(["infer-study", "--methods", "random", "--methods", "oracle"])
    assert study.methods == "random,oracle"


class _NotAPolicy:
    pass


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ({"weights": _NotAPolicy()}, "holds objects other than tensors and plain values"),
        ({"weights": torch.zeros(2)}, "has format None; allowed: 'tolins.policy/1'"),
    ],
)
def test_a_non_policy_pt_is_one_line(tmp_path, capsys, content, message):
    path = tmp_path / "other.pt"
    torch.save(content, path)
    assert main([*EVALUATE, "--policy", str(path)]) == 2
    err = _one_line(capsys)
    assert message in err and "weights_only" not in err, err


def test_record_removes_the_temporaries_of_dead_processes(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    alive = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        stale = tmp_path / f".x.rrd.{dead.pid}.tmp"
        running = tmp_path / f".x.rrd.{alive.pid}.tmp"
        shot = tmp_path / f".x.{dead.pid}.cut.rrd"
        for path in (stale, running, shot):
            path.write_bytes(b"partial")
        argv = ["record", "--env", ENV, "--backend", "kinematic", "--episodes", "1"]
        assert main([*argv, "--out", str(tmp_path / "x.rrd")]) == 0
        assert not stale.exists() and not shot.exists()
        assert running.exists()  # a live writer's file is left alone
    finally:
        alive.kill()
        alive.wait()
