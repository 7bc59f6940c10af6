"""The bench's progress bar: one bar over every stage, the stage running, and the time
left, learnt from the stages that have finished (:mod:`tolins.bench.pipeline.progress`).

The estimator is checked on synthetic runs laid out by the executors' own
:class:`~tolins.bench.pipeline.executor.Schedule` over the quick bench's real plan, on a
machine uniformly 2× slower than the cost table and on one whose kinds of stage are off by
different factors."""

from __future__ import annotations

import heapq
import json
import math
import socket
from collections.abc import Callable, Mapping

import pytest

from tolins.bench.machine import cpu
from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.executor import Job, Schedule
from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.pipeline.progress import (
    MIN_SEEN_S,
    OVERRUN_SHARE,
    BenchProgress,
    estimate_remaining,
    expected_cost,
    speed_class,
    speed_factors,
)
from tolins.bench.pipeline.runner import PROGRESS_LOG, plan_bench, run_bench
from tolins.bench.reference import reference_path
from tolins.bench.store.cache import MARKER, StageCache


class _Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


STAGES = {
    "demos-Circle2x2-safe-seed0-0": 10.0,
    "bc_safe-seed0": 10.0,
    "eval-C1.1-seed0": 5.0,
    "eval-C1.1-seed1": 5.0,
    "robust-safe-seed0": 5.0,
    "inference-study": 20.0,
}


# --- the estimator on synthetic inputs ------------------------------------------------------


def test_no_estimate_until_enough_has_finished_then_a_uniformly_slower_machine_exactly():
    expected = {"a": 5.0, "b": 5.0, "c": 10.0, "d": 10.0}
    todo = {name: () for name in "bcd"}
    assert estimate_remaining(todo, expected, {"a": 10.0}, {}, 1) is None  # 5 s seen
    assert 5.0 < MIN_SEEN_S <= 10.0
    seen = {"a": 10.0, "b": 10.0}
    assert estimate_remaining({"c": (), "d": ()}, expected, seen, {}, 1) == pytest.approx(40.0)
    assert estimate_remaining({"c": (), "d": ()}, expected, seen, {}, 2) == pytest.approx(20.0)
    assert estimate_remaining({}, expected, {}, {}, 1) == 0.0  # nothing left: nothing to tell


def test_the_longest_chain_bounds_the_time_left_however_many_workers():
    expected = {"seen": 20.0, "t1": 100.0, "t2": 100.0, "t3": 100.0}
    expected |= {f"eval-C1.1-seed{i}": 10.0 for i in range(4)}
    todo: dict[str, tuple[str, ...]] = {"t1": (), "t2": ("t1",), "t3": ("t2",)}
    todo |= {f"eval-C1.1-seed{i}": () for i in range(4)}
    seen = {"seen": 20.0}  # the table's speed
    # 340 s of work: 170 s on 2 workers, but t1 -> t2 -> t3 takes 300 s on one
    assert estimate_remaining(todo, expected, seen, {}, 2) == pytest.approx(300.0)
    assert estimate_remaining(todo, expected, seen, {}, 1) == pytest.approx(340.0)
    assert estimate_remaining(todo, expected, seen, {}, 8) == pytest.approx(300.0)


def test_a_running_stage_is_credited_with_the_time_it_has_run_and_an_overrun_kept_going():
    expected = {"seen": 20.0, "long": 100.0}
    seen = {"seen": 40.0}  # 2x slower: "long" will take 200 s
    todo = {"long": ()}
    assert estimate_remaining(todo, expected, seen, {"long": 50.0}, 1) == pytest.approx(150.0)
    overran = estimate_remaining(todo, expected, seen, {"long": 300.0}, 1)
    assert overran == pytest.approx(OVERRUN_SHARE * 300.0)


