"""Deep-RL trainings survive interruption: a paper-profile SAC stage ended by the bench's
executor (SIGTERM), then killed (SIGKILL), or interrupted by SIGINT, and run again ends with
the weights (and optimiser states) of an uninterrupted one, bit for bit; so does PPO
stopped on request. A checkpoint of another configuration, one whose envs do not replay,
and a diverged training are refused (``RunRefused``); ``tolins train`` reports a refusal as
one line with exit status 3 and a bug's ``ValueError`` as a traceback."""

from __future__ import annotations

import csv
import io
import json
import os
import pickle
import shutil
import signal
import subprocess
import sys
import time
import zipfile
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch

from tolins.bench.jobs.training import train_job, training_stage
from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.pipeline.settings import training_spec
from tolins.bench.store.cache import MARKER, StageCache
from tolins.learning.agents import sb3
from tolins.learning.agents.sb3_config import CHECKPOINT, CURVES, MODEL, Sb3Config
from tolins.learning.artefacts import RunRefused
from tolins.stopping import Stopped, clear_stop, request_stop, stop_requested

#: A SAC stage of the paper profile (its settings: 64×64 networks, 1,000 random steps
#: first) on a tiny budget: 100 gradient steps, a checkpoint every 50 env steps.
BUDGET = {"env_steps": 1100, "curve_every": 550, "curve_episodes": 1, "checkpoint_every": 50}

#: Run in a process of its own: the stage of the pickled file, that process ending itself
#: with a signal once SB3 has taken a number of env steps (argv: stage, root, signal, steps).
_KILLED = """
import os, pickle, sys
from pathlib import Path
from tolins.bench.jobs.training import train_job
from tolins.learning.agents import sb3

stage = pickle.loads(Path(sys.argv[1]).read_bytes())
number, at = int(sys.argv[3]), int(sys.argv[4])
step = sb3._Checkpoints._on_step

def on_step(self):
    if self.run.model.num_timesteps == at:
        os.kill(os.getpid(), number)
    return step(self)

sb3._Checkpoints._on_step = on_step
train_job(Path(sys.argv[2]), stage, None, False, None)
"""


@pytest.fixture(scope="module")
def sac_stage():
    spec = training_spec("sac_circle_sparse", 0, PROFILES["paper"], "kinematic")
    return training_stage(replace(spec, sb3=replace(spec.sb3, **BUDGET)), None)


@pytest.fixture(scope="module")
def uninterrupted(sac_stage, tmp_path_factory) -> Path:
    """The finished folder of the SAC stage run without interruption."""
    root = tmp_path_factory.mktemp("whole")
    return train_job(root, sac_stage, None, False, None).parent


def _saved(folder: Path) -> dict[str, Any]:
    """Every torch file in the folder's SB3 zip: weights, optimiser states, SAC's α."""
    with zipfile.ZipFile(folder / MODEL) as archive:
        names = [name for name in archive.namelist() if name.endswith(".pth")]
        return {n: torch.load(io.BytesIO(archive.read(n)), weights_only=True) for n in names}


def _assert_identical(a: Any, b: Any, where: str = "") -> None:
    if isinstance(a, torch.Tensor):
        assert torch.equal(a, b), where
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for key in a:
            _assert_identical(a[key], b[key], f"{where}/{key}")
    elif isinstance(a, list | tuple):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _assert_identical(x, y, f"{where}/{i}")
    else:
        assert a == b, where


def _curve(folder: Path) -> list[tuple[str, ...]]:
    """The learning curve without its timings."""
    with open(folder / CURVES) as file:
        return [(r["env_steps"], r["reward"], r["success"]) for r in csv.DictReader(file)]


def _folder(root: Path, stage) -> Path:
    """The folder of ``stage`` in the bench's cache under ``root``."""
    return StageCache(root).folder(stage.name, stage.config)


def _finished(folder: Path) -> bool:
    return (folder / MARKER).is_file()


def _steps(checkpoint: Path) -> int:
    payload = torch.load(checkpoint, weights_only=True)
    return payload["model"]["counters"]["num_timesteps"]


def _kill(stage, root: Path, number: int, at: int) -> int:
    """Run ``stage`` under ``root`` in a new process that ends itself with signal
    ``number`` at env step ``at``; its exit status."""
    path = root / "stage.pickle"
    path.write_bytes(pickle.dumps(stage))
    command = [sys.executable, "-c", _KILLED, str(path), str(root), str(number), str(at)]
    return subprocess.run(command, timeout=300).returncode


