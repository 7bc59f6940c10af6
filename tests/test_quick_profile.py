"""The quick profile against its shipped reference: no row of its table is zero by
construction, and every trained row's budget lets its learning curve leave zero."""

from __future__ import annotations

import json
from dataclasses import asdict

from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.reference import reference_path
from tolins.bench.table.baselines import curves_from_json, first_success
from tolins.bench.table.results import read_results
from tolins.bench.table.rows import SB3_METHODS, select_rows

QUICK = PROFILES["quick"]
FOLDER = reference_path("quick").parent


def test_reference_quick_measured_todays_quick_budgets():
    run = json.loads((FOLDER / "run.json").read_text())
    assert run["profile"] == asdict(QUICK)
    assert run["config"]["rows"] is None and run["seeds"] == QUICK.seeds


def test_every_quick_row_trains_on_a_budget_where_its_curve_leaves_zero():
    rows = read_results(FOLDER)["rows"]
    curves = curves_from_json(json.loads((FOLDER / "curves.json").read_text()))
    table = select_rows(None, baselines=QUICK.baselines)
    assert list(rows) == [row.id for row in table]
    budgets = {"rs-gail": QUICK.rs_gail_env_steps}
    budgets |= dict.fromkeys(SB3_METHODS, QUICK.deep_rl_env_steps)
    for row in table:
        assert rows[row.id]["success_mean"] > 0, row.id
        for training in row.trainings:
            if training.method not in budgets:
                continue  # BC and π_φ: no env-step curve (π_φ starts from π_n's)
            for seed in range(QUICK.seeds):
                leaves = first_success(curves[f"{training.name}-seed{seed}"])
                assert leaves is not None and leaves <= budgets[training.method], (
                    training.name,
                    seed,
                    leaves,
                )