def test_a_training_learns_from_its_other_seeds_and_an_evaluation_from_evaluations():
    quick = PROFILES["quick"]
    names = [f"pi_n_efficient-seed{s}" for s in range(3)]
    names += [f"pi_n_safe-seed{s}" for s in range(3)]
    names += [f"eval-C{row}-seed{s}" for row in ("1.1", "2.1", "2.2") for s in range(3)]
    expected = {name: expected_cost(name, quick, "mujoco") for name in names}
    walls = {"pi_n_efficient-seed0": 3 * expected["pi_n_efficient-seed0"]}
    walls |= {"pi_n_safe-seed0": expected["pi_n_safe-seed0"]}
    walls |= {f"eval-C1.1-seed{s}": 0.5 * expected[f"eval-C1.1-seed{s}"] for s in range(3)}
    factor = speed_factors(expected, walls)
    assert factor is not None
    # each nearer its own seed's speed than the other's
    assert 3.0 > factor("pi_n_efficient-seed1") > 2.0 > factor("pi_n_safe-seed1") > 1.0
    # an evaluation of another row: nearer the evaluations' 0.5 than a typical class's 2
    assert pytest.approx(factor("eval-C1.1-seed0"), rel=0.2) == 0.5
    assert factor("eval-C1.1-seed0") < factor("eval-C2.2-seed1") < 1.25
    assert speed_class("pi_n_safe-seed1") == "training rs-gail"
    assert speed_class("eval-C4.2-seed0") == "evaluation with inference"
    assert speed_class("eval-C4.1-seed0") == "evaluation"


def test_the_speed_follows_the_machine_as_its_load_changes():
    expected = {f"eval-C1.1-seed{s}": 10.0 for s in range(3)} | {"eval-C1.2-seed0": 10.0}
    walls = {"eval-C1.1-seed0": 40.0, "eval-C1.1-seed1": 40.0, "eval-C1.1-seed2": 10.0}

    def factor(old: float) -> float:
        """Seeds 0 and 1 ended ``old`` s ago under load, seed 2 just now without."""
        ages = {"eval-C1.1-seed0": old, "eval-C1.1-seed1": old, "eval-C1.1-seed2": 0.0}
        factors = speed_factors(expected, walls, ages)
        assert factors is not None
        return factors("eval-C1.2-seed0")

    assert factor(0.0) == pytest.approx(3.0)  # all alike: 90 s for 30
    assert 1.25 < factor(60.0) < 3.0  # a minute ago: still much of it
    assert 1.0 < factor(600.0) < 1.25  # ten minutes ago: mostly the speed of now


@pytest.fixture(scope="module")
def quick_plan(tmp_path_factory) -> tuple[dict[str, tuple[str, ...]], dict[str, float]]:
    """The stages of a quick bench from an empty folder (each with the stages it needs)
    and their expected costs."""
    planned = plan_bench(BenchConfig(out=str(tmp_path_factory.mktemp("empty"))))
    return {s.name: s.needs for s in planned}, {s.name: s.expected_s for s in planned}


def _simulate(
    needs: Mapping[str, tuple[str, ...]],
    expected: Mapping[str, float],
    wall: Callable[[str], float],
    workers: int,
) -> tuple[list[tuple[float, float | None]], float]:
    """Run the plan on a fake clock as the executors schedule it, each stage taking
    ``wall(name)``, through a :class:`BenchProgress`; its estimate after every event and
    the run's end."""
    clock = _Clock()
    progress = BenchProgress(expected, needs=needs, workers=workers, show=False, clock=clock)
    jobs = [Job(name, print, deps=deps) for name, deps in needs.items()]
    schedule = Schedule(jobs, expected)
    ends: list[tuple[float, str]] = []
    estimates = []
    while schedule.ready or ends:
        while schedule.ready and len(ends) < workers:
            name = schedule.next()
            progress.start(name)
            heapq.heappush(ends, (clock.now + wall(name), name))
            estimates.append((clock.now, progress.remaining_s()))
        clock.now = ends[0][0]
        while ends and ends[0][0] == clock.now:  # every stage that ends at this instant
            name = heapq.heappop(ends)[1]
            progress.finish(name, wall(name))
            schedule.finished(name)
        estimates.append((clock.now, progress.remaining_s()))
    return estimates, clock.now


def test_on_a_machine_twice_slower_than_the_table_the_estimate_converges_to_the_truth(
    quick_plan,
):
    needs, expected = quick_plan
    estimates, end = _simulate(needs, expected, lambda name: 2.0 * expected[name], 2)
    first = next(i for i, (_, estimate) in enumerate(estimates) if estimate is not None)
    assert 0 < estimates[first][0] < end / 4  # estimating, then the first stages tell
    for now, estimate in estimates[first:]:
        assert estimate == pytest.approx(end - now, rel=1e-6, abs=1e-6)


#: Measured over expected time per class of stage on a machine about 2× slower than the
#: table's, each class by up to 20 % more or less.
_SLOWER = {
    "demonstrations": 1.7,
    "training bc": 2.3,
    "training rs-gail": 2.0,
    "training tolerance-guided": 1.8,
    "evaluation": 1.7,
    "evaluation with inference": 2.3,
    "robustness": 2.4,
    "robustness with inference": 2.2,
    "robot": 1.8,
    "robot with inference": 2.0,
    "delicate": 1.9,
    "delicate with inference": 2.1,
    "study": 2.2,
}


