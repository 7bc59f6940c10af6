"""What a deep-RL training's checkpoint costs (size and seconds to write, seconds to
resume), and a paper-profile SAC stage killed with SIGKILL against an uninterrupted one.

Usage::

    python benchmarks/sb3_checkpoint.py                     # paper-profile SAC and PPO
    python benchmarks/sb3_checkpoint.py sac --steps 1500 --fills 14400,144000,288000
    python benchmarks/sb3_checkpoint.py --kill --steps 4000 --every 1500 --after 5

Each algorithm's paper-profile stage config (``Profile.sb3``: SAC 64×64 on one env, PPO on
8) on ``--env`` trains ``--steps`` real env steps (SAC: 1,000 of them random, then a
gradient step each), then its checkpoint (:mod:`tolins.learning.agents.sb3_checkpoint`) is
written ``--repeats`` times (median seconds) and read back into a new model (the resume:
the model made, its envs replayed). For SAC the replay buffer's fill is then set to each of
``--fills`` transitions (the real ones first, the rest as allocated: the file's size and
cost do not depend on the values) to give the checkpoints of a longer training.

``--kill`` runs the bench's stage of R1.2 (SAC, sparse reward, 2*2, paper profile) with its
budget cut to ``--steps`` env steps and a checkpoint every ``--every``: once uninterrupted,
once in a process of its own killed with SIGKILL ``--after`` seconds after its first
checkpoint and then run again in the same folder (as a rerun of the bench does); it prints
where the kill left the training and whether both end with the same weights, optimiser
states and curve, bit for bit.
"""

from __future__ import annotations

import argparse
import io
import os
import pickle
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import replace
from pathlib import Path

import torch

import tolins  # noqa: F401  (registers the envs)
from tolins.bench.jobs.training import train_job, training_stage
from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.pipeline.settings import training_spec
from tolins.bench.table.rows import CIRCLE_2X2
from tolins.learning.agents.sb3 import checkpoint_metadata, make_model
from tolins.learning.agents.sb3_checkpoint import load_checkpoint, save_checkpoint
from tolins.learning.agents.sb3_config import CHECKPOINT, CURVES, MODEL
from tolins.learning.artefacts import single_threaded_torch


def _write(path: Path, model, metadata: dict, repeats: int) -> tuple[float, int]:
    """Median seconds to write the checkpoint, and its size (bytes)."""
    loop = {"history": [], "learning_s": 0.0, "wall_s": 0.0, "target": None}
    seconds = []
    for _ in range(repeats):
        began = time.perf_counter()
        save_checkpoint(path, model, metadata, loop)
        seconds.append(time.perf_counter() - began)
    return statistics.median(seconds), path.stat().st_size


def _resume(path: Path, config, metadata: dict) -> float:
    """Seconds to make a new model and read the checkpoint into it."""
    began = time.perf_counter()
    model = make_model(config)
    load_checkpoint(path, model, metadata)
    seconds = time.perf_counter() - began
    model.env.close()
    return seconds


def measure(algorithm: str, args: argparse.Namespace, folder: Path) -> None:
    config = PROFILES["paper"].sb3(algorithm, args.env, args.backend, 0, "sparse")
    metadata = checkpoint_metadata(config, {})
    model = make_model(config)
    path = folder / f"{algorithm}.pt"
    with single_threaded_torch():
        began = time.perf_counter()
        model.learn(args.steps)
        rate = model.num_timesteps / (time.perf_counter() - began)
        print(
            f"{algorithm} on {args.env} ({args.backend}, {config.n_envs} envs): "
            f"{model.num_timesteps} env steps at {rate:.0f} steps/s"
        )
        buffer = getattr(model, "replay_buffer", None)
        fills = [None] if buffer is None else [None, *args.fills]
        for fill in fills:
            if fill is not None:
                buffer.pos = max(fill, buffer.pos)
            seconds, size = _write(path, model, metadata, args.repeats)
            resume = _resume(path, config, metadata)
            held = "" if buffer is None else f", {buffer.pos:,} transitions"
            print(
                f"  checkpoint{held}: {size / 1e6:.1f} MB, written in {seconds:.2f} s, "
                f"resumed in {resume:.2f} s"
            )
    model.env.close()


