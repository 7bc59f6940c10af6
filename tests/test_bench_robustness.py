"""The bench's robustness table (tolins.bench.table.robustness, its stages in
tolins.bench.jobs.robustness): tiny runs end to end, cached."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from tolins.bench.jobs import robustness
from tolins.bench.jobs.row_evaluation import evaluate_row
from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.pipeline.runner import run_bench
from tolins.bench.pipeline.settings import robustness_spec
from tolins.bench.reports.robustness import plot_robustness
from tolins.bench.table.robustness import CONDITIONS, KEY, POLICIES
from tolins.bench.table.rows import ROWS
from tolins.bench.table.seeds import eval_seeds
from tolins.cli import main

TINY = PROFILES["tiny"]


def _png_size(path):
    import matplotlib.image

    image = matplotlib.image.imread(path)
    return image.shape[0] * image.shape[1]


def test_conditions_are_the_grades_the_defect_kinds_and_random_physics():
    assert [c.id for c in CONDITIONS] == [
        *("fit200", "fit100", "fit50", "fit20"),
        *("bent", "pitch", "burr", "short", "blocked"),
        "physics",
    ]
    assert [c.clearance_um for c in CONDITIONS[:4]] == [200, 100, 50, 20]
    assert CONDITIONS[0].env_id == "tolins/Circle2x2-v2"
    assert CONDITIONS[2].env_id == "tolins/Circle2x2Fit50-v2"
    assert CONDITIONS[8].env_kwargs == {"defects": ("blocked", None)}
    assert not CONDITIONS[8].vectorizable("mujoco") and CONDITIONS[8].vectorizable("kinematic")
    assert [p.label for p in POLICIES] == ["π_e^safe", "π_e^eff", "π_n", "π_φ", "π_φ*"]
    assert POLICIES[-1].inference and POLICIES[-1].agent == POLICIES[-2].agent


def test_the_stage_key_sees_the_trained_policy_and_the_episodes():
    def config(stage, profile=TINY):
        spec = robustness_spec(POLICIES[2], 0, stage, profile, "mujoco")
        return robustness.robustness_stage(spec).config

    assert config("pi_n_safe-seed0-aaa") != config("pi_n_safe-seed0-bbb")
    assert config("x")["seeds"] == eval_seeds(0, TINY.robustness_episodes)
    assert config("x", PROFILES["quick"])["seeds"] != config("x")["seeds"]
    assert 1 <= TINY.robustness_episodes <= 2 < PROFILES["quick"].robustness_episodes


def test_tiny_robustness_runs_end_to_end_and_is_cached_on_a_second_run(tiny_bench, tmp_path):
    """The robustness stages run here; the trainings and row evaluations they read are the
    shared tiny bench's (tests/conftest.py, the same stages as a run of these rows makes)."""
    names = [robustness.stage_name(p, 0) for p in POLICIES]
    tiny_bench.copy_stages(tmp_path, keep=lambda name: name not in names)
    config = BenchConfig(
        profile="tiny", backend="kinematic", rows="C2.1,C2.3,C4.2", out=str(tmp_path), study=False
    )
    run = run_bench(config, progress=False, log=lambda _: None)
    assert all(name in run.stage_folders for name in names)
    assert not any(name in run.cached for name in names)
    table = run.robustness
    assert [p["id"] for p in table["policies"]] == [p.id for p in POLICIES]
    for policy in POLICIES:
        cells = table["cells"][policy.id]
        assert list(cells) == [c.id for c in CONDITIONS]
        assert cells["blocked"]["success_mean"] == 0.0  # a plugged hole never inserts
        assert cells["blocked"]["success_ci"] == [0.0, 0.0]
        assert all(cell["episodes"] == TINY.robustness_episodes for cell in cells.values())
        assert cells["fit20"]["clearance_um"] == 20
    # The 200 µm cell is the table row's first episodes (same seeds, same env).
    assert table["cells"]["safe"]["fit200"]["reward_per_episode"] == [
        run.results["C2.1"]["reward_per_episode"][0][: TINY.robustness_episodes]
    ]
    document = json.loads((tmp_path / "results.json").read_text())
    assert document[KEY]["cells"]["pi_phi_star"]["burr"]["ci_over"] == "episodes"
    text = (tmp_path / "results.md").read_text()
    assert "## Robustness (beyond the paper)" in text and "| π_φ* |" in text
    assert _png_size(tmp_path / "robustness.png") > 0

    again = run_bench(replace(config, figures=False), progress=False, log=lambda _: None)
    assert all(name in again.cached for name in names)
    assert again.robustness == table

    # Without the table: no key, no plot, and tolins compare reads both documents.
    without = replace(config, robustness=False, out=str(tmp_path / "b"))
    tiny_bench.copy_stages(tmp_path / "b", keep=lambda name: name not in names)
    run_bench(without, progress=False, log=lambda _: None)
    assert KEY not in json.loads((tmp_path / "b" / "results.json").read_text())
    assert not (tmp_path / "b" / "robustness.png").exists()
    assert main(["compare", str(tmp_path), str(tmp_path / "b")]) == 0


