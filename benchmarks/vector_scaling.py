"""Scaling of the batched vector env: steps/s against N, threads and processes;
SB3 PPO wall time with 1 and 8 envs; the step cost of Meta-World's ``peg-insert-side-v3``.

Usage::

    python benchmarks/vector_scaling.py                    # full run, ~26 min on 2 cores
    python benchmarks/vector_scaling.py --quick            # ~11 s of CPU, a smoke test
    python benchmarks/vector_scaling.py --ppo-steps 51200 --no-metaworld

What it measures, all in one run. Every figure is timed by blocks: a block resets (untimed)
and then steps a fixed number of control steps; the configurations being compared run
their blocks in turn, ``--repeats`` rounds, and the fastest block of each is kept, so a
slow moment of a shared machine hits all alike and drops out. Steps/s are env-steps summed
over the envs (one env-step = one 0.25 s control step = 250 MuJoCo steps of 1 ms).

1. **Throughput against N.** For N in ``--envs`` (1, 2, 4, 8, 16, 64), on the 2*2 socket
   (``tolins/Circle2x2-v1``) and, in contact, the 2*8 socket (``tolins/Circle2x8-v1``),
   both backends and two regimes, ``free`` (pose ``[0, 0, 0, 10]``, ``ux = uy = ±2.5``
   alternating: in the air, no contact) and ``contact`` (pose ``[1.0, 0, 0, 0.05]``, pins on
   the board 1 mm beside their holes, ``uz = -2.5``: blocked, pushing at the force limit),
   with ``horizon`` = 10^6 so that no episode ends in a block:

   * ``vec t=1`` / ``vec t=K``: :func:`tolins.make_vec` (``autoreset_mode="Disabled"``),
     MuJoCo with ``num_threads`` = 1 and = K, every core of the machine; the kinematic
     backend's vector env is one numpy batch (``vec``);
   * ``pool``: N single envs (``gymnasium.make(id, backend=...)``) split into two groups,
     each group stepped by one thread of a 2-thread ``ThreadPoolExecutor`` per control step
     (``mj_step`` releases the GIL);
   * ``async``: gymnasium's ``AsyncVectorEnv`` of N single envs, one process each
     (``forkserver``: forking this multithreaded process can hang a worker), for
     N <= ``--async-max`` (16): more processes than that on 2 cores only add switching.

2. **Threads model** (what a 16- or 64-core machine gives). ``mujoco.batch`` splits the N
   simulations among its threads, so speed-up(threads) ≈ min(threads, N) × e, with e the
   per-thread efficiency. Checked here by the measured ``t=K / t=1`` ratio of the table
   above at N = 2, 16, 64; the 16- and 64-core figures are that model, not measurements.

3. **PPO wall time.** SB3 PPO (``tolins.learning.agents.sb3.make_model``, SB3 defaults, dense
   reward) on MuJoCo 2*2 with ``n_envs`` = 1 and 8 to ``--ppo-steps`` env steps, ``n_steps``
   = 2048 / n_envs so that every update sees the same 2,048 env steps and does the same
   gradient work; the two trainings alternate in chunks of 2 updates (torch on one thread).

4. **Meta-World.** ``peg-insert-side-v3`` (``gymnasium.make("Meta-World/MT1",
   env_name=...)``, its scripted policy) in a virtual environment of its own,
   ``benchmarks/.venv-metaworld`` (``metaworld==3.1.1`` pins ``mujoco==3.3.0``; built on
   first use with ``python -m venv`` and pip), driven as a subprocess block by block in
   turn with a single tolins env (2*2, free and contact). Only ``env.step`` is timed on
   both sides. Ratios per env step, per simulated second and per MuJoCo step.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import datetime
import functools
import json
import multiprocessing
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import mujoco
import numpy as np

import tolins

HORIZON = 10**6
CONTROL_DT = 0.25
MJ_STEPS = 250  # MuJoCo steps of 1 ms per control step
CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
POOL_THREADS = 2
IDS = {"2*2": "tolins/Circle2x2-v1", "2*8": "tolins/Circle2x8-v1"}
POSES = {"free": [0.0, 0.0, 0.0, 10.0], "contact": [1.0, 0.0, 0.0, 0.05]}
#: Env-steps per block (summed over envs), per backend and regime, for the 2*2 socket.
BLOCK_ENV_STEPS = {
    ("mujoco", "free"): 128,
    ("mujoco", "contact"): 32,
    ("kinematic", "free"): 512,
    ("kinematic", "contact"): 256,
}
VENV = Path(__file__).resolve().parent / ".venv-metaworld"
#: gymnasium's mujoco envs import ``packaging`` without declaring it.
METAWORLD = ("metaworld==3.1.1", "packaging")


def actions(regime: str, n: int, k: int) -> np.ndarray:
    """Actions ``(n, 4)`` of control step ``k``: lateral back and forth, or pushing down."""
    if regime == "free":
        sign = 1.0 if k % 2 == 0 else -1.0
        return np.tile([2.5 * sign, 2.5 * sign, 0.0, 0.0], (n, 1))
    return np.tile([0.0, 0.0, 0.0, -2.5], (n, 1))


# ---------------------------------------------------------------------------------------
# Ways to step N envs; each has reset(pose), step(actions (n, 4)) -> poses (n, 4), close().
# ---------------------------------------------------------------------------------------


class Vector:
    """The native vector env."""

    def __init__(self, env_id: str, n: int, backend: str, threads: int | None) -> None:
        kwargs = {"num_threads": threads} if backend == "mujoco" else {}
        self.env = tolins.make_vec(
            env_id, n, backend=backend, autoreset_mode="Disabled", horizon=HORIZON, **kwargs
        )
        self.physics_cpu = 0.0  # CPU seconds inside the batched physics step since reset
        self._physics_step = self.env.unwrapped.physics.step
        self.env.unwrapped.physics.step = self._timed_physics_step

    def _timed_physics_step(self, *args):
        begin = time.process_time()
        out = self._physics_step(*args)
        self.physics_cpu += time.process_time() - begin
        return out

    def reset(self, pose) -> None:
        self.env.reset(seed=0, options={"pose": pose})
        self.physics_cpu = 0.0

    def step(self, a: np.ndarray) -> np.ndarray:
        return self.env.step(a)[0][:, :4]

    def close(self) -> None:
        self.env.close()


class Pool:
    """N single envs in two groups, each stepped by one thread of a thread pool."""

    def __init__(self, env_id: str, n: int, backend: str) -> None:
        self.envs = [gym.make(env_id, backend=backend, horizon=HORIZON) for _ in range(n)]
        self.groups = np.array_split(np.arange(n), min(POOL_THREADS, n))
        self.executor = concurrent.futures.ThreadPoolExecutor(POOL_THREADS)

    def reset(self, pose) -> None:
        for i, env in enumerate(self.envs):
            env.reset(seed=i, options={"pose": pose})

    def _step_group(self, group: np.ndarray, a: np.ndarray) -> list[np.ndarray]:
        return [self.envs[i].step(a[i])[0][:4] for i in group]

    def step(self, a: np.ndarray) -> np.ndarray:
        futures = [self.executor.submit(self._step_group, g, a) for g in self.groups]
        return np.array([obs for f in futures for obs in f.result()])

    def close(self) -> None:
        self.executor.shutdown()
        for env in self.envs:
            env.close()


def _single(env_id: str, backend: str) -> gym.Env:
    import tolins  # noqa: F401  (registers the ids in the worker)

    return gym.make(env_id, backend=backend, horizon=HORIZON)


class Async:
    """gymnasium's ``AsyncVectorEnv`` of N single envs (one process each)."""

    def __init__(self, env_id: str, n: int, backend: str) -> None:
        self.env = gym.vector.AsyncVectorEnv(
            [functools.partial(_single, env_id, backend)] * n, context="forkserver"
        )

    def reset(self, pose) -> None:
        self.env.reset(seed=0, options={"pose": pose})

    def step(self, a: np.ndarray) -> np.ndarray:
        return self.env.step(a)[0][:, :4]

    def close(self) -> None:
        self.env.close()


