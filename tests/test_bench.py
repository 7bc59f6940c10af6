"""The benchmark suite: claims check, figures per row, the stage cache, whole tiny runs."""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import gymnasium
import numpy as np
import pytest

from tolins.bench.jobs import row_evaluation
from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.runner import plan_bench, run_bench
from tolins.bench.store.cache import MARKER, StageCache, stage_key
from tolins.bench.table.claims import CLAIMS, HELD, INCONCLUSIVE, NOT_EVALUATED, NOT_HELD
from tolins.bench.table.results import read_results, row_entry
from tolins.bench.table.rows import ALL_ROW_IDS, PAPER, ROW_IDS, ROWS, TRAININGS, select_rows
from tolins.cli import main
from tolins.inference.study import METHODS
from tolins.record import check_rrd
from tolins.rollouts.episodes import Episode

SCHEMA = {
    "policy",
    "train_env",
    "eval_env",
    "reward_mean",
    "reward_std",
    "success_mean",
    "success_std",
    "steps_mean",
    "steps_std",
    "collisions_mean",
    "collisions_std",
    "episodes",
    "seeds",
}


# The claims check (three-valued verdicts on interval estimates): tests/test_statistics.py.


# --- one row's figures --------------------------------------------------------------------


def _episodes(rewards, success=True):
    return [Episode(float(r), success, 30 + i, i % 3) for i, r in enumerate(rewards)]


def test_row_entry_one_seed_spreads_over_episodes():
    entry = row_entry(ROWS[0], [_episodes([10, 20, 30])])
    assert set(entry) >= SCHEMA
    assert entry["reward_mean"] == 20 and entry["reward_std"] == pytest.approx(np.std([10, 20, 30]))
    assert entry["steps_mean"] == 31 and entry["success_mean"] == 1.0
    assert (entry["episodes"], entry["seeds"], entry["std_over"]) == (3, 1, "episodes")


def test_row_entry_several_seeds_spread_over_the_seed_means():
    entry = row_entry(ROWS[0], [_episodes([10, 20]), _episodes([30, 50])])
    assert entry["reward_mean"] == 27.5
    assert entry["reward_std"] == pytest.approx(np.std([15, 40]))
    assert (entry["episodes"], entry["seeds"], entry["std_over"]) == (4, 2, "seeds")
    with pytest.raises(ValueError, match="no episodes"):
        row_entry(ROWS[0], [_episodes([1.0]), []])


# --- the table and the configuration -------------------------------------------------------


def test_table_has_the_papers_15_rows_and_their_trainings():
    assert tuple(PAPER) == ROW_IDS
    assert len(ROWS) == 15
    by_id = {row.id: row for row in ROWS}
    assert [t.name for t in by_id["C3.2"].trainings] == ["bc_safe", "pi_n_safe", "pi_phi_circle"]
    assert by_id["C4.2"].inference and by_id["C4.2"].agent == by_id["C4.1"].agent
    assert by_id["C3.1"].agent == by_id["C2.3"].agent  # the paper: the same policy
    assert by_id["C1.1"].trainings == []
    assert TRAININGS["pi_phi_polygon"].env_ids == ("tolins/Square-v2", "tolins/Hexagon-v2")


def test_bad_rows_profiles_backends_and_seeds_are_refused():
    assert [r.id for r in select_rows("P2.2, C1.1")] == ["C1.1", "P2.2"]
    with pytest.raises(ValueError, match=r"rows: 'C9\.9' is unknown; allowed: .* of C1\.1"):
        select_rows("C1.1,C9.9")
    with pytest.raises(ValueError, match=r"rows: 'C1\.1' is named twice"):
        select_rows(["C1.1", "C1.1"])
    with pytest.raises(ValueError, match="profile='fast'; allowed: paper, quick, tiny"):
        BenchConfig(profile="fast")
    with pytest.raises(ValueError, match="backend='bullet'; allowed: mujoco, kinematic"):
        BenchConfig(backend="bullet")
    with pytest.raises(ValueError, match="seeds=0"):
        BenchConfig(seeds=0)


def test_cli_reports_a_bad_row_and_exits_2(capsys, tmp_path):
    assert main(["bench", "--rows", "C7.1", "--out", str(tmp_path)]) == 2
    assert "tolins bench: rows: 'C7.1' is unknown" in capsys.readouterr().err
    assert not (tmp_path / "stages").exists()


