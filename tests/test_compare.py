"""Verdicts and `tolins compare` on real tiny bench runs (kinematic backend), and the
command's errors."""

from __future__ import annotations

import gzip
import json
import shutil
from pathlib import Path

import pytest

from tolins.bench.reference import reference_names, reference_path
from tolins.bench.table.claims import (
    HELD,
    INCONCLUSIVE,
    NO_DIFFERENCE,
    NOT_EVALUATED,
    NOT_HELD,
    ONE_SEED,
    check_claims,
)
from tolins.bench.table.compare import A_HIGHER, B_HIGHER, CONSISTENT, compare, format_comparison
from tolins.bench.table.results import SCHEMA, read_results
from tolins.bench.table.statistics import EPISODES, ONE_SEED_MARGIN, SEEDS, equivalent, sign
from tolins.cli import main

DATA = Path(__file__).parent / "data"

ROWS = "C2.1,C2.2,C2.3,C3.1,C3.2"


@pytest.fixture(scope="module")
def runs(tiny_bench, tmp_path_factory):
    """One tiny run with one training seed (its stages the shared tiny bench's,
    tests/conftest.py), then the same folder with three (seed 0's stages come from the
    cache): each run's results folder."""
    root = tmp_path_factory.mktemp("runs")
    tiny_bench.copy_stages(root / "bench")
    bench = ["bench", "--profile", "tiny", "--backend", "kinematic", "--rows", ROWS]
    bench += ["--no-study", "--out", str(root / "bench")]
    assert main([*bench, "--seeds", "1", "--no-figures"]) == 0  # figures: the second run's
    shutil.copytree(root / "bench", root / "one", ignore=shutil.ignore_patterns("stages"))
    assert main([*bench, "--seeds", "3"]) == 0
    return root / "one", root / "bench"


@pytest.mark.slow
def test_claims_of_a_real_run_follow_the_intervals_in_its_results_json(runs):
    one, three = runs
    rows = read_results(three)["rows"]
    assert list(rows) == ROWS.split(",")
    for entry in rows.values():
        assert (entry["seeds"], entry["ci_over"], entry["ci_n"]) == (3, SEEDS, 3)
        assert len(entry["reward_per_seed"]) == 3 and len(entry["reward_per_episode"]) == 3
        low, high = entry["reward_ci"]
        assert low <= entry["reward_mean"] <= high
        low, high = entry["reward_iqm_ci"]
        assert low <= entry["reward_iqm"] <= high
    # seed 0 of the three-seed run is the one-seed run's (cached stages)
    first = read_results(one)["rows"]
    assert all(rows[r]["reward_per_seed"][0] == first[r]["reward_per_seed"][0] for r in rows)

    checks = {c.claim.name: c for c in check_claims(rows)}
    recorded = json.loads((three / "run.json").read_text())["claims"]
    assert {name: c["verdict"] for name, c in recorded.items()} == {
        name: c.verdict for name, c in checks.items()
    }
    assert read_results(three)["claims"] == recorded  # results.json carries them too
    guided = checks["tolerance_guided"]
    assert [checks[n].verdict for n in ("rs_gail", "inference", "polygon_transfer")] == [
        NOT_EVALUATED
    ] * 3
    (pair,) = guided.comparisons
    assert (pair.difference.over, pair.difference.n, pair.margin) == (SEEDS, 3, 0.0)
    expected = {1: HELD, -1: NOT_HELD, 0: INCONCLUSIVE}[sign(pair.difference)]
    if expected == INCONCLUSIVE and equivalent(pair.difference, pair.delta):
        expected = NO_DIFFERENCE
    assert pair.verdict == guided.verdict == expected
    assert guided.basis == "3 training seeds; 95 % CIs over seeds"
    markdown = (three / "results.md").read_text()
    assert "| reward | 95 % CI | IQM | paper |" in markdown
    assert f"π_φ beats π_n on the unseen 2*4: {guided.verdict}** (3 training seeds" in markdown
    assert "![tolerance_guided](claims/tolerance_guided.png)" in markdown
    assert (three / "claims" / "tolerance_guided.png").read_bytes()[:4] == b"\x89PNG"
    assert not (three / "claims" / "rs_gail.png").exists()

    guided_one = {c.claim.name: c for c in check_claims(first)}["tolerance_guided"]
    (single,) = guided_one.comparisons
    assert single.difference.over == EPISODES and single.margin == ONE_SEED_MARGIN
    assert guided_one.basis.startswith(ONE_SEED)
    assert ONE_SEED in (one / "results.md").read_text()


@pytest.mark.slow
def test_a_run_compared_with_itself_is_consistent_over_seeds(runs):
    _, three = runs
    result = compare(str(three), str(three / "results.json"))
    assert [r.row for r in result.rows] == ROWS.split(",")
    for row in result.rows:
        assert row.difference.estimate == 0.0
        assert (row.difference.over, row.difference.n, row.margin) == (SEEDS, 3, 0.0)
        assert row.status == CONSISTENT
    assert result.only_a == result.only_b == ()
    assert "5 of 5 shared rows consistent." in format_comparison(result)


