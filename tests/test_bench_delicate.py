"""The bench's delicate-pins table: its stages, cells, claim and section, on MuJoCo."""

from __future__ import annotations

import json

import pytest

from tolins.bench.jobs.robustness import EPISODES
from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.runner import plan_bench, run_bench
from tolins.bench.table.claims import HELD, INCONCLUSIVE, NO_DIFFERENCE, NOT_HELD
from tolins.bench.table.delicate import DELICATE, damage_claim, gentlest
from tolins.rollouts.episodes import Episode, episode_from_dict, episode_to_dict


def _config(out, **kwargs) -> BenchConfig:
    """The experts' row only, no other section: the delicate table's experts."""
    options = {"profile": "tiny", "rows": "C2.1", "study": False, "robustness": False}
    return BenchConfig(**{**options, "robot": False, "figures": False, "out": str(out), **kwargs})


@pytest.mark.slow
def test_the_bench_evaluates_its_policies_on_delicate_pins(tmp_path) -> None:
    run = run_bench(_config(tmp_path), progress=False, log=lambda _: None)
    table = run.delicate
    columns = ["delicate", "delicate_fit50", "delicate_2x4", "delicate_c4"]
    assert [c["id"] for c in table["conditions"]] == columns
    assert [p["id"] for p in table["policies"]] == ["safe", "efficient"]  # nothing trained
    for policy in ("safe", "efficient"):
        for condition in columns:
            cell = table["cells"][policy][condition]
            assert 0.0 <= cell["damage_mean"] <= 1.0
            assert cell["success_undamaged_mean"] <= cell["success_mean"]
            assert len(cell["damage_ci"]) == 2 and cell["damage_per_episode"]
    assert table["claim"]["verdict"] in (HELD, NOT_HELD, NO_DIFFERENCE, INCONCLUSIVE)
    assert list(table["claim_by_condition"]) == columns
    assert table["claim_by_condition"]["delicate"] == table["claim"]
    assert table["gentlest"] is None  # no learned policy ran
    written = json.loads((tmp_path / "results.json").read_text())
    assert written["delicate"]["claim"] == table["claim"]
    markdown = (tmp_path / "results.md").read_text()
    assert "## Delicate pins (beyond the paper)" in markdown
    assert "`tolins/Circle2x1Defective-v2` with `pins='elastic-plastic'`" in markdown
    assert "The same claim on each workpiece: 2*2: " in markdown
    stages = sorted(p.name.rsplit("-", 1)[0] for p in (tmp_path / "stages").glob("delicate-*"))
    assert stages == ["delicate-efficient-seed0", "delicate-safe-seed0"]
    stage = next((tmp_path / "stages").glob("delicate-safe-*"))
    episodes = json.loads((stage / EPISODES).read_text())
    assert all("damaged" in row for column in columns for row in episodes[column])
    # Without the section, and on the kinematic simulator (whose pins cannot bend): none.
    off = run_bench(_config(tmp_path / "off", delicate=False), progress=False, log=lambda _: 0)
    kinematic = _config(tmp_path / "kinematic", backend="kinematic")
    assert off.delicate is None and run_bench(kinematic, progress=False).delicate is None


def _table(safe: list[list[float]], efficient: list[list[float]]) -> dict:
    """A delicate table of the two experts with these damage outcomes per seed."""

    def cell(damage: list[list[float]]) -> dict:
        return {
            "damage_per_seed": [sum(s) / len(s) for s in damage],
            "damage_per_episode": damage,
            "damage_mean": 0.0,
            "success_undamaged_mean": 0.0,
        }

    policies = [{"id": "safe", "agent": "safe"}, {"id": "efficient", "agent": "efficient"}]
    cells = {"safe": {"delicate": cell(safe)}, "efficient": {"delicate": cell(efficient)}}
    return {"policies": policies, "cells": cells}


@pytest.mark.parametrize(
    ("safe", "efficient", "verdict"),
    [
        ([[0.0] * 10], [[1.0] * 10], HELD),
        ([[1.0] * 10], [[0.0] * 10], NOT_HELD),
        ([[0.0] * 20], [[0.0] * 20], NO_DIFFERENCE),
        ([[0.0, 1.0] * 5], [[1.0, 0.0] * 5], INCONCLUSIVE),
        ([[0.0]], [[0.0]], INCONCLUSIVE),  # one episode decides nothing
        ([[0.0] * 4, [0.1] * 4, [0.0] * 4], [[0.5] * 4, [0.6] * 4, [0.7] * 4], HELD),
    ],
)
def test_the_damage_claim_is_four_valued(safe, efficient, verdict) -> None:
    claim = damage_claim(_table(safe, efficient))
    assert claim["verdict"] == verdict
    assert claim["difference"]["over"] == ("seeds" if len(safe) > 1 else "episodes")


def test_the_gentlest_learned_policy_damages_least_then_succeeds_most() -> None:
    table = {
        "policies": [
            {"id": "safe", "label": "safe", "agent": "safe"},
            {"id": "pi_n", "label": "π_n", "agent": "pi_n_safe"},
            {"id": "pi_phi", "label": "π_φ", "agent": "pi_phi_circle"},
        ],
        "cells": {
            "safe": {"delicate": {"damage_mean": 0.0, "success_undamaged_mean": 1.0}},
            "pi_n": {
                "delicate": {"damage_mean": 0.0, "success_undamaged_mean": 1.0},
                "delicate_fit50": {"damage_mean": 0.2, "success_undamaged_mean": 0.8},
            },
            "pi_phi": {
                "delicate": {"damage_mean": 0.1, "success_undamaged_mean": 0.9},
                "delicate_fit50": {"damage_mean": 0.1, "success_undamaged_mean": 0.85},
            },
        },
    }
    assert gentlest(table)["policy"] == "pi_n"  # same mean damage, more undamaged successes
    table["cells"]["pi_phi"]["delicate_fit50"]["damage_mean"] = 0.05
    assert gentlest(table)["policy"] == "pi_phi"  # the least damage over both columns
    assert DELICATE.prefix == "delicate-"


def test_an_episode_keeps_damage_only_where_pins_bend() -> None:
    rigid = Episode(1.0, True, 3, 0)
    assert "damaged" not in episode_to_dict(rigid)  # the rigid pins' JSON as it was
    bent = Episode(1.0, True, 3, 0, damaged=True)
    assert episode_to_dict(bent)["damaged"] is True
    assert episode_from_dict(episode_to_dict(bent)) == bent


def test_the_table_evaluates_row_c1s_imitators_beside_row_c2s(tmp_path) -> None:
    config = _config(tmp_path, rows="C1.2,C1.3,C2.2")
    planned = {stage.name: stage for stage in plan_bench(config)}
    delicate = [name for name in planned if name.startswith(DELICATE.prefix)]
    assert delicate == [
        "delicate-safe-seed0",
        "delicate-efficient-seed0",
        "delicate-bc_efficient-seed0",  # C1: the efficient expert's imitators
        "delicate-pi_n_efficient-seed0",
        "delicate-pi_bc-seed0",  # C2: the safe one's (its π_n is not trained by these rows)
    ]
    assert "bc_efficient-seed0" in planned["delicate-bc_efficient-seed0"].needs
    labels = {policy.id: policy.label for policy in DELICATE.policies}
    assert labels["bc_efficient"] == "π_bc (C1)" and labels["pi_bc"] == "π_bc (C2)"
