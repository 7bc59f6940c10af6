"""The Ray executor (``tolins bench --executor ray``) and RS-GAIL on Ray actors: results
identical to the local executor's, RS-GAIL's on a local Ray instance, the bench's on a
two-node cluster that the test starts on 127.0.0.1 (and stops: it ends the two ``ray start
--block`` processes it started, which take their raylets, GCS and workers with them)."""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
import ray

from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.executor import Job as Stage
from tolins.bench.pipeline.executor import RayExecutor, failed_stage
from tolins.bench.pipeline.runner import run_bench
from tolins.cli import main
from tolins.learning.imitation.bc import behaviour_clone
from tolins.learning.imitation.config import BCConfig, RSGailConfig
from tolins.learning.imitation.demonstrations import collect
from tolins.learning.imitation.rs_gail import Workpiece, train_rs_gail
from tolins.policies import EXPERTS
from tolins.rollouts.collectors import Pairs
from tolins.rollouts.pool import VectorPool
from tolins.rollouts.ray_pool import RayPool
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs

RAY_ENV = {"RAY_USAGE_STATS_ENABLED": "0", "RAY_AUTH_MODE": "disabled"}
OBJECT_STORE = 200 * 2**20
ROWS = "C1.1,C2.3,C3.2"  # an expert, π_n (BC -> RS-GAIL) and π_φ (-> tolerance-guided)
RAY_BIN = str(Path(sys.executable).parent / "ray")


@pytest.fixture(scope="module", autouse=True)
def ray_environment():
    before = {k: os.environ.get(k) for k in RAY_ENV}
    os.environ.update(RAY_ENV)
    yield
    for key, value in before.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value


@pytest.fixture(scope="module")
def local_ray():
    """A Ray instance in this process with 2 CPUs."""
    ray.init(
        num_cpus=2,
        include_dashboard=False,
        object_store_memory=OBJECT_STORE,
        configure_logging=False,
        log_to_driver=False,
    )
    yield
    ray.shutdown()


def _bench(out: Path, **kwargs) -> BenchConfig:
    return BenchConfig(profile="tiny", rows=ROWS, backend="kinematic", out=str(out), **kwargs)


def _outputs(out: Path) -> tuple[dict, dict | None]:
    rows = json.loads((out / "results.json").read_text())["rows"]
    study = out / "inference.json"
    return rows, json.loads(study.read_text()) if study.exists() else None


@pytest.fixture(scope="module")
def local_outputs(tiny_bench, tmp_path_factory):
    """The local executor's results of the rows: the shared tiny bench's stages (made by
    the local executor, tests/conftest.py), re-reported for these rows."""
    out = tmp_path_factory.mktemp("local")
    tiny_bench.copy_stages(out)
    run = run_bench(_bench(out, figures=False), progress=False, log=lambda _: None)
    assert sorted(run.cached) == sorted(run.stage_times)  # nothing ran again
    return _outputs(out)


def test_a_vector_env_kept_between_runs_gives_a_fresh_ones_episodes():
    for env_id in ("tolins/Circle2x2-v1", "tolins/Circle2x1Defective-v1"):
        kept = VectorEnvCache("mujoco", num_envs=2, num_threads=2)
        run_jobs(kept, [Job(env_id, EXPERTS["safe"](), seed) for seed in (3, 4, 6)])
        again = run_jobs(kept, [Job(env_id, EXPERTS["efficient"](), 5, (Pairs(),))])[0]
        fresh = VectorEnvCache("mujoco", num_envs=1, num_threads=1)
        first = run_jobs(fresh, [Job(env_id, EXPERTS["efficient"](), 5, (Pairs(),))])[0]
        assert np.array_equal(again.observations, first.observations), env_id
        assert (again.reward, again.collisions) == (first.reward, first.collisions)
        assert kept.env_ids == [env_id]
        kept.close()
        fresh.close()