_RUN = """
import pickle, sys
from pathlib import Path
from tolins.bench.jobs.training import train_job
train_job(Path(sys.argv[2]), pickle.loads(Path(sys.argv[1]).read_bytes()), None, False, None)
"""


def _saved(folder: Path) -> dict:
    """The torch files of the folder's SB3 zip (weights, optimisers, SAC's α)."""
    with zipfile.ZipFile(folder / MODEL) as archive:
        names = [n for n in archive.namelist() if n.endswith(".pth")]
        return {n: torch.load(io.BytesIO(archive.read(n)), weights_only=True) for n in names}


def _same(a, b) -> bool:
    if isinstance(a, torch.Tensor):
        return torch.equal(a, b)
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


def _curve(folder: Path) -> list[str]:
    """The curve's rows without their timings (the last two columns)."""
    lines = (folder / CURVES).read_text().splitlines()
    return [",".join(line.split(",")[:-2]) for line in lines]


def kill(args: argparse.Namespace, root: Path) -> None:
    spec = training_spec("sac_circle_sparse", 0, PROFILES["paper"], args.backend)
    budget = {"env_steps": args.steps, "curve_every": args.steps // 2}
    sb3 = replace(spec.sb3, **budget, checkpoint_every=args.every)
    stage = training_stage(replace(spec, sb3=sb3), None)
    began = time.perf_counter()
    whole = train_job(root / "whole", stage, None, False, None).parent
    print(f"uninterrupted: {time.perf_counter() - began:.0f} s")
    cut = root / "cut"
    folder = cut / "stages" / whole.name
    pickled = root / "stage.pickle"
    pickled.write_bytes(pickle.dumps(stage))
    process = subprocess.Popen([sys.executable, "-c", _RUN, str(pickled), str(cut)])
    while not (folder / CHECKPOINT).exists() and process.poll() is None:
        time.sleep(0.2)
    time.sleep(args.after)
    os.kill(process.pid, signal.SIGKILL)
    process.wait()
    from tolins.learning.agents.sb3_checkpoint import FORMAT
    from tolins.learning.artefacts import load_payload

    payload = load_payload(folder / CHECKPOINT, FORMAT)
    print(
        f"killed (status {process.returncode}) {args.after} s after the first checkpoint; "
        f"checkpoint at {payload['model']['counters']['num_timesteps']} env steps, "
        f"{len(payload['loop']['history'])} curve points"
    )
    began = time.perf_counter()
    train_job(cut, stage, None, False, None)
    print(f"run again: {time.perf_counter() - began:.0f} s")
    print(
        f"same weights and optimiser states: {_same(_saved(folder), _saved(whole))}; "
        f"same curve: {_curve(folder) == _curve(whole)}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("algorithms", nargs="*", default=["sac", "ppo"])
    parser.add_argument("--env", default=CIRCLE_2X2)
    parser.add_argument("--backend", choices=("mujoco", "kinematic"), default="mujoco")
    parser.add_argument("--steps", type=int, default=2048, help="real env steps first")
    parser.add_argument(
        "--fills",
        type=lambda text: [int(x) for x in text.split(",")],
        default=[72_000, 144_000, 288_000],
        help="SAC replay-buffer fills to write (comma-separated)",
    )
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--kill", action="store_true", help="kill a SAC stage, resume, compare")
    parser.add_argument("--every", type=int, default=1500, help="--kill: checkpoint interval")
    parser.add_argument("--after", type=float, default=5.0, help="--kill: seconds, then kill")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        if args.kill:
            kill(args, Path(folder))
            return
        for algorithm in args.algorithms:
            measure(algorithm, args, Path(folder))


if __name__ == "__main__":
    main()