def _train_slowly(root: str, stage) -> None:
    """``train_job`` that, after the first point of the curve, waits (up to a minute) for
    the stop the test makes, so that it arrives mid-training however loaded the machine."""
    step = sb3._Checkpoints._on_step

    def on_step(self) -> bool:
        if self.run.model.num_timesteps > BUDGET["curve_every"]:
            deadline = time.monotonic() + 60.0
            while self.signals.pending is None and not stop_requested():
                if time.monotonic() > deadline:
                    break
                time.sleep(0.01)
        return step(self)

    sb3._Checkpoints._on_step = on_step
    train_job(Path(root), stage, None, False, None)


def _fail_after_the_first_point(folder: str) -> None:
    """Another stage, which fails once the training has its first point."""
    while not (Path(folder) / CURVES).exists() and not stop_requested():
        time.sleep(0.05)
    raise RuntimeError("another stage failed")


def _with_interval(stage, every: int):
    """``stage`` with a checkpoint every ``every`` env steps (the same stage and folder)."""
    spec = stage.spec
    other = training_stage(replace(spec, sb3=replace(spec.sb3, checkpoint_every=every)), None)
    assert other.name == stage.name and other.config == stage.config
    return other


@pytest.mark.slow
def test_a_sac_stage_ended_by_the_bench_then_killed_resumes_to_the_same_weights(
    sac_stage, uninterrupted, tmp_path
) -> None:
    from tolins.bench.pipeline.executor import Job, LocalExecutor

    folder = _folder(tmp_path, sac_stage)
    # The bench's executor ends the training's process with SIGTERM when another stage
    # fails (as on Ctrl-C); the training writes its checkpoint first (its only one here).
    stage = _with_interval(sac_stage, 10**6)
    training = Job("sac", _train_slowly, (str(tmp_path), stage), own_process=True)
    other = Job("other", _fail_after_the_first_point, (str(folder),))
    executor = LocalExecutor(workers=2)
    try:
        with pytest.raises(RuntimeError, match="another stage failed"):
            executor.run([training, other])
    finally:
        executor.close()
    stopped = _steps(folder / CHECKPOINT)
    assert BUDGET["curve_every"] < stopped < BUDGET["env_steps"] and not _finished(folder)
    # resumed there, then killed outright 25 steps after a checkpoint (every 50 steps: at
    # 1050 or later, 50 gradient steps into learning: replay buffer and optimisers full)
    killed = _with_interval(sac_stage, 50)
    assert _kill(killed, tmp_path, signal.SIGKILL, 1075) == -signal.SIGKILL
    assert 1025 < _steps(folder / CHECKPOINT) < 1075 and not _finished(folder)
    # the bench runs the stage again in the same folder: it resumes from that checkpoint
    assert train_job(tmp_path, sac_stage, None, False, None).parent == folder
    assert _finished(folder) and not (folder / CHECKPOINT).exists()
    _assert_identical(_saved(folder), _saved(uninterrupted))
    assert _curve(folder) == _curve(uninterrupted)


def test_sigint_checkpoints_then_interrupts_and_the_stage_resumes(
    sac_stage, uninterrupted, tmp_path, monkeypatch
) -> None:
    step = sb3._Checkpoints._on_step

    def on_step(self) -> bool:
        if self.run.model.num_timesteps == 1030:
            os.kill(os.getpid(), signal.SIGINT)
        return step(self)

    monkeypatch.setattr(sb3._Checkpoints, "_on_step", on_step)
    # Ctrl-C as an interactive run gets it (a pytest-xdist worker ignores SIGINT)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            train_job(tmp_path, sac_stage, None, False, None)
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored
    finally:
        signal.signal(signal.SIGINT, previous)
    monkeypatch.undo()
    folder = _folder(tmp_path, sac_stage)
    assert _steps(folder / CHECKPOINT) == 1030 and not _finished(folder)
    train_job(tmp_path, sac_stage, None, False, None)
    _assert_identical(_saved(folder), _saved(uninterrupted))
    assert _curve(folder) == _curve(uninterrupted)