def test_rs_gail_on_ray_actors_searches_exactly_as_on_threads(local_ray, tmp_path):
    env = "tolins/Circle2x2-v1"
    demos = collect(env, "efficient", 4, seed=0, backend="mujoco")
    policy = behaviour_clone(demos, BCConfig(epochs=5), seed=0).policy
    config = RSGailConfig(iterations=2, popsize=4, episodes=2, eval_episodes=2, sigma0=0.05)
    pools = {"threads": VectorPool(num_threads=2), "ray": RayPool.start()}
    results = {}
    for name, pool in pools.items():
        results[name] = train_rs_gail(
            policy.with_flat(policy.get_flat()),
            [Workpiece(env)],
            demos,
            config,
            seed=0,
            backend="mujoco",
            out=tmp_path / name,
            metadata={},
            progress=False,
            pool=pool,
        )
    figures = {
        n: [{k: v for k, v in row.items() if k != "wall_s"} for row in r.history]
        for n, r in results.items()
    }
    assert figures["ray"] == figures["threads"]
    assert np.array_equal(results["ray"].means, results["threads"].means)
    assert results["ray"].final == results["threads"].final
    kept = ray.get([w.env_ids.remote() for w in pools["ray"].workers])
    assert [("mujoco", env)] in kept  # the actors keep their envs between iterations
    assert len(pools["ray"].workers) == 2  # one per CPU
    pools["threads"].close()
    pools["ray"].shutdown()


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _alive_nodes(address: str) -> int:
    code = (
        f"import ray; ray.init(address={address!r}, configure_logging=False, "
        "log_to_driver=False); print(sum(n['Alive'] for n in ray.nodes()))"
    )
    try:
        done = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, timeout=30
        )
    except subprocess.TimeoutExpired:
        return 0
    return int(done.stdout.strip() or 0)


def _wait_for_nodes(address: str, nodes: int, started: list[subprocess.Popen]) -> None:
    deadline = time.monotonic() + 90
    while _alive_nodes(address) < nodes:
        failed = [p.args for p in started if p.poll() is not None]
        assert not failed, f"ray start exited: {failed}"
        assert time.monotonic() < deadline, f"{nodes} Ray node(s) did not come up"
        time.sleep(1)


@pytest.fixture()
def two_nodes():
    """A head and a worker node (1 CPU each) on 127.0.0.1; their address."""
    port = _free_port()
    address = f"127.0.0.1:{port}"
    temp = tempfile.mkdtemp(prefix="tolins-ray-")  # short: Ray's socket paths have a limit
    common = ["--num-cpus=1", "--node-ip-address=127.0.0.1", "--block"]
    common += [f"--object-store-memory={OBJECT_STORE}", f"--temp-dir={temp}"]
    head = [RAY_BIN, "start", "--head", f"--port={port}", "--include-dashboard=false"]
    env = {**os.environ, **RAY_ENV}
    quiet = {"env": env, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    started = [subprocess.Popen([*head, *common], **quiet)]
    try:
        _wait_for_nodes(address, 1, started)
        started.append(
            subprocess.Popen([RAY_BIN, "start", f"--address={address}", *common], **quiet)
        )
        _wait_for_nodes(address, 2, started)
        yield address
    finally:
        for process in reversed(started):
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
        shutil.rmtree(temp, ignore_errors=True)


@pytest.mark.slow
def test_a_two_node_cluster_gives_the_local_executors_results(two_nodes, local_outputs, tmp_path):
    command = [
        str(Path(sys.executable).parent / "tolins"),
        "bench",
        "--profile",
        "tiny",
        "--rows",
        ROWS,
    ]
    command += ["--backend", "kinematic", "--out", str(tmp_path), "--executor", "ray"]
    done = subprocess.run(
        [*command, "--address", two_nodes],
        env={**os.environ, **RAY_ENV},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert _outputs(tmp_path) == local_outputs
    stages = json.loads((tmp_path / "run.json").read_text())["stages"]
    # 2 demonstration datasets (2*2, 2*8), 3 trainings (bc_safe, pi_n_safe, pi_phi_circle),
    # 3 evaluations, the study, 5 robustness stages (tolins.bench.jobs.robustness), π_n's
    # trajectories
    assert len(stages) == 15
    assert all(s["node"] and s["finished"] >= s["started"] for s in stages.values())
    assert len({s["node"] for s in stages.values()}) == 2  # both nodes ran stages
    assert (tmp_path / "timeline.png").read_bytes()[:4] == b"\x89PNG"


def _bench_cli(tmp_path, *options: str) -> list[str]:
    return ["bench", "--profile", "tiny", "--rows", "C1.1", "--out", str(tmp_path), *options]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (("--address", "auto"), "needs executor='ray' (--executor ray)"),
        (("--executor", "ray", "--address", "head"), "allowed: auto"),
        (("--executor", "ray", "--address", "127.0.0.1:0"), "allowed: auto"),
    ],
)
def test_bad_executor_options_are_refused_with_what_is_allowed(tmp_path, capsys, options, message):
    assert main(_bench_cli(tmp_path, *options)) == 2
    assert message in capsys.readouterr().err