def test_only_the_experts_when_the_rows_train_no_circle_policy_and_cis_over_seeds(tmp_path):
    config = BenchConfig(
        profile="tiny",
        backend="kinematic",
        rows="C1.1",
        seeds=2,
        out=str(tmp_path),
        study=False,
        figures=False,
    )
    run = run_bench(config, progress=False, log=lambda _: None)
    assert [p["id"] for p in run.robustness["policies"]] == ["safe", "efficient"]
    cell = run.robustness["cells"]["safe"]["fit50"]
    assert (cell["ci_over"], cell["ci_n"], cell["seeds"]) == ("seeds", 2, 2)
    assert len(cell["success_per_seed"]) == 2
    assert "95 % CI over the 2 training seeds" in (tmp_path / "results.md").read_text()


def test_an_expert_on_mujoco_fails_blocked_holes_and_repeats_its_row(tmp_path):
    safe = POLICIES[0]
    stage = robustness.robustness_stage(robustness_spec(safe, 0, None, TINY, "mujoco"))
    folder = robustness.robustness_job(tmp_path, stage, None)
    episodes = robustness.read_stage(folder, TINY.robustness_episodes)
    assert [e.success for e in episodes["blocked"]] == [False] * TINY.robustness_episodes
    row = next(r for r in ROWS if r.id == "C2.1")
    expected = evaluate_row(row, None, "mujoco", eval_seeds(0, TINY.robustness_episodes))
    assert [e.reward for e in episodes["fit200"]] == pytest.approx([e.reward for e in expected])
    again = robustness.robustness_job(tmp_path, stage, None)
    assert again == folder
    count = TINY.robustness_episodes
    results = robustness.robustness_results({robustness.stage_name(safe, 0): folder}, count, 1)
    assert list(results["cells"]) == ["safe"]
    path = plot_robustness(tmp_path / "robustness.png", results)
    assert _png_size(path) > 0


def test_the_pandas_table_runs_the_experts_on_the_arm_with_and_without_a_grasp_error(tmp_path):
    from tolins.bench.reports.robustness import format_robot_section
    from tolins.bench.table.robot import GRASP_ERROR, ROBOT, ROBOT_ENV

    safe = ROBOT.policies[0]
    spec = robustness_spec(safe, 0, None, TINY, "mujoco", ROBOT)
    stage = robustness.robustness_stage(spec)
    assert stage.name == "robot-safe-seed0"
    assert stage.config["conditions"][1]["grasp_error"] == GRASP_ERROR
    # The robustness table's stages keep their names and keys.
    plain = robustness.robustness_stage(robustness_spec(safe, 0, None, TINY, "mujoco"))
    assert plain.name == "robust-safe-seed0" and "grasp_error" not in str(plain.config)
    folder = robustness.robustness_job(tmp_path, stage, None)
    count = TINY.robustness_episodes
    episodes = robustness.read_stage(folder, count, ROBOT.conditions)
    assert set(episodes) == {"panda", "grasp"}
    import gymnasium as gym

    from tolins.policies import SafeExpert
    from tolins.rollouts.episodes import run_episode

    env = gym.make(ROBOT_ENV).unwrapped
    seed = eval_seeds(0, count)[0]
    again = run_episode(env, SafeExpert(), seed=seed)
    assert episodes["panda"][0].reward == pytest.approx(again.reward)
    results = robustness.robustness_results({stage.name: folder}, count, 1, ROBOT)
    assert list(results["cells"]["safe"]) == ["panda", "grasp"]
    lines = "\n".join(format_robot_section(results))
    assert "## A robot holding the part (beyond the paper)" in lines
    assert "| π_e^safe |" in lines and ROBOT_ENV in lines
    # The grasp-error column joins the robustness table, the same episodes.
    from tolins.bench.table.robot import with_grasp_column

    plain_folder = robustness.robustness_job(tmp_path, plain, None)
    table = robustness.robustness_results({plain.name: plain_folder}, count, 1)
    merged = with_grasp_column(table, results)
    assert [c["id"] for c in merged["conditions"]][-1] == "grasp"
    assert merged["cells"]["safe"]["grasp"] == results["cells"]["safe"]["grasp"]
    assert table["conditions"] == merged["conditions"][:-1]  # the input is left as it was
    assert _png_size(plot_robustness(tmp_path / "merged.png", merged)) > 0
    assert with_grasp_column(table, None) is table