def test_a_stage_killed_after_training_before_its_record_trains_no_more(
    sac_stage, uninterrupted, tmp_path, monkeypatch
) -> None:
    """Killed once the training has finished but before the stage's record is written, the
    stage keeps the finished training's checkpoint: run again, it takes no env step and
    ends with the uninterrupted weights; the record leaves the checkpoint out, which goes."""
    from tolins.bench.store import cache

    class Killed(BaseException):
        pass

    def killed(*_args, **_kwargs):
        raise Killed

    monkeypatch.setattr(cache, "atomic_json", killed)
    with pytest.raises(Killed):
        train_job(tmp_path, sac_stage, None, False, None)
    monkeypatch.undo()
    folder = _folder(tmp_path, sac_stage)
    assert _steps(folder / CHECKPOINT) == BUDGET["env_steps"] and not _finished(folder)

    def learn(*_args, **_kwargs):
        raise AssertionError("the finished training trained again")

    monkeypatch.setattr(sb3._Run, "learn", learn)
    train_job(tmp_path, sac_stage, None, False, None)
    assert _finished(folder) and not (folder / CHECKPOINT).exists()
    _assert_identical(_saved(folder), _saved(uninterrupted))
    assert _curve(folder) == _curve(uninterrupted)
    assert CHECKPOINT not in json.loads((folder / MARKER).read_text())["files"]
    assert StageCache(tmp_path).problem(folder) is None


def test_the_checkpoint_interval_is_not_part_of_the_stage(sac_stage) -> None:
    spec = sac_stage.spec
    other = replace(spec, sb3=replace(spec.sb3, checkpoint_every=7))
    assert training_stage(other, None).config == sac_stage.config


def test_new_envs_replay_the_running_episodes_to_the_same_state() -> None:
    """Episodes of different lengths (successes end some early) on contact physics."""
    from tolins.paper import A_MAX
    from tolins.policies.experts import SafeExpert
    from tolins.rollouts.sb3_vec import Sb3VectorEnv

    expert, rng, n = SafeExpert(), np.random.default_rng(0), 3
    ours = Sb3VectorEnv("tolins/Circle2x2-v2", n, reward_mode="dense")
    ours.seed(3)
    observations = ours.reset()

    def actions() -> np.ndarray:
        moves = np.array([expert(o.astype(float)) / A_MAX for o in observations])
        return np.clip(moves + rng.normal(0, 0.05, (n, 4)), -1, 1).astype(np.float32)

    for _ in range(70):
        observations = ours.step(actions())[0]
    lengths = {len(episode.actions) for episode in ours.episodes()}
    assert len(lengths) > 1, lengths  # the envs are at different steps of their episodes
    theirs = Sb3VectorEnv("tolins/Circle2x2-v2", n, reward_mode="dense")
    assert np.array_equal(theirs.replay(ours.episodes()), observations)
    for _ in range(50):  # and go on as the envs replayed would, resets included
        moves = actions()
        a, b = ours.step(moves), theirs.step(moves)
        for x, y in zip(a[:3], b[:3], strict=True):
            assert np.array_equal(x, y)
        observations = a[0]
    with pytest.raises(ValueError, match="on an env that has not been reset"):
        theirs.replay(ours.episodes())
    ours.close()
    theirs.close()


# --- PPO, on contact physics, stopped on request; refusals ------------------------------

PPO = Sb3Config(
    "ppo", "tolins/Circle2x2-v2", env_steps=384, curve_every=256, curve_episodes=1, n_envs=4,
    checkpoint_every=10**6,
)  # fmt: skip
PPO_SETTINGS = {"n_steps": 32, "batch_size": 64, "n_epochs": 2}  # 128 env steps a rollout


def _stop_at(monkeypatch, steps: int) -> None:
    """Request a stop once SB3 has taken ``steps`` env steps."""
    step = sb3._Checkpoints._on_step

    def on_step(self) -> bool:
        if self.run.model.num_timesteps >= steps:
            request_stop()
        return step(self)

    monkeypatch.setattr(sb3._Checkpoints, "_on_step", on_step)