@pytest.mark.slow
def test_three_seeds_against_one_compares_episodes_and_says_so(runs, tmp_path):
    one, three = runs
    result = compare(str(three), str(one))
    by_row = {r.row: r for r in result.rows}
    assert all(r.difference.over == EPISODES for r in result.rows)
    assert by_row["C2.1"].margin == 0.0  # an expert: no training variance to allow for
    assert by_row["C2.3"].margin == ONE_SEED_MARGIN
    for row in result.rows:
        assert row.status in (CONSISTENT, A_HIGHER, B_HIGHER)
        low, high = row.difference.low, row.difference.high
        assert (row.status == CONSISTENT) == (low <= row.margin and high >= -row.margin)
    text = format_comparison(result)
    assert "3 training seed(s)" in text and "1 training seed(s)" in text
    assert "Over episodes" in text and f"margin ±{ONE_SEED_MARGIN}" in text

    partial = tmp_path / "partial.json"  # rows only one side has are listed
    document = read_results(one)
    del document["rows"]["C3.2"]
    partial.write_text(json.dumps(document))
    assert compare(str(partial), str(three)).only_b == ("C3.2",)


@pytest.mark.slow
def test_cli_compare_prints_the_table_and_writes_json(runs, tmp_path, capsys):
    one, three = runs
    out = tmp_path / "comparison.json"
    assert main(["compare", str(three), str(one / "results.json"), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "| ID | policy | eval env | reward A | reward B | A − B [95 % CI] |" in text
    assert "| C3.2 | π_φ | Circle2x4 |" in text
    written = json.loads(out.read_text())
    assert list(written["rows"]) == ROWS.split(",")
    assert written["rows"]["C2.1"]["difference"]["over"] == EPISODES


def _error(argv: list[str], capsys) -> str:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    return captured.err


def test_cli_compare_refuses_missing_and_invalid_results(tmp_path, capsys):
    good = tmp_path / "good.json"
    good.write_text(json.dumps({"schema": "tolins.results/1", "rows": {}}))
    assert "no such file" in _error(["compare", str(tmp_path / "nope"), str(good)], capsys)
    assert "results.json: no such file" in _error(["compare", str(tmp_path), str(good)], capsys)
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    assert "not JSON" in _error(["compare", str(broken), str(broken)], capsys)
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"schema": "something/9", "rows": {}}))
    assert "schema 'something/9'" in _error(["compare", str(other), str(other)], capsys)
    assert "no rows" in _error(["compare", str(good), str(good)], capsys)
    old = tmp_path / "old.json"  # tolins ≤ 0.2: rows at the top, no per-seed figures
    old.write_text(json.dumps({"C2.1": {"reward_mean": 12.6, "seeds": 1, "episodes": 100}}))
    assert "row C2.1: no reward_per_seed" in _error(["compare", str(old), str(old)], capsys)


def test_a_missing_reference_is_a_one_line_error(capsys):
    for name in reference_names():  # what is shipped is a real results.json
        assert read_results(reference_path(name))["rows"]
    shipped = ", ".join(f"reference:{n}" for n in reference_names()) or "none yet"
    with pytest.raises(ValueError, match=f"shipped: {shipped}"):
        reference_path("no-such-run")
    err = _error(["compare", "reference:no-such-run", "reference:paper"], capsys)
    assert "reference:no-such-run: no such reference results" in err and "README.md" in err
    assert "no such reference" in _error(["compare", "reference:../..", "x"], capsys)


def test_compare_reads_the_schema_of_tolins_0_3_against_todays(tmp_path, capsys):
    """The paper reference tolins 0.3.0 shipped (schema 1, `-v1`, Table 1 only) against
    today's (schema 3, `-v2`, with the deep-RL rows): the expert rows measure the same."""
    old = tmp_path / "paper-0.3.0.json"
    with gzip.open(DATA / "paper_results_tolins_0.3.0.json.gz", "rb") as packed:
        old.write_bytes(packed.read())
    document = read_results(old)
    assert document["schema"] == "tolins.results/1" and document["tolins_version"] == "0.3.0"
    assert read_results(reference_path("paper"))["schema"] == SCHEMA != document["schema"]
    result = compare("reference:paper", str(old))
    assert [row.row for row in result.rows] == list(document["rows"])
    assert all(row.status == CONSISTENT for row in result.rows)
    for expert in ("C1.1", "C2.1", "P1.1"):
        row = next(r for r in result.rows if r.row == expert)
        assert row.a["reward_per_episode"] == row.b["reward_per_episode"], expert
    assert {r[:3] for r in result.only_a} == {"R1.", "R2."}
    assert main(["compare", "reference:paper", str(old)]) == 0
    assert "15 of 15 shared rows consistent" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("content", "says"),
    [
        (b"[" * 5000, "nested deeper than"),
        (b"\x80\x81 not text", "not UTF-8 text"),
        (b"{not json", "not JSON"),
    ],
)
def test_an_unreadable_results_file_is_one_line_naming_it(tmp_path, capsys, content, says):
    bad = tmp_path / "bad.json"
    bad.write_bytes(content)
    err = _error(["compare", str(bad), "reference:quick"], capsys)
    assert f"{bad}: {says}" in err and "allowed: " in err, err


def test_a_long_results_argument_is_echoed_shortened(capsys):
    err = _error(["compare", "a" * 20_000, "reference:quick"], capsys)
    assert "no such file" in err and "…" in err and len(err) < 400, err
