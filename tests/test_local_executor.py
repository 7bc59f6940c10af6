"""The local executor: every job as soon as its dependencies are done, on its worker
threads, the one with the most work behind it first; results as by a plain loop."""

from __future__ import annotations

import os
import threading
import time

import pytest

from tolins.bench.pipeline.executor import Job, LocalExecutor, critical_paths, failed_stage
from tolins.policies import EXPERTS
from tolins.rollouts import runner
from tolins.stopping import stop_requested

_BARRIER = threading.Barrier(2, timeout=10)
_LOG: list[str] = []


def _meet(name: str) -> str:
    _BARRIER.wait()  # both workers must hold a job at once, or this times out
    return name


def _record(name: str, *deps: object) -> str:
    _LOG.append(name)
    return name + "".join(f"<{d}" for d in deps)


def _fail(name: str) -> str:
    raise RuntimeError(f"{name} failed")


def _slow(name: str) -> str:
    time.sleep(0.2)
    _LOG.append(name)
    return name


def test_independent_jobs_run_side_by_side() -> None:
    jobs = [Job("a", _meet, ("a",)), Job("b", _meet, ("b",))]
    assert LocalExecutor(2).run(jobs) == {"a": "a", "b": "b"}


def test_a_job_waits_for_its_dependencies_and_takes_their_results() -> None:
    _LOG.clear()
    jobs = [
        Job("train", _slow, ("train",)),
        Job("eval", _record, ("eval",), deps=("train",)),
        Job("other", _record, ("other",)),
    ]
    results = LocalExecutor(2).run(jobs)
    assert results == {"train": "train", "eval": "eval<train", "other": "other"}
    assert list(results) == ["train", "eval", "other"]  # the jobs' order
    assert _LOG.index("train") < _LOG.index("eval")


def test_the_ready_job_with_the_costliest_chain_starts_first() -> None:
    _LOG.clear()
    jobs = [
        Job("cheap", _record, ("cheap",)),
        Job("long", _record, ("long",)),
        Job("after-long", _record, ("after-long",), deps=("long",)),
    ]
    costs = {"cheap": 5.0, "long": 3.0, "after-long": 4.0}
    assert critical_paths(jobs, costs) == {"cheap": 5.0, "long": 7.0, "after-long": 4.0}
    LocalExecutor(1).run(jobs, costs=costs)
    assert _LOG == ["long", "cheap", "after-long"]  # by the chain behind each: 7, 5, 4


def test_a_failure_stops_the_run_and_is_raised() -> None:
    _LOG.clear()
    jobs = [
        Job("bad", _fail, ("bad",)),
        Job("after", _record, ("after",), deps=("bad",)),
    ]
    with pytest.raises(RuntimeError, match="bad failed") as raised:
        LocalExecutor(2).run(jobs)
    assert "after" not in _LOG
    assert failed_stage(raised.value) == "bad"
    assert "(raised by the bench's stage bad)" in raised.value.__notes__


def _many_episodes(name: str) -> str:
    """20,000 episodes of the kinematic 2*2 (half a minute or more), then its name logged."""
    envs = runner.VectorEnvCache("kinematic", num_envs=16)
    try:
        jobs = [runner.Job("tolins/Circle2x2-v2", EXPERTS["safe"](), s) for s in range(20_000)]
        runner.run_jobs(envs, jobs)
    finally:
        envs.close()
    _LOG.append(name)
    return name


def _fail_soon(name: str) -> str:
    time.sleep(0.5)
    return _fail(name)


def test_a_failure_stops_the_running_jobs_at_their_next_control_step() -> None:
    _LOG.clear()
    jobs = [Job("long", _many_episodes, ("long",)), Job("bad", _fail_soon, ("bad",))]
    with pytest.raises(RuntimeError, match="bad failed"):
        LocalExecutor(2).run(jobs)
    assert "long" not in _LOG  # it stopped instead of running its episodes to the end
    assert not stop_requested()  # and rollouts run again
    envs = runner.VectorEnvCache("kinematic", num_envs=1)
    assert runner.run_jobs(envs, [runner.Job("tolins/Circle2x2-v2", EXPERTS["safe"](), 0)])
    envs.close()


def _count(name: str, *deps: object) -> tuple[str, int, tuple]:
    """A pure-Python loop (it holds the GIL), then where it ran and what it was given."""
    total = sum(i * i for i in range(200_000))
    assert total > 0
    return name, os.getpid(), deps


def test_own_process_jobs_run_in_processes_of_their_own_and_take_results() -> None:
    jobs = [
        Job("a", _count, ("a",), own_process=True),
        Job("b", _count, ("b",), own_process=True),
        Job("c", _count, ("c",), deps=("a",), own_process=True),
        Job("d", _record, ("d",), deps=("c",)),  # a thread's job after a process's
    ]
    executor = LocalExecutor(2)
    try:
        results = executor.run(jobs)
    finally:
        executor.close()
    pids = {results[n][1] for n in "abc"}
    assert os.getpid() not in pids and len(pids) <= 2  # the executor's two processes
    assert results["c"][2] == (results["a"],)
    assert results["d"] == f"d<{results['c']}"
    assert {executor.placement[n]["pid"] for n in "abc"} == pids
    assert executor.placement["d"]["pid"] == os.getpid()


def _sleep_long(name: str) -> str:
    time.sleep(600)
    return name


def test_a_failure_ends_a_running_own_process_job_with_its_process() -> None:
    executor = LocalExecutor(2)
    began = time.monotonic()
    try:
        with pytest.raises(RuntimeError, match="bad failed"):
            executor.run(
                [
                    Job("slow", _sleep_long, ("slow",), own_process=True),
                    Job("bad", _fail_soon, ("bad",)),
                ]
            )
    finally:
        executor.close()
    assert time.monotonic() - began < 300  # not the 600 s the process would sleep


def test_a_failure_in_an_own_process_job_is_raised() -> None:
    executor = LocalExecutor(2)
    try:
        with pytest.raises(RuntimeError, match="bad failed"):
            executor.run([Job("bad", _fail, ("bad",), own_process=True)])
    finally:
        executor.close()