def test_an_address_without_a_ray_head_says_so(tmp_path, capsys):
    assert (
        main(_bench_cli(tmp_path, "--executor", "ray", "--address", f"127.0.0.1:{_free_port()}"))
        == 2
    )
    assert "no Ray head answers there" in capsys.readouterr().err
    assert not (tmp_path / "stages").exists()


@pytest.fixture
def not_a_head():
    """A port on a loopback address that accepts connections and never answers (as a
    service other than a Ray head, or a firewall, can): its ``HOST:PORT``."""
    with socket.socket() as listener:
        listener.bind(("127.0.0.2", 0))  # not 127.0.0.1, which Ray swaps for the machine's IP
        listener.listen(16)
        yield f"127.0.0.2:{listener.getsockname()[1]}"


@pytest.mark.parametrize("where", ["closed port", "no Ray head"])
def test_an_address_without_a_ray_head_is_one_line(tmp_path, not_a_head, where):
    address = "127.0.0.1:1" if where == "closed port" else not_a_head
    command = [sys.executable, "-m", "tolins", *_bench_cli(tmp_path / "out", "--executor", "ray")]
    try:
        done = subprocess.run(
            [*command, "--address", address], capture_output=True, text=True, timeout=60
        )
    except subprocess.TimeoutExpired as expired:
        pytest.fail(f"still connecting after 60 s; its stderr: {expired.stderr!r}"[:3000])
    err = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(err) == 1, done.stderr[-3000:]
    assert f"address={address!r}" in err[0] and "no Ray head answers there" in err[0], err
    assert not (tmp_path / "out" / "stages").exists()


@pytest.mark.parametrize("where", ["closed port", "no Ray head"])
def test_an_address_without_a_ray_head_is_refused_in_seconds_before_ray_init(
    monkeypatch, not_a_head, where
):
    from tolins.bench.pipeline.executor import PROBE_S

    def init(*args, **kwargs):
        raise AssertionError("ray.init was called: it retries for minutes")

    monkeypatch.setattr(ray, "init", init)
    address = "127.0.0.1:1" if where == "closed port" else not_a_head
    began = time.monotonic()
    with pytest.raises(ValueError, match="no Ray head answers there"):
        RayExecutor(address)
    assert time.monotonic() - began < 2 * PROBE_S + 3


def test_a_damaged_stage_file_read_in_a_task_is_its_one_line(local_ray, tmp_path):
    from tolins.bench.store.integrity import StageFileError, read_json

    (tmp_path / "episodes.json").write_text("[1,")
    with pytest.raises(StageFileError) as raised:
        RayExecutor().run([Stage("eval", read_json, (tmp_path / "episodes.json",))])
    assert type(raised.value) is StageFileError and failed_stage(raised.value) == "eval"
    assert str(raised.value).startswith(f"{tmp_path / 'episodes.json'}: not JSON")
    assert "\n" not in str(raised.value)


