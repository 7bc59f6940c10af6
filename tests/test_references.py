"""The shipped references against today's profiles.

- ``reference:quick``: no row of its table is zero by construction, and every trained row's
  budget lets its learning curve leave zero.
- ``reference:paper``: every row of today's table (Table 1 and the deep-RL rows on both
  rewards) at the paper profile's budgets with five training seeds, a learning curve per
  training and seed, and claims that its own figures give again.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path

from tolins.bench.pipeline.profiles import PROFILES, Profile
from tolins.bench.reference import reference_path
from tolins.bench.table.baselines import Curve, curves_from_json, first_success
from tolins.bench.table.claims import check_claims
from tolins.bench.table.results import read_results
from tolins.bench.table.rows import SB3_METHODS, Row, select_rows
from tolins.learning.agents.sb3 import PPO_ROLLOUT

QUICK, PAPER = PROFILES["quick"], PROFILES["paper"]


def _folder(name: str) -> Path:
    return reference_path(name).parent


def _run(name: str) -> dict:
    return json.loads((_folder(name) / "run.json").read_text())


def _env_step_curves(
    name: str, profile: Profile, rows: list[Row]
) -> Iterator[tuple[str, int, str, Curve]]:
    """``(training, seed, method, curve)`` of every RS-GAIL, PPO and SAC training of ``rows``
    in reference ``name`` (BC and π_φ have no env-step curve: π_φ starts from π_n's)."""
    curves = curves_from_json(json.loads((_folder(name) / "curves.json").read_text()))
    for row in rows:
        for training in row.trainings:
            if training.method in ("rs-gail", *SB3_METHODS):
                for seed in range(profile.seeds):
                    curve = curves[f"{training.name}-seed{seed}"]
                    yield training.name, seed, training.method, curve


def test_reference_quick_measured_todays_quick_budgets():
    run = _run("quick")
    assert run["profile"] == asdict(QUICK)
    assert run["config"]["rows"] is None and run["seeds"] == QUICK.seeds


def test_every_quick_row_trains_on_a_budget_where_its_curve_leaves_zero():
    rows = read_results(_folder("quick"))["rows"]
    table = select_rows(None, baselines=QUICK.baselines)
    assert list(rows) == [row.id for row in table]
    for row in table:
        assert rows[row.id]["success_mean"] > 0, row.id
    budgets = {"rs-gail": QUICK.rs_gail_env_steps}
    budgets |= dict.fromkeys(SB3_METHODS, QUICK.deep_rl_env_steps)
    for training, seed, method, curve in _env_step_curves("quick", QUICK, table):
        leaves = first_success(curve)
        assert leaves is not None and leaves <= budgets[method], (training, seed, leaves)


def test_reference_paper_measured_every_row_at_the_paper_budgets_with_five_seeds():
    """Five training seeds, and more where a claim needed them (benchmarks/extend_reference.py:
    the pentagon's rows, with six), each such row from a run of the same profile."""
    run = _run("paper")
    assert run["profile"] == asdict(PAPER)
    assert run["config"]["rows"] is None and run["config"]["backend"] == "mujoco"
    rows = read_results(_folder("paper"))["rows"]
    assert list(rows) == [row.id for row in select_rows(None)]
    extended = run["extended_rows"]
    assert sorted(extended) == ["P2.1", "P2.2"]
    for row_id, entry in rows.items():
        if row_id in extended:
            assert entry["seeds"] == extended[row_id]["seeds"] == 6
            assert extended[row_id]["config"]["profile"] == "paper"
        else:
            assert entry["seeds"] == PAPER.seeds == 5
    assert all(entry["eval_env"].endswith("-v2") for entry in rows.values())


def test_reference_paper_has_a_curve_per_training_and_seed_at_equal_env_steps():
    # RS-GAIL's episodes end early on success; PPO rounds its budget up to whole rollouts
    budgets = {"rs-gail": (1, PAPER.rs_gail_env_steps)}
    budgets |= dict.fromkeys(SB3_METHODS, (PAPER.deep_rl_env_steps, PAPER.deep_rl_env_steps))
    budgets["ppo"] = (PAPER.deep_rl_env_steps, PAPER.deep_rl_env_steps + PPO_ROLLOUT)
    assert PAPER.deep_rl_env_steps == PAPER.rs_gail_env_steps
    for training, seed, method, curve in _env_step_curves("paper", PAPER, select_rows(None)):
        low, high = budgets[method]
        assert low <= curve["env_steps"][-1] <= high, (training, seed)


def test_reference_paper_claims_are_what_its_figures_give():
    rows = read_results(_folder("paper"))["rows"]
    budgets = (PAPER.deep_rl_env_steps, PAPER.rs_gail_env_steps)
    checked = {check.claim.name: check.to_json() for check in check_claims(rows, budgets=budgets)}
    assert {name: claim["verdict"] for name, claim in _run("paper")["claims"].items()} == {
        name: claim["verdict"] for name, claim in checked.items()
    }
    assert "not evaluated" not in {claim["verdict"] for claim in checked.values()}