def test_a_stage_that_raises_is_its_traceback_and_exit_1_naming_it(capsys, tmp_path, monkeypatch):
    def broken(*_args, **_kwargs):
        raise ValueError("a bug inside the evaluation")

    monkeypatch.setattr(row_evaluation, "evaluate_row", broken)
    options = ["--profile", "tiny", "--rows", "C1.1", "--backend", "kinematic", "--no-study"]
    options += ["--no-robustness", "--no-robot", "--out", str(tmp_path)]
    assert main(["bench", *options]) == 1
    err = capsys.readouterr().err
    assert "Traceback" in err and "ValueError: a bug inside the evaluation" in err
    assert "tolins bench: stage eval-C1.1-seed0 failed (ValueError" in err
    assert not (tmp_path / "results.json").exists()


def _send_sigint(process: subprocess.Popen, to: str) -> None:
    """SIGINT to ``process`` as a whole (the kernel picks the thread), or to one of its
    threads other than the main one (what the kernel does while the main thread has signals
    blocked, as glibc's ``pthread_create`` does for an instant)."""
    if to == "process":
        process.send_signal(signal.SIGINT)
        return
    threads = [int(t) for t in os.listdir(f"/proc/{process.pid}/task") if int(t) != process.pid]
    assert threads, "the bench runs its stages on threads"
    libc = ctypes.CDLL(None, use_errno=True)
    assert libc.tgkill(process.pid, max(threads), signal.SIGINT) == 0, ctypes.get_errno()


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="tgkill and /proc are Linux's")
@pytest.mark.parametrize("to", ["process", "worker thread"])
def test_ctrl_c_stops_the_running_training_and_exits_130(tmp_path, to):
    """SIGINT while π_n trains: the bench stops within a control step of its rollouts
    (the training's stage is left unfinished, not run to its end) and exits 130, whichever
    of its threads the signal reaches."""
    options = ["bench", "--profile", "quick", "--rows", "C2.3", "--backend", "kinematic"]
    options += ["--seeds", "1", "--no-study", "--no-robustness", "--no-robot"]
    options += ["--out", str(tmp_path)]
    # SIGINT raises KeyboardInterrupt even where the test runs in the background (a shell
    # starts background jobs with SIGINT ignored, and their children inherit that).
    code = "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
    code += f"from tolins.cli import main; sys.exit(main({options!r}))"
    command = [sys.executable, "-c", code]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}  # each log line as it is written
    bench = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    try:
        for line in bench.stdout:
            if line.startswith("training pi_n_safe-seed0"):
                _send_sigint(bench, to)
                break
        _, err = bench.communicate(timeout=120)
    finally:
        bench.kill()
    assert bench.returncode == 130, err[-2000:]
    assert "tolins bench: interrupted" in err
    # Stopped before its folder was made or half-way through it: not finished.
    assert not list((tmp_path / "stages").glob("pi_n_safe-seed0-*/" + MARKER))
    assert list((tmp_path / "stages").glob("bc_safe-seed0-*/" + MARKER))  # kept for a resume


def test_a_training_that_refuses_to_go_on_is_one_line_naming_its_stage(
    tmp_path, monkeypatch, capsys
):
    from tolins.learning.artefacts import RunRefused
    from tolins.learning.imitation import runs

    def refuse(*_, **__):
        raise RunRefused("diverged: the BC loss is nan; lower the learning rate")

    monkeypatch.setattr(runs, "run_bc", refuse)
    options = ["bench", "--profile", "tiny", "--rows", "C2.2", "--backend", "kinematic"]
    options += ["--no-study", "--no-robustness", "--no-robot", "--out", str(tmp_path)]
    assert main(options) == 3
    lines = [line for line in capsys.readouterr().err.splitlines() if "tolins bench" in line]
    assert lines == [
        "tolins bench: stage bc_safe-seed0: diverged: the BC loss is nan; lower the learning rate"
    ]
    assert list((tmp_path / "stages").glob("demos-*/" + MARKER))  # kept for a resume


# --- the stage cache -------------------------------------------------------------------


def test_stage_key_ignores_key_order_and_sees_every_value():
    assert stage_key({"a": 1, "b": [1, 2]}) == stage_key({"b": [1, 2], "a": 1})
    assert stage_key({"a": 1, "b": [1, 2]}) != stage_key({"a": 1, "b": [2, 1]})