def block(runner, regime: str, pose, steps: int, n: int) -> tuple[float, float, np.ndarray]:
    """Wall and process CPU seconds of ``steps`` control steps from a reset (excluded); the
    last poses."""
    runner.reset(pose)
    plan = [actions(regime, n, k) for k in range(steps)]
    begin, cpu = time.perf_counter(), time.process_time()
    for a in plan:
        poses = runner.step(a)
    return time.perf_counter() - begin, time.process_time() - cpu, poses


def best_of(runners: dict, regime: str, pose, steps: int, n: int, repeats: int) -> dict:
    """Steps/s of each runner (fastest of ``repeats`` blocks, the runners in turn), and for
    the vector envs ``name:cpu`` (fewest CPU seconds per env-step), ``name:share`` (CPU/wall
    of the fastest block: cores' worth the process got) and ``name:serial`` (share of the
    CPU spent outside the batched physics step)."""
    best = {name: (np.inf, np.inf) for name in runners}
    least_cpu = {name: (np.inf, 0.0) for name in runners}
    for _ in range(repeats):
        for name, runner in runners.items():
            wall, cpu, poses = block(runner, regime, pose, steps, n)
            check_regime(regime, poses, name)
            best[name] = min(best[name], (wall, cpu))
            least_cpu[name] = min(least_cpu[name], (cpu, getattr(runner, "physics_cpu", 0.0)))
    out = {name: n * steps / wall for name, (wall, _) in best.items()}
    for name in (name for name, runner in runners.items() if isinstance(runner, Vector)):
        cpu, physics = least_cpu[name]
        out[f"{name}:cpu"] = cpu / (n * steps)
        out[f"{name}:share"] = best[name][1] / best[name][0]
        out[f"{name}:serial"] = 1.0 - physics / cpu
    return out


