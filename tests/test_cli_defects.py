"""CLI cases a new user meets: impossible figures in a results file refused by ``tolins
compare``, ``--resume`` without a checkpoint and an empty ``--methods`` refused, every
registered id accepted wherever an id is, and ``--version`` (the bench's progress bar:
tests/test_progress.py)."""

from __future__ import annotations

import json
import re
from importlib.metadata import version
from pathlib import Path

import gymnasium as gym
import pytest

import tolins
from tolins.bench.reference import reference_path
from tolins.cli import build_parser, main
from tolins.envs.tasks import GENERIC_ID, GENERIC_IDS, GRADE_TASKS, env_ids

ENV = "tolins/Circle2x2-v1"
GRADE = "tolins/Circle2x2Fit20-v1"
ROOT = Path(__file__).resolve().parents[1]


def _one_line(capsys) -> str:
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1, captured.err
    return captured.err


# --- tolins compare: figures no run can give -----------------------------------------


def _row(document: dict) -> dict:
    return document["rows"]["C1.1"]


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (lambda r: r.update(success_mean=5.0), "success_mean 5.0"),
        (lambda r: r.update(success_mean=-0.1), "success_mean -0.1"),
        (lambda r: r.update(success_std=0.7), "success_std 0.7"),
        (lambda r: r.update(success_per_seed=[1.0, 1.2, 1.0]), "success_per_seed [1.0, 1.2"),
        (lambda r: r.update(success_ci=[0.5, 1.5]), "success_ci [0.5, 1.5]"),
        (lambda r: r.update(success_ci=[1.0, 0.5]), "success_ci [1.0, 0.5]"),
        (lambda r: r.update(success_ci="high"), "success_ci 'high'"),
        (lambda r: r.update(reward_ci=[24.0, 23.0]), "reward_ci [24.0, 23.0]"),
        (lambda r: r.update(steps_mean=-3.0), "steps_mean -3.0"),
        (lambda r: r.update(collisions_std=-1.0), "collisions_std -1.0"),
        (lambda r: r.update(collisions_per_seed=[-1.0, 1.0, 1.0]), "collisions_per_seed"),
        (lambda r: r.update(faults=-1), "faults -1"),
        (lambda r: r.update(faults=151), "faults 151 > episodes 150"),
        (lambda r: r.update(seeds=3, episodes=2), "seeds 3 > episodes 2"),
    ],
)
def test_compare_refuses_impossible_figures_naming_file_row_and_field(
    tmp_path, capsys, edit, field
):
    document = json.loads(reference_path("quick").read_text())
    good = tmp_path / "good.json"
    good.write_text(json.dumps(document))
    edit(_row(document))
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(document))
    assert main(["compare", str(bad), str(good)]) == 2
    err = _one_line(capsys)
    assert f"{bad}: row C1.1: {field}" in err and "allowed" in err, err


def test_the_shipped_references_hold_possible_figures_only():
    from tolins.bench.reference import reference_names
    from tolins.bench.table.results import read_results

    for name in reference_names():
        assert read_results(reference_path(name))["rows"]


# --- tolins train --resume without a checkpoint -----------------------------------------


@pytest.fixture
def no_training(monkeypatch):
    """Any training the command would start fails the test at once."""
    from tolins.learning.imitation import runs

    def started(*_, **__):
        raise AssertionError("a training started")

    for name in ("run_bc", "run_rs_gail", "run_tolerance_guided"):
        monkeypatch.setattr(runs, name, started)


@pytest.mark.parametrize("method", ["rs-gail", "tolerance-guided"])
def test_resume_without_a_checkpoint_is_refused(tmp_path, capsys, no_training, method):
    nominal = tmp_path / "nominal.pt"
    nominal.write_bytes(b"a policy file")
    extra = ["--nominal", str(nominal)] if method == "tolerance-guided" else []
    for out in (tmp_path / "empty", tmp_path / "new" / "run"):
        out.parent.mkdir(exist_ok=True)
        if out.name == "empty":
            out.mkdir()
        argv = ["train", method, "--env", ENV, "--out", str(out), "--resume", *extra]
        assert main(argv) == 2
        err = _one_line(capsys)
        assert err.startswith(f"tolins train {method}: --resume: no checkpoint found in {out}")
        assert "allowed" in err
    assert not (tmp_path / "new" / "run").exists()