def test_a_stage_runs_once_and_an_interrupted_one_runs_again(tmp_path):
    cache = StageCache(tmp_path)
    calls = []

    def fail(folder: Path) -> None:
        (folder / "half.txt").write_text("half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        cache.run("train", {"x": 1}, fail)
    assert not cache.finished("train", {"x": 1})  # half-written: not finished

    def build(folder: Path) -> None:
        calls.append((folder / "half.txt").exists())
        (folder / "out.txt").write_text("done")

    folder, cached = cache.run("train", {"x": 1}, build)
    assert not cached and (folder / MARKER).is_file()
    again, cached = cache.run("train", {"x": 1}, build)
    assert cached and again == folder
    assert calls == [True]  # built once, in the interrupted stage's folder
    other, cached = cache.run("train", {"x": 2}, build)
    assert not cached and other != folder and calls == [True, False]
    assert json.loads((folder / MARKER).read_text())["config"] == {"x": 1}


# --- whole runs --------------------------------------------------------------------------


def _check_outputs(out: Path, backend: str) -> dict:
    document = json.loads((out / "results.json").read_text())
    assert document["schema"] == "tolins.results/3" and document["source"] == "bench"
    assert document["backend"] == backend and document["profile"] == "tiny"
    assert read_results(out) == document
    results = document["rows"]
    assert list(results) == list(ALL_ROW_IDS)  # Table 1, then the deep-RL baselines
    for entry in results.values():
        assert set(entry) >= SCHEMA
        assert entry["episodes"] == 2 and entry["seeds"] == 1
        assert all(np.isfinite(entry[k]) for k in SCHEMA if k.endswith(("_mean", "_std")))
    assert json.loads((out / f"results.{backend}.json").read_text()) == document
    run = json.loads((out / "run.json").read_text())
    assert set(run["claims"]) == {c.name for c in CLAIMS}
    claims = dict(run["claims"])
    for name in ("rs_gail_vs_deep_rl", "rs_gail_vs_dense_deep_rl"):
        deep_rl = claims.pop(name)  # tiny: 200 env steps against RS-GAIL's 240
        assert deep_rl["verdict"] == NOT_EVALUATED and "unequal budgets" in deep_rl["basis"]
        assert len(deep_rl["comparisons"]) == 4
    assert all(c["verdict"] in (HELD, NOT_HELD, INCONCLUSIVE) for c in claims.values())
    for name in run["claims"]:
        assert (out / "claims" / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    study = json.loads((out / "inference.json").read_text())
    assert set(METHODS) == set(study["methods"])
    markdown = (out / "results.md").read_text()
    assert all(f"| {row_id} |" in markdown for row_id in ALL_ROW_IDS)
    # the deep-RL section: every baseline's and π_n's curve, in curves.json too
    curves = json.loads((out / "curves.json").read_text())
    baselines = [t for t in TRAININGS.values() if t.method in ("ppo", "sac")]
    assert {f"{t.name}-seed0" for t in baselines} <= set(curves)
    assert "| training | reward learnt from | settings | env steps |" in markdown
    for training in baselines:
        assert f"| {training.name} | {training.reward_mode} | {training.method.upper()}, " in (
            markdown
        )
    assert "n_steps 256, n_envs 8 |" in markdown  # PPO keeps SB3's rollout of 2,048
    assert "| pi_n_safe | sparse + discriminator (RS-GAIL) |" in markdown
    assert "## The paper's claims in this run" in markdown
    for name in ("table", "learning_curves", "env_step_curves", "trajectories", "tolerance_images"):
        assert (out / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for row_id in ALL_ROW_IDS:
        check_rrd(out / "recordings" / f"{row_id}.rrd")
    return results


@pytest.mark.slow
def test_tiny_bench_on_both_backends_resumes_from_its_cache(tiny_bench, tmp_path):
    """The whole tiny bench on the kinematic backend (run once for the session, the
    ``tiny_bench`` fixture of tests/conftest.py), resumed in a copy of its folder, then run
    on MuJoCo there."""
    kinematic = tiny_bench.run
    tmp_path = tmp_path / "bench"
    shutil.copytree(tiny_bench.folder, tmp_path)
    first = _check_outputs(tmp_path, "kinematic")
    assert kinematic.cached == []
    assert "Backends side by side" not in (tmp_path / "results.md").read_text()

    again = run_bench(
        BenchConfig(profile="tiny", backend="kinematic", out=str(tmp_path), figures=False)
    )
    # 5 demonstration datasets, 8 + 8 (SB3) trainings, 15 + 8 evaluations, the study, 5
    # robustness stages, π_n's trajectories: none ran again
    assert len(again.cached) == 51
    assert json.loads((tmp_path / "results.json").read_text())["rows"] == first

    # Table 1 on MuJoCo (the deep-RL rows train the same SB3 code on it: tests/test_sb3.py;
    # the robustness and Panda tables: tests/test_bench_robustness.py; the delicate table:
    # tests/test_bench_delicate.py)
    mujoco = BenchConfig(
        profile="tiny",
        backend="mujoco",
        rows=",".join(ROW_IDS),
        out=str(tmp_path),
        study=False,
        robustness=False,
        robot=False,
        delicate=False,
        figures=False,  # drawn and checked in the kinematic run above
    )
    run_bench(mujoco)
    results = json.loads((tmp_path / "results.json").read_text())["rows"]
    assert list(results) == list(ROW_IDS)
    markdown = (tmp_path / "results.md").read_text()
    assert "## Backends side by side (mujoco vs kinematic)" in markdown
    assert "## Inference study" not in markdown
    assert not (tmp_path / "inference.json").exists()  # not the kinematic run's study


def _no_sections(out, rows: str | None = None, figures: bool = False) -> BenchConfig:
    """The tiny kinematic bench (of ``rows``, default all) without the study and the
    robustness table (and, unless asked for, without figures)."""
    return BenchConfig(
        profile="tiny",
        backend="kinematic",
        rows=rows,
        out=str(out),
        study=False,
        robustness=False,
        figures=figures,
    )


def test_a_dry_run_counts_the_stages_to_run_and_runs_nothing(tmp_path, capsys):
    options = ["bench", "--profile", "tiny", "--rows", "C1.3", "--backend", "kinematic"]
    options += ["--no-study", "--no-robustness", "--no-robot", "--out", str(tmp_path / "b")]
    config = _no_sections(tmp_path / "b", rows="C1.3")
    assert main([*options, "--dry-run"]) == 0
    before = capsys.readouterr().out
    assert not (tmp_path / "b").exists()  # nothing written
    # the 2*2's efficient demonstrations, BC, RS-GAIL and the row's evaluation
    assert before.startswith(f"4 stages in {tmp_path / 'b'}: 0 finished, 4 to run")
    assert "| training | 0 | 2 |" in before and "Nothing was run." in before
    run_bench(config, progress=False, log=lambda _: None)
    planned = plan_bench(config)
    assert len(planned) == 4 and all(stage.finished for stage in planned)
    [bc] = (tmp_path / "b" / "stages").glob("bc_efficient-seed0-*")
    (bc / "policy.pt").write_bytes(b"damaged")
    assert main([*options, "--dry-run"]) == 0
    assert "| training | 1 | 1 |" in capsys.readouterr().out  # it would run BC again
    assert (bc / MARKER).exists()  # and left it where it was


@pytest.mark.slow
def test_an_interrupted_bench_resumes_to_the_same_results(tiny_bench, tmp_path):
    whole = tiny_bench.run
    rows = "C2.2,C2.3,C3.2,C4.1"  # BC and π_n on the 2*2 before π_φ, which is interrupted

    def interrupt(line: str) -> None:
        if line.startswith("training pi_phi_circle"):
            raise KeyboardInterrupt

    config = _no_sections(tmp_path / "b", rows=rows)
    with pytest.raises(KeyboardInterrupt):
        run_bench(config, progress=False, log=interrupt)
    assert not (tmp_path / "b" / "results.json").exists()  # nothing reported half-way
    resumed = run_bench(config, progress=False, log=lambda _: None)
    # What finished before the interruption is cached (stages run side by side, so which
    # did depends on the schedule); the interrupted training is not.
    assert "bc_safe-seed0" in resumed.cached and "pi_phi_circle-seed0" not in resumed.cached
    assert resumed.results == {row: whole.results[row] for row in rows.split(",")}


@pytest.mark.slow
def test_a_moved_bench_folder_resumes_and_is_re_reported_from_its_cache(
    tiny_bench, tmp_path, monkeypatch
):
    """Interrupted after π_n's RS-GAIL checkpoint (before its stage finished), moved, resumed;
    moved again, every stage cached; the figures are those of an uninterrupted run. (The
    study, which needs no training, is the whole tiny bench's, already finished in the
    folder: its own run is the whole bench's.)"""
    from tolins.learning.imitation import runs

    whole = tiny_bench.run
    tiny_bench.copy_stages(tmp_path / "a", keep=lambda name: name == "inference-study")
    rows = ["C2.2", "C2.3"]

    def config(folder: str) -> BenchConfig:
        out = str(tmp_path / folder)
        return BenchConfig(
            profile="tiny",
            backend="kinematic",
            rows=",".join(rows),
            out=out,
            robustness=False,
            figures=False,
        )

    def quiet(config: BenchConfig):
        return run_bench(config, progress=False, log=lambda _: None)

    finish = runs._finish
    with monkeypatch.context() as patch:
        patch.setattr(runs, "_finish", lambda *_: (_ for _ in ()).throw(KeyboardInterrupt))
        with pytest.raises(KeyboardInterrupt):
            quiet(config("a"))
    assert runs._finish is finish
    (checkpoint,) = (tmp_path / "a" / "stages").glob("pi_n_safe-seed0-*/checkpoint.pt")
    assert not (checkpoint.parent / MARKER).exists()  # the stage was left half-way

    (tmp_path / "a").rename(tmp_path / "b")
    resumed = quiet(config("b"))
    # π_n resumed from its checkpoint
    assert {"demos-Circle2x2-safe-seed0-0", "bc_safe-seed0"} <= set(resumed.cached)
    assert "pi_n_safe-seed0" not in resumed.cached
    assert resumed.results == {row: whole.results[row] for row in rows}

    (tmp_path / "b").rename(tmp_path / "c")
    with monkeypatch.context() as patch:  # the reports read the stages, they run no episode
        patch.setattr(gymnasium, "make", lambda *_, **__: pytest.fail("an env was made"))
        again = quiet(config("c"))
    assert sorted(again.cached) == sorted(again.stage_wall_s)  # every stage, none re-run
    # the demonstrations, bc, π_n, two evaluations, the study, π_n's trajectories
    assert len(again.cached) == 7
    assert again.results == {row: whole.results[row] for row in rows}
    assert again.study == whole.study
    assert json.loads((tmp_path / "c" / "inference.json").read_text()) == whole.study


def test_timeline_kinds_of_every_stage_name():
    from tolins.bench.pipeline.timeline import KINDS, stage_kind

    kinds = {
        "demos-Circle2x2-safe-seed0-0": "demonstrations",
        "bc_safe-seed0": "training",
        "eval-C2.3-seed1": "evaluation",
        "robust-pi_phi_star-seed2": "evaluation",
        "inference-study": "study",
    }
    assert {name: stage_kind(name) for name in kinds} == kinds
    assert set(kinds.values()) == set(KINDS)


#: The bench's parts in import order: a file may import its own part and those before it
#: (``if TYPE_CHECKING:`` imports aside).
BENCH_PARTS = {
    "reference": 0,
    "machine": 0,
    "table": 1,
    "store": 2,
    "jobs": 3,
    "reports": 4,
    "pipeline": 5,
    "evaluate": 6,
}


def test_the_bench_parts_import_downwards_only():
    from import_graph import read_imports

    root = Path(__file__).resolve().parents[1] / "tolins"

    def part(module: str) -> str:
        return module.split(".")[2]

    inside = [
        found
        for found in read_imports(root)
        if found.importer.startswith("tolins.bench.")
        and found.target.startswith("tolins.bench.")
        and not found.typing_only
    ]
    assert {part(found.importer) for found in inside} <= set(BENCH_PARTS)
    upward = [
        str(found)
        for found in inside
        if BENCH_PARTS[part(found.target)] > BENCH_PARTS[part(found.importer)]
    ]
    assert not upward, "bench imports against its parts' order:\n" + "\n".join(upward)


def test_a_bench_of_deep_rl_rows_only_reports_their_workpieces(tiny_bench, tmp_path):
    tiny_bench.copy_stages(tmp_path)  # the training and evaluation of the row: its reports
    config = _no_sections(tmp_path, rows="R1.1", figures=True)
    bench = run_bench(config, progress=False, log=lambda _: None)
    assert list(bench.results) == ["R1.1"]
    assert (tmp_path / "tolerance_images.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "| R1.1 |" in (tmp_path / "results.md").read_text()


def test_a_run_without_figures_writes_the_same_results_and_no_png(tiny_bench, tmp_path):
    """``--no-figures``: the shared tiny bench's folder (its figures drawn) re-reported
    without them: the same results, every earlier figure gone, results.md links none."""
    out = tmp_path / "bench"
    shutil.copytree(tiny_bench.folder, out)
    assert (out / "table.png").is_file() and list((out / "claims").glob("*.png"))
    before = read_results(out)
    options = ["bench", "--profile", "tiny", "--backend", "kinematic", "--no-robot"]
    assert main([*options, "--no-figures", "--out", str(out)]) == 0
    assert read_results(out)["rows"] == before["rows"]
    assert not [p for p in out.rglob("*.png") if "stages" not in p.relative_to(out).parts]
    markdown = (out / "results.md").read_text()
    assert "![" not in markdown and "--no-figures" in markdown
    for row_id in ALL_ROW_IDS:
        check_rrd(out / "recordings" / f"{row_id}.rrd")
