"""The shipped paper reference: every row of today's table (Table 1 and the deep-RL rows on
both rewards) at the paper profile's budgets with five training seeds, a learning curve per
training and seed, and claims that its own figures give again."""

from __future__ import annotations

import json
from dataclasses import asdict

from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.reference import reference_path
from tolins.bench.table.baselines import curves_from_json
from tolins.bench.table.claims import check_claims
from tolins.bench.table.results import read_results
from tolins.bench.table.rows import SB3_METHODS, select_rows
from tolins.learning.agents.sb3 import PPO_ROLLOUT

PAPER = PROFILES["paper"]
FOLDER = reference_path("paper").parent


def test_reference_paper_measured_every_row_at_the_paper_budgets_with_five_seeds():
    run = json.loads((FOLDER / "run.json").read_text())
    assert run["profile"] == asdict(PAPER)
    assert run["config"]["rows"] is None and run["config"]["backend"] == "mujoco"
    rows = read_results(FOLDER)["rows"]
    assert list(rows) == [row.id for row in select_rows(None)]
    assert {entry["seeds"] for entry in rows.values()} == {PAPER.seeds} == {5}
    assert all(entry["eval_env"].endswith("-v2") for entry in rows.values())


def test_reference_paper_has_a_curve_per_training_and_seed_at_equal_env_steps():
    rows = {row.id: row for row in select_rows(None)}
    curves = curves_from_json(json.loads((FOLDER / "curves.json").read_text()))
    # RS-GAIL's episodes end early on success; PPO rounds its budget up to whole rollouts
    budgets = {"rs-gail": (1, PAPER.rs_gail_env_steps)}
    budgets |= dict.fromkeys(SB3_METHODS, (PAPER.deep_rl_env_steps, PAPER.deep_rl_env_steps))
    budgets["ppo"] = (PAPER.deep_rl_env_steps, PAPER.deep_rl_env_steps + PPO_ROLLOUT)
    assert PAPER.deep_rl_env_steps == PAPER.rs_gail_env_steps
    for row in rows.values():
        for training in row.trainings:
            if training.method not in budgets:
                continue  # BC and π_φ: no env-step curve
            for seed in range(PAPER.seeds):
                curve = curves[f"{training.name}-seed{seed}"]
                low, high = budgets[training.method]
                assert low <= curve["env_steps"][-1] <= high, (training.name, seed)


def test_reference_paper_claims_are_what_its_figures_give():
    rows = read_results(FOLDER)["rows"]
    run = json.loads((FOLDER / "run.json").read_text())
    budgets = (PAPER.deep_rl_env_steps, PAPER.rs_gail_env_steps)
    checked = {check.claim.name: check.to_json() for check in check_claims(rows, budgets=budgets)}
    assert {name: claim["verdict"] for name, claim in run["claims"].items()} == {
        name: claim["verdict"] for name, claim in checked.items()
    }
    assert "not evaluated" not in {claim["verdict"] for claim in checked.values()}