def check_regime(regime: str, poses: np.ndarray, name: str) -> None:
    """Free stays in the air, contact stays blocked on the board (noisy observations)."""
    z = float(np.mean(poses[:, 3]))
    ok = z > 5.0 if regime == "free" else -0.5 < z < 0.5
    if not ok:
        raise RuntimeError(f"{name}: {regime} block ended at mean z = {z:.3f} mm")


# ---------------------------------------------------------------------------------------
# 1. Throughput against N
# ---------------------------------------------------------------------------------------


def configurations(env_id: str, n: int, backend: str, async_max: int) -> dict:
    """The runners compared at one (socket, backend, N); async first (before threads)."""
    runners = {}
    if n <= async_max:
        runners["async"] = Async(env_id, n, backend)
    if backend == "mujoco":
        runners["vec t=1"] = Vector(env_id, n, backend, 1)
        runners[f"vec t={CORES}"] = Vector(env_id, n, backend, CORES)
    else:
        runners["vec"] = Vector(env_id, n, backend, None)
    runners["pool"] = Pool(env_id, n, backend)
    return runners


def throughput(cases: list[tuple[str, str, str, list[int]]], args) -> list[dict]:
    rows = []
    for socket, backend, regime, ns in cases:
        for n in ns:
            runners = configurations(IDS[socket], n, backend, args.async_max)
            per_block = BLOCK_ENV_STEPS[backend, regime] * args.scale
            if socket != "2*2":
                per_block /= 4
            steps = max(args.min_steps, int(np.ceil(per_block / n)))
            rates = best_of(runners, regime, POSES[regime], steps, n, args.repeats)
            for runner in runners.values():
                runner.close()
            rows.append({"socket": socket, "backend": backend, "regime": regime, "n": n, **rates})
            print_row(rows[-1], steps)
    return rows


def _fmt(x: float | None, ratio: bool = False) -> str:
    if x is None:
        return "–"
    return f"{x:.2f}" if ratio else f"{x:,.0f}"


def print_header(backend: str) -> None:
    vec = f"vec t=1 | vec t={CORES}" if backend == "mujoco" else "vec"
    cols = f"| socket | regime | N | steps | {vec} | pool | async | vec / pool | vec / async |"
    if backend == "mujoco":
        cols += f" t={CORES} / t=1 |"
    print(f"\n**{backend}**, steps/s (env-steps summed over envs), best of blocks:\n", flush=True)
    print(cols)
    print("|" + "---|" * (cols.count("|") - 1), flush=True)


def print_row(row: dict, steps: int) -> None:
    mujoco_ = row["backend"] == "mujoco"
    vec = row[f"vec t={CORES}"] if mujoco_ else row["vec"]
    cells = [row["socket"], row["regime"], str(row["n"]), str(steps)]
    cells += [_fmt(row["vec t=1"]), _fmt(vec)] if mujoco_ else [_fmt(vec)]
    cells += [_fmt(row["pool"]), _fmt(row.get("async"))]
    cells += [_fmt(vec / row["pool"], True)]
    cells += [_fmt(vec / row["async"], True) if "async" in row else "–"]
    if mujoco_:
        cells += [_fmt(vec / row["vec t=1"], True)]
    print("| " + " | ".join(cells) + " |", flush=True)