def test_kinds_of_stage_off_by_different_factors_are_within_a_quarter_from_a_quarter_on(
    quick_plan,
):
    needs, expected = quick_plan
    assert {speed_class(name) for name in needs} == set(_SLOWER)

    def wall(name: str) -> float:
        slow = 1.3 if name.startswith("pi_n_efficient") else 1.0  # its candidates in contact
        return expected[name] * _SLOWER[speed_class(name)] * slow

    estimates, end = _simulate(needs, expected, wall, 2)
    errors = [
        abs(estimate - (end - now)) / (end - now)
        for now, estimate in estimates
        if now >= end / 4 and end - now >= 60 and estimate is not None
    ]
    assert all(e is not None for t, e in estimates if t >= end / 4)
    assert errors and max(errors) < 0.25, max(errors)


# --- the bar and its log ------------------------------------------------------------------


def test_progress_counts_every_stage_names_the_current_one_and_estimates_the_rest():
    clock = _Clock()
    cached = {"demos-Circle2x2-safe-seed0-0"}
    progress = BenchProgress(STAGES, cached, show=False, clock=clock)
    assert (progress.total, progress.finished) == (6, 1)
    assert progress.fraction == pytest.approx(10 / 55)
    assert progress.current() is None
    assert progress.remaining_s() is None  # nothing of this machine's speed known yet
    progress.start("bc_safe-seed0")
    clock.now = 4.0
    assert progress.current() == "training bc_safe-seed0"
    assert progress.remaining_s() is None
    clock.now = 20.0
    progress.finish("bc_safe-seed0", 20.0)  # twice as slow as expected: so is the rest
    assert progress.remaining_s() == pytest.approx(2 * (5 + 5 + 5 + 20))  # one worker
    progress.start("eval-C1.1-seed0")
    progress.start("eval-C1.1-seed1")
    clock.now = 22.0
    assert progress.current() == "evaluation eval-C1.1-seed0 (+1 more)"
    clock.now = 25.0
    progress.finish("eval-C1.1-seed0", 5.0)  # as expected
    progress.finish("eval-C1.1-seed1", 5.0)
    assert progress.fraction == pytest.approx(30 / 55)
    # robustness and the study at a typical class's speed: BC's 2 and the evaluations' 1
    # weigh alike (geometric mean; BC's, 5 s older, a little less)
    assert progress.remaining_s() == pytest.approx(math.sqrt(2) * (5 + 20), rel=0.02)
    progress.start("robust-safe-seed0")
    clock.now = 30.0
    assert progress.current() == "robustness robust-safe-seed0"
    progress.finish("robust-safe-seed0", 5.0)
    progress.start("inference-study")
    assert progress.current() == "study inference-study"
    clock.now = 40.0
    progress.finish("inference-study", 10.0)
    assert (progress.finished, progress.fraction, progress.remaining_s()) == (6, 1.0, 0.0)


def test_cached_stages_that_ran_on_this_machine_tell_its_speed_from_the_start():
    walls = {"demos-Circle2x2-safe-seed0-0": 30.0, "bc_safe-seed0": 30.0}  # 3x the table
    cached = set(walls)
    progress = BenchProgress(STAGES, cached, walls=walls, show=False, clock=_Clock())
    assert progress.remaining_s() == pytest.approx(3 * (5 + 5 + 5 + 20))
    two = BenchProgress(STAGES, cached, walls=walls, workers=2, show=False, clock=_Clock())
    assert two.remaining_s() == pytest.approx(3 * 20)  # the study; the rest beside it
    unknown = BenchProgress(STAGES, cached, show=False, clock=_Clock())  # ran elsewhere
    assert unknown.remaining_s() is None


def test_progress_draws_one_bar_with_the_stage_and_the_time_left(capsys):
    clock = _Clock()
    with BenchProgress(STAGES, show=True, clock=clock, refresh_s=None) as progress:
        progress.start("bc_safe-seed0")
        clock.now = 20.0
        progress.finish("bc_safe-seed0", 20.0)
    err = capsys.readouterr().err
    assert "bench:   0%|" in err
    assert "0/6 stages, training bc_safe-seed0, estimating the time left" in err
    assert "bench:  18%|" in err and "1/6 stages, about 2 min left" in err  # 20 s for 10: 90 s