def test_ppo_stopped_on_request_resumes_to_the_same_weights(tmp_path, monkeypatch) -> None:
    whole = tmp_path / "whole"
    sb3.train_sb3(PPO, whole, **PPO_SETTINGS)
    cut = tmp_path / "cut"
    _stop_at(monkeypatch, 200)  # mid-rollout: the checkpoint is at the next one's start
    try:
        with pytest.raises(Stopped):
            sb3.train_sb3(PPO, cut, **PPO_SETTINGS)
    finally:
        clear_stop()
    monkeypatch.undo()
    assert _steps(cut / CHECKPOINT) == 256 and not (cut / MODEL).exists()
    _refusals(cut, tmp_path)
    torch.manual_seed(5)  # what ran between the two must not matter
    sb3.train_sb3(PPO, cut, resume=True, **PPO_SETTINGS)
    assert not (cut / CHECKPOINT).exists()
    _assert_identical(_saved(cut), _saved(whole))
    assert _curve(cut) == _curve(whole)


def _refusals(cut: Path, tmp_path: Path) -> None:
    """Each way a checkpoint is refused, on copies of ``cut``."""
    with pytest.raises(RunRefused, match=r"checkpoint\.pt exists; allowed: resume=True"):
        sb3.train_sb3(PPO, cut, **PPO_SETTINGS)
    with pytest.raises(RunRefused, match=r"another training \(differs in: configs, seed\)"):
        sb3.train_sb3(replace(PPO, seed=1), cut, resume=True, **PPO_SETTINGS)
    with pytest.raises(RunRefused, match=r"another training \(differs in: configs\)"):
        sb3.train_sb3(PPO, cut, resume=True, **{**PPO_SETTINGS, "n_epochs": 3})
    # another checkpoint interval is the same training
    edited = tmp_path / "edited"
    shutil.copytree(cut, edited)
    payload = torch.load(edited / CHECKPOINT, weights_only=True)
    payload["model"]["last_obs"][0, 0] += 1.0
    torch.save(payload, edited / CHECKPOINT)
    with pytest.raises(RunRefused, match="do not replay to the observations it holds"):
        sb3.train_sb3(replace(PPO, checkpoint_every=1), edited, resume=True, **PPO_SETTINGS)
    (edited / CHECKPOINT).write_bytes(b"half a checkpoint")
    with pytest.raises(RunRefused, match=r"not a readable torch checkpoint.*start the training"):
        sb3.train_sb3(PPO, edited, resume=True, **PPO_SETTINGS)


def test_a_diverged_training_is_refused_and_writes_no_model(tmp_path) -> None:
    config = Sb3Config(
        "sac", "tolins/Circle2x2-v1", backend="kinematic", env_steps=40, curve_every=40,
        curve_episodes=1,
    )  # fmt: skip
    with pytest.raises(RunRefused, match=r"sac diverged: weights not all finite after \d+ env"):
        sb3.train_sb3(config, tmp_path, learning_starts=10, learning_rate=1e30)
    assert not (tmp_path / MODEL).exists() and not (tmp_path / CHECKPOINT).exists()


# --- tolins train: refusals and bugs ----------------------------------------------------


def test_tolins_train_reports_a_refusal_in_one_line_with_status_3(tmp_path, monkeypatch, capsys):
    from tolins.cli import main
    from tolins.learning.imitation import runs

    def refuse(*_args, **_kwargs):
        raise RunRefused("behaviour cloning diverged: loss nan at epoch 3; allowed: a smaller")

    argv = ["train", "bc", "--env", "tolins/Circle2x2-v1", "--out", str(tmp_path / "bc")]
    monkeypatch.setattr(runs, "run_bc", refuse)
    assert main(argv) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["tolins train bc: behaviour cloning diverged: loss nan at epoch 3; allowed: "
                   "a smaller"]  # fmt: skip

    def bug(*_args, **_kwargs):
        raise ValueError("a bug, not an option")

    monkeypatch.setattr(runs, "run_bc", bug)
    with pytest.raises(ValueError, match="a bug, not an option"):
        main(argv)


def test_tolins_train_checks_the_init_policy_file_as_an_option(tmp_path, capsys) -> None:
    from tolins.cli import main

    init = tmp_path / "init.pt"
    init.write_bytes(b"not a policy")
    argv = ["train", "rs-gail", "--env", "tolins/Circle2x2-v1", "--init", str(init)]
    assert main([*argv, "--out", str(tmp_path / "rs")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"tolins train rs-gail: --init: {init} is not a readable torch"), err
    assert not (tmp_path / "rs").exists()