# ---------------------------------------------------------------------------------------
# 2. Threads model
# ---------------------------------------------------------------------------------------


def threads_model(rows: list[dict]) -> None:
    """Measured t=K/t=1 and the model's speed-up on idle 2-, 16- and 64-core machines."""
    if not rows:
        return
    k = f"vec t={CORES}"
    print(
        "\n**Threads model**: `mujoco.batch` splits the N simulations among its threads, "
        "so on idle cores speed-up ≈ min(threads, N) × e. Here e = w × (Amdahl factor of "
        "the serial Python share s): w = CPU per env-step at t=1 / at t="
        f"{CORES} (threading overhead), s = share of t=1 CPU outside the batched physics "
        "step. Modelled speed-up(K) = 1 / (s + (1 − s) / (min(K, N) · w)); modelled "
        "steps/s = speed-up × 1 / (CPU s per env-step at t=1), i.e. a dedicated core. "
        "`share` = CPU s / wall s of the process in its fastest block (cores' worth it got "
        f"from the shared machine): wall t={CORES}/t=1 can only reach the model where the "
        f"t={CORES} share is near {CORES}. Model columns are not measurements.\n"
    )
    print(
        f"| socket | regime | N | wall t={CORES} / t=1 | share t=1 | share t={CORES} | w "
        f"| s | model ×{CORES} | steps/s per core | 16 cores (model) | 64 cores (model) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in (r for r in rows if r["backend"] == "mujoco"):
        n, w, serial = r["n"], r["vec t=1:cpu"] / r[f"{k}:cpu"], r["vec t=1:serial"]
        per_core = 1.0 / r["vec t=1:cpu"]

        def model(cores: int, n=n, w=w, serial=serial) -> float:
            return 1.0 / (serial + (1.0 - serial) / (min(cores, n) * (w if n > 1 else 1.0)))

        cells = [r["socket"], r["regime"], str(n), _fmt(r[k] / r["vec t=1"], True)]
        cells += [_fmt(r["vec t=1:share"], True), _fmt(r[f"{k}:share"], True)]
        cells += [_fmt(w, True), _fmt(serial, True), _fmt(model(CORES), True)]
        cells += [_fmt(per_core)] + [_fmt(per_core * model(c)) for c in (16, 64)]
        print("| " + " | ".join(cells) + " |", flush=True)


# ---------------------------------------------------------------------------------------
# 3. PPO wall time
# ---------------------------------------------------------------------------------------


def ppo(budget: int, rollout: int, n_envs: tuple[int, ...]) -> None:
    from tolins.learning.agents.sb3 import make_model
    from tolins.learning.agents.sb3_config import Sb3Config
    from tolins.learning.artefacts import single_threaded_torch

    models, seconds, grad = {}, dict.fromkeys(n_envs, 0.0), dict.fromkeys(n_envs, 0.0)
    for n in n_envs:
        config = Sb3Config("ppo", IDS["2*2"], backend="mujoco", env_steps=budget, n_envs=n)
        models[n] = make_model(config, n_steps=rollout // n, batch_size=min(64, rollout))
        models[n].train = _timed(models[n].train, grad, n)
    chunk = 2 * rollout
    with single_threaded_torch():
        while any(m.num_timesteps < budget for m in models.values()):
            for n, model in models.items():
                if model.num_timesteps < budget:
                    begin = time.perf_counter()
                    todo = min(chunk, budget - model.num_timesteps)
                    model.learn(todo, reset_num_timesteps=False)
                    seconds[n] += time.perf_counter() - begin
    print(f"\n**SB3 PPO**, MuJoCo 2*2, {rollout} env steps per update, chunks alternating:\n")
    print("| n_envs | n_steps | env steps | wall s | of which updates s | env steps/s | speed-up |")
    print("|---|---|---|---|---|---|---|")
    for n, model in models.items():
        cells = [str(n), str(rollout // n), f"{model.num_timesteps:,}", f"{seconds[n]:.1f}"]
        cells += [f"{grad[n]:.1f}", _fmt(model.num_timesteps / seconds[n])]
        cells += [_fmt(seconds[n_envs[0]] / seconds[n], True)]
        print("| " + " | ".join(cells) + " |", flush=True)


def _timed(train, totals: dict, key):
    def timed_train(*args, **kwargs):
        begin = time.perf_counter()
        train(*args, **kwargs)
        totals[key] += time.perf_counter() - begin

    return timed_train


# ---------------------------------------------------------------------------------------
# 4. Meta-World
# ---------------------------------------------------------------------------------------

CHILD = r"""
import json, sys, time, warnings
warnings.filterwarnings("ignore")
import gymnasium as gym, metaworld, mujoco, numpy as np
from importlib.metadata import version
env = gym.make("Meta-World/MT1", env_name="peg-insert-side-v3", seed=0)
u = env.unwrapped
from metaworld.policies import SawyerPegInsertionSideV3Policy
policy = SawyerPegInsertionSideV3Policy()
print(json.dumps({"mujoco": mujoco.__version__, "metaworld": version("metaworld"),
                  "dt": float(u.dt), "timestep": float(u.model.opt.timestep),
                  "frame_skip": int(u.frame_skip)}), flush=True)
successes, blocks = 0, 0
for line in sys.stdin:  # one block: up to that many steps of one episode from a reset
    obs, _ = env.reset(seed=blocks)
    elapsed, ncon, steps, success = 0.0, 0, 0, 0.0
    for _ in range(int(line)):
        action = np.clip(policy.get_action(obs), -1, 1)
        begin = time.perf_counter()
        obs, reward, terminated, truncated, info = env.step(action)
        elapsed += time.perf_counter() - begin
        ncon, steps = ncon + u.data.ncon, steps + 1
        success = max(success, float(info.get("success", 0.0)))
        if terminated or truncated:
            break
    successes, blocks = successes + int(success > 0), blocks + 1
    print(json.dumps({"seconds": elapsed, "steps": steps, "ncon": ncon / steps,
                      "successes": successes, "blocks": blocks}), flush=True)
"""


def metaworld_python(build: bool) -> Path | None:
    """The venv's interpreter with Meta-World installed; built first if ``build``."""
    python = VENV / "bin" / "python"
    probe = [str(python), "-c", "import metaworld"]
    if python.exists() and subprocess.run(probe, capture_output=True).returncode == 0:
        return python
    if not build:
        return None
    print(f"building {VENV} ({' '.join(METAWORLD)}) ...", flush=True)
    base = getattr(sys, "_base_executable", sys.executable)
    subprocess.run([base, "-m", "venv", str(VENV)], check=True)
    subprocess.run([str(python), "-m", "pip", "install", "-q", *METAWORLD], check=True)
    return python


def metaworld(python: Path, scale: float, repeats: int) -> None:
    """Blocks of one tolins env (free, contact) and of Meta-World's episode, in turn."""
    child = subprocess.Popen(
        [str(python), "-c", CHILD],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "OMP_NUM_THREADS": "1"},
    )
    facts = json.loads(child.stdout.readline())
    ours = {r: Vector(IDS["2*2"], 1, "mujoco", 1) for r in POSES}
    steps = {r: max(2, int(BLOCK_ENV_STEPS["mujoco", r] * scale / 4)) for r in POSES}
    steps["metaworld"] = max(10, int(500 * scale))  # one whole episode (500 steps)
    best = dict.fromkeys(steps, np.inf)
    for _ in range(repeats):
        for regime, runner in ours.items():
            seconds = block(runner, regime, POSES[regime], steps[regime], 1)[0]
            best[regime] = min(best[regime], seconds)
        child.stdin.write(f"{steps['metaworld']}\n")
        child.stdin.flush()
        report = json.loads(child.stdout.readline())
        best["metaworld"] = min(best["metaworld"], report["seconds"] / report["steps"])
    child.stdin.close()
    child.wait()
    rate = {r: steps[r] / best[r] for r in POSES} | {"metaworld": 1.0 / best["metaworld"]}
    sim_dt = {"free": CONTROL_DT, "contact": CONTROL_DT, "metaworld": facts["dt"]}
    mj = {"free": MJ_STEPS, "contact": MJ_STEPS, "metaworld": facts["frame_skip"]}
    print(
        f"\n**Meta-World peg-insert-side-v3** (metaworld {facts['metaworld']}, MuJoCo "
        f"{facts['mujoco']}, timestep {facts['timestep'] * 1e3:g} ms × frame_skip "
        f"{facts['frame_skip']} = {facts['dt'] * 1e3:g} ms per env step; blocks of one "
        f"{report['steps']}-step episode of its scripted policy, {report['ncon']:.1f} "
        f"contacts per step in the last, success in {report['successes']} of "
        f"{report['blocks']}) against one tolins env (2*2, MuJoCo {mujoco.__version__}, "
        f"1 thread; blocks of {steps['free']} free, {steps['contact']} contact steps), "
        f"best of {repeats}, in turn:\n"
    )
    print(
        "| env | env steps/s | simulated s per s | µs per MuJoCo step | "
        "cost per env step / MW | cost per simulated s / MW |"
    )
    print("|---|---|---|---|---|---|")
    for name in ("metaworld", "free", "contact"):
        label = "Meta-World peg-insert-side" if name == "metaworld" else f"tolins 2*2 {name}"
        cells = [label, _fmt(rate[name]), f"{rate[name] * sim_dt[name]:.1f}"]
        cells += [f"{1e6 / (rate[name] * mj[name]):.1f}"]
        cells += [_fmt(rate["metaworld"] / rate[name], True)]
        sim = (rate["metaworld"] * sim_dt["metaworld"]) / (rate[name] * sim_dt[name])
        cells += [_fmt(sim, True)]
        print("| " + " | ".join(cells) + " |", flush=True)
    for runner in ours.values():
        runner.close()


# ---------------------------------------------------------------------------------------


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return f"{CORES} cores ({os.cpu_count()} online), {cpu}, load average {load:.1f}"


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a smoke test (~11 s of CPU)")
    parser.add_argument("--envs", default="1,2,4,8,16,64", help="the Ns of the 2*2 socket")
    parser.add_argument("--envs-2x8", default="1,16", help="the Ns of the 2*8 socket")
    parser.add_argument("--backends", default="mujoco,kinematic", help="backends of part 1")
    parser.add_argument("--repeats", type=int, default=3, help="blocks per configuration")
    parser.add_argument("--scale", type=float, default=1.0, help="block length multiplier")
    parser.add_argument("--min-steps", type=int, default=3, help="fewest steps in a block")
    parser.add_argument("--async-max", type=int, default=16, help="largest N for async")
    parser.add_argument("--ppo-steps", type=int, default=100_000, help="0: no PPO")
    parser.add_argument("--ppo-rollout", type=int, default=2048, help="env steps per update")
    parser.add_argument("--no-metaworld", action="store_true")
    args = parser.parse_args()
    if args.quick:
        args.envs, args.envs_2x8, args.repeats, args.scale, args.min_steps = "2", "", 1, 0.05, 2
        args.async_max = min(args.async_max, 2)
        args.ppo_steps, args.ppo_rollout = 64, 32
    return args


def main() -> None:
    args = parse()
    # AsyncVectorEnv's workers fork from a single-threaded server with these loaded: a fork
    # of this process (batch and pool threads alive) can inherit a held lock and hang.
    multiprocessing.set_forkserver_preload(["tolins", "gymnasium", "mujoco", "numpy"])
    began = time.perf_counter()
    ns = [int(n) for n in args.envs.split(",") if n]
    ns_2x8 = [int(n) for n in args.envs_2x8.split(",") if n]
    print(
        f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; {machine()}; Python "
        f"{platform.python_version()}, MuJoCo {mujoco.__version__}, gymnasium "
        f"{gym.__version__}, tolins {tolins.__version__}; `{' '.join(sys.argv[1:])}`",
        flush=True,
    )
    mujoco_rows: list[dict] = []
    for backend in args.backends.split(","):
        print_header(backend)
        cases = [("2*2", backend, regime, ns) for regime in ("free", "contact")]
        if ns_2x8:
            cases.append(("2*8", backend, "contact", ns_2x8))
        rows = throughput(cases, args)
        if backend == "mujoco":
            mujoco_rows = rows
    threads_model(mujoco_rows)
    if args.ppo_steps:
        ppo(args.ppo_steps, args.ppo_rollout, (1, 8))
    python = None if args.no_metaworld else metaworld_python(build=not args.quick)
    if python is not None:
        metaworld(python, args.scale, max(3, 2 * args.repeats))
    elif not args.no_metaworld:
        print(f"\nMeta-World skipped: no {VENV.name} (a full run builds it)")
    print(f"\nwall time {time.perf_counter() - began:.0f} s; {machine()}", flush=True)


if __name__ == "__main__":
    main()