def test_progress_logs_every_estimate_as_a_json_line(tmp_path):
    clock = _Clock()
    log = tmp_path / "progress.jsonl"
    with BenchProgress(STAGES, log=log, show=False, clock=clock) as progress:
        progress.start("bc_safe-seed0")
        clock.now = 20.0
        progress.finish("bc_safe-seed0", 20.0)
    lines = [json.loads(line) for line in log.read_text().splitlines()]
    assert [line["event"] for line in lines] == ["begin", "start", "finish"]
    assert [line["stage"] for line in lines] == [None, "bc_safe-seed0", "bc_safe-seed0"]
    assert [line["t"] for line in lines] == [0.0, 0.0, 20.0]
    assert [line["finished"] for line in lines] == [0, 0, 1]
    assert lines[0]["remaining_s"] is None and lines[1]["remaining_s"] is None
    assert lines[2]["remaining_s"] == pytest.approx(2 * (10 + 5 + 5 + 5 + 20))


def test_a_stage_ran_here_when_its_marker_names_this_host_and_cpu(tmp_path):
    cache = StageCache(tmp_path)
    folder, _ = cache.run("train", {"x": 1}, lambda folder: None)
    marker = json.loads((folder / MARKER).read_text())
    assert marker["host"] == socket.gethostname() and marker["cpu"] == cpu()["description"]
    assert cache.ran_here(folder)
    for change in ({"cpu": "another CPU"}, {"host": "another-host"}):
        (folder / MARKER).write_text(json.dumps({**marker, **change}))
        assert not cache.ran_here(folder), change
    del marker["cpu"]  # written before markers named the CPU: the host alone
    (folder / MARKER).write_text(json.dumps(marker))
    assert cache.ran_here(folder)


# --- the cost table and a real run ----------------------------------------------------------


def test_expected_costs_follow_the_budgets_and_the_measured_reference_run():
    quick = PROFILES["quick"]
    record = json.loads(reference_path("quick").with_name("run.json").read_text())
    measured = {name: stage["wall_s"] for name, stage in record["stages"].items()}
    expected = {name: expected_cost(name, quick, "mujoco") for name in measured}
    assert 0.5 < sum(expected.values()) / sum(measured.values()) < 2.0
    # (the quick profile trains no deep-RL baseline)
    for kind in ("bc_", "pi_n_", "pi_phi_", "eval-", "inference-study"):
        names = [name for name in measured if name.startswith(kind)]
        ratio = sum(expected[n] for n in names) / sum(measured[n] for n in names)
        assert 0.4 < ratio < 2.5, (kind, ratio)
    cost = {name: expected_cost(name, quick, "mujoco") for name in STAGES}
    assert all(value > 0.5 for value in cost.values())
    assert expected_cost("eval-C4.2-seed0", quick, "mujoco") > cost["eval-C1.1-seed0"]
    assert expected_cost("pi_n_safe-seed0", quick, "kinematic") < measured["pi_n_safe-seed0"]


def test_a_bench_run_shows_one_bar_over_its_stages_and_logs_its_estimates(tmp_path, capsys):
    out = tmp_path / "bench"
    config = BenchConfig(
        profile="tiny",
        rows="C2.1",
        backend="kinematic",
        out=str(out),
        study=False,
        robustness=False,
    )
    run_bench(config, log=lambda _: None)
    err = capsys.readouterr().err
    assert "0/1 stages, evaluation eval-C2.1-seed0" in err and "1/1 stages" in err, err
    assert "evaluate:" not in err
    lines = [json.loads(line) for line in (out / PROGRESS_LOG).read_text().splitlines()]
    assert [(line["event"], line["stage"]) for line in lines] == [
        ("begin", None),
        ("start", "eval-C2.1-seed0"),
        ("finish", "eval-C2.1-seed0"),
    ]
    assert lines[-1]["finished"] == lines[-1]["total"] == 1 and lines[-1]["remaining_s"] == 0
    # no deep-RL row ran: results.md says where they are
    markdown = (out / "results.md").read_text()
    assert "## Deep RL from scratch against RS-GAIL at equal env steps" in markdown
    assert "This run has no deep-RL row (`--rows`); these rows are `reference:paper`'s" in markdown
    assert "| R1.1 | PPO (sparse) |" in markdown and "| R2.4 | SAC (dense) |" in markdown
    assert json.loads((out / "curves.json").read_text()) == {}