# --- tolins infer-study --methods -------------------------------------------------------


@pytest.mark.parametrize(
    ("methods", "why"),
    [
        ("", "names nothing"),
        (",", "names nothing"),
        ("inference,,random", "has an empty name"),
        ("inference,nope", "'nope' is unknown"),
        ("random,random", "'random' is named twice"),
    ],
)
def test_infer_study_refuses_an_empty_or_bad_method_list(monkeypatch, capsys, methods, why):
    from tolins.inference import study

    def started(*_, **__):
        raise AssertionError("the study started")

    monkeypatch.setattr(study, "run_study", started)
    assert main(["infer-study", "--samples", "1", "--methods", methods]) == 2
    err = _one_line(capsys)
    assert err.startswith("tolins infer-study: --methods") and why in err, err
    assert "allowed: a comma-separated subset of " + ", ".join(study.METHODS) in err


def test_a_method_list_is_parsed_in_order_spaces_ignored():
    from tolins.inference.study import parse_methods

    assert parse_methods("random, inference") == ("random", "inference")


# --- every registered id, wherever an id is taken ---------------------------------------


def test_the_task_table_lists_every_registered_id_and_one_check_serves_all():
    from tolins.rollouts import episodes

    registered = {i for i in gym.registry if i.startswith("tolins/")}
    assert set(env_ids()) == registered
    assert env_ids(generic=False) == tuple(i for i in env_ids() if i not in GENERIC_IDS.values())
    assert episodes.check_env_id is tolins.envs.tasks.check_env_id
    with pytest.raises(ValueError, match=f"unknown env 'tolins/Nope-v1'; allowed: .*{GRADE}"):
        tolins.envs.tasks.check_env_id("tolins/Nope-v1")


def _commands(env_id: str, tmp: Path) -> list[list[str]]:
    out = str(tmp / "out")
    return [
        ["record", "--env", env_id, "--out", str(tmp / "x.rrd")],
        ["dataset", "--env", env_id, "--policy", "safe", "--out", out],
        ["train", "bc", "--env", env_id, "--out", out],
        ["train", "rs-gail", "--env", env_id, "--out", out],
        ["train", "tolerance-guided", "--env", f"{ENV},{env_id}", "--out", out, "--nominal", "p"],
    ]


@pytest.mark.parametrize("env_id", env_ids(generic=False))
def test_every_preset_id_passes_the_id_check_of_every_command(tmp_path, env_id):
    parser = build_parser()
    for argv in _commands(env_id, tmp_path):
        assert env_id in parser.parse_args(argv).env  # refused: UsageError


def test_the_generic_id_is_still_refused_with_why(tmp_path, capsys):
    for argv in _commands(GENERIC_ID, tmp_path):
        assert main(argv) == 2
        err = _one_line(capsys)
        assert "needs socket=" in err and all(task.gym_id in err for task in GRADE_TASKS)


def test_evaluate_takes_a_grade_id(tmp_path, capsys):
    argv = ["evaluate", "--policy", "safe", "--env", GRADE, "--episodes", "1"]
    assert main([*argv, "--backend", "kinematic", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "| safe | safe | Circle2x2Fit20-v1 |" in out
    rows = json.loads((tmp_path / "results.json").read_text())["rows"]
    assert rows["safe"]["eval_env"] == GRADE


# --- --version and the agents doc -------------------------------------------------------


def test_version_prints_the_installed_version(capsys):
    with pytest.raises(SystemExit) as leaving:
        main(["--version"])
    assert leaving.value.code == 0
    assert capsys.readouterr().out == f"tolins {version('tolins')}\n"
    assert version("tolins") == tolins.__version__


def test_the_agents_doc_names_the_schema_evaluate_writes():
    from tolins.bench.table.results import SCHEMA

    doc = (ROOT / "docs" / "agents.md").read_text()
    named = set(re.findall(r"tolins\.results/\d+", doc))
    assert named == {SCHEMA}, named