def test_a_task_is_reported_started_when_it_begins_not_when_submitted(local_ray):
    # Library functions: Ray imports them by name on its workers.
    jobs = [Stage("slow", time.sleep, (2.5,)), Stage("after", print, ("after",), deps=("slow",))]
    started, finished = {}, {}
    executor = RayExecutor()
    executor.run(
        jobs,
        on_start=lambda job: started.setdefault(job.name, time.monotonic()),
        on_done=lambda job, _: finished.setdefault(job.name, time.monotonic()),
    )
    executor.close()
    assert set(started) == set(finished) == {"slow", "after"}
    # "after" cannot begin before "slow" ends; the executor reads the starts once a second
    assert started["after"] - started["slow"] > 1.0
    assert all(started[name] <= finished[name] for name in started)


def test_tasks_start_as_cpus_free_up_the_costliest_chain_first(local_ray):
    executor = RayExecutor()
    warm_up = [Stage(name, time.sleep, (0.5,)) for name in ("a", "b")]
    executor.run(warm_up, on_start=lambda _: None)  # both workers and the start queue up
    jobs = [Stage(name, time.sleep, (3.0,)) for name in ("x", "y", "big")]
    order = []
    executor.run(jobs, on_start=lambda job: order.append(job.name), costs={"big": 10.0})
    executor.close()
    # 2 CPUs: "big" and "x" first, "y" once one of them has ended (submitted all at once,
    # Ray would start "x" and "y")
    assert sorted(order[:2]) == ["big", "x"] and order[2] == "y"


def test_a_failed_task_is_raised_naming_its_stage(local_ray):
    executor = RayExecutor()
    with pytest.raises(ValueError, match="math domain error") as raised:
        executor.run([Stage("bad", math.sqrt, (-1.0,))], on_start=lambda _: None)
    assert failed_stage(raised.value) == "bad"
    executor.close()


def test_an_address_while_ray_runs_in_this_process_is_refused(local_ray):
    with pytest.raises(ValueError, match="already initialised in this process"):
        RayExecutor("auto")


def test_the_ray_executor_without_ray_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    assert main(_bench_cli(tmp_path, "--executor", "ray")) == 2
    assert "pip install 'tolins[ray]'" in capsys.readouterr().err


@pytest.mark.slow
def test_the_local_executor_runs_without_importing_ray(tmp_path):
    code = (
        "import sys; from tolins.cli import main;"
        f"code = main(['bench', '--profile', 'tiny', '--rows', 'C1.1', '--backend', "
        f"'kinematic', '--no-study', '--out', {str(tmp_path)!r}]);"
        "assert code == 0, code; assert 'ray' not in sys.modules"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]


def test_the_timeline_draws_the_stages_that_ran_on_their_workers(tmp_path):
    from tolins.bench.pipeline.timeline import plot_timeline, timeline_rows, worker_label

    local = {"node": None, "host": "vm", "pid": 7, "thread": "MainThread"}
    times = {
        "bc_safe-seed0": {"started": 100.0, "finished": 110.0, "cached": False, **local},
        "eval-C2.1-seed0": {
            "started": 110.0,
            "finished": 115.0,
            "cached": False,
            **{**local, "thread": "ThreadPoolExecutor-0_1"},
        },
        "pi_n_safe-seed0": {"started": 1.0, "finished": 2.0, "cached": True, **local},
        "inference-study": {
            "started": 105.0,
            "finished": 120.0,
            "cached": False,
            **local,
            "node": "f31ce0abcdef",
            "pid": 9,
        },
    }
    rows = timeline_rows(times)
    assert [r["name"] for r in rows] == ["bc_safe-seed0", "inference-study", "eval-C2.1-seed0"]
    assert [(r["start"], r["end"]) for r in rows] == [(0, 10), (5, 20), (10, 15)]
    assert [r["kind"] for r in rows] == ["training", "study", "evaluation"]
    assert worker_label(local) == "vm pid 7"
    assert rows[1]["lane"] == "node f31ce0 pid 9"
    assert rows[2]["lane"] == "vm pid 7 ThreadPoolExecutor-0_1"
    path = plot_timeline(tmp_path / "timeline.png", rows, "test")
    assert path.read_bytes()[:4] == b"\x89PNG"
    assert timeline_rows({"x": {**times["pi_n_safe-seed0"]}}) == []  # nothing ran
