"""Control-step throughput of ``InsertionEnv`` against a bare MuJoCo loop, and thread scaling.

Usage::

    python benchmarks/env_throughput.py            # full run, about 90 s on 2 cores
    python benchmarks/env_throughput.py --quick    # a few seconds, a smoke test
    python benchmarks/env_throughput.py --steps 20 --min-time 2
    python benchmarks/env_throughput.py --models-only   # part 2 alone
    python benchmarks/env_throughput.py --against a110726   # this tree against a revision

What it measures, all in one run:

1. **Env vs bare MuJoCo.** For each socket (circular 2*2, 2*8, 2*20; square; hexagon) and
   two regimes (``free``: in the air, moving slowly; ``contact``: pins pressed onto the
   board next to their holes), control steps per second of

   * ``env``: ``InsertionEnv(socket, measurement_noise=0).step(action)``;
   * ``bare``: the same model (``env.backend.model``) with a fresh ``mujoco.MjData``, the
     same start pose and the same controls; per control step the servos are re-anchored
     (``data.act[:] = data.qpos``) and five chunks of 50 physics steps run, each as 49
     ``mj_step`` with the sensors off and one with them on (:func:`bare_steps`), exactly
     what the backend does, minus everything else;
   * ``env cc=1``: the env with its backend replaced by
     ``MujocoBackend(socket, 0.25, contact_checks=1)`` (one contact-force read and one
     ``mj_step`` call per control step instead of 5).

   Timing is by blocks of ``--steps`` control steps (default 40 = one episode), each
   starting from a reset, so every block simulates the same trajectory; both loops also
   reset when an episode ends (truncation after ``horizon`` = 40 steps), and the time of
   resets is excluded from both. Blocks of env, bare and cc=1 run in turn (at least
   ``--repeats`` each, more for cheap cases until each variant has run ``--min-time``
   seconds) and the fastest block of each is kept: a slow period of a shared machine
   then hits all three alike and drops out. The ``match`` column checks that the bare
   loop ends at the same pose as the env, bit for bit.

2. **Eager vs lazy sensors**. For each socket and the five regimes of
   ``contact_profile.py`` (free, approaching, blocked, sliding, inserted), blocks of
   ``--steps`` control steps of the env's :class:`ServoStepper` alternate between
   ``old`` (sensors in every physics step: the eager-sensor step), ``new`` (today's default:
   sensors only in the physics step before each read) and ``pairs`` (new, on
   ``make_mjcf(socket, contact_pairs=True)``); the fastest block of each is kept.
   ``new x`` and ``pairs x`` = old time / their time (CPU time of the stepping thread,
   which other load disturbs less than the wall clock); ``same``: all three end at the
   same state bit for bit (qpos, qvel, sensordata).

3. **Threads.** ``--envs`` environments (2*2 socket) stepped ``--thread-steps`` control
   steps each, round-robin, by one thread, then the same envs split into ``--threads``
   disjoint groups stepped concurrently (``ThreadPoolExecutor``; ``mj_step`` releases
   the GIL). Resets are included in both timings here. Best of ``--repeats``.
   Speed-up = one-thread time / threaded time. The same work done by bare MuJoCo loops
   gives ``bare speed-up``: what the machine allows at that moment.

Targets: env/bare time ratio <= 1.10 everywhere; thread speed-up >= 1.6 (2 threads).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import math
import os
import platform
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from tolins import CircularSocket, PolygonSocket, make_mjcf
from tolins.envs import InsertionEnv
from tolins.physics.mujoco import MujocoBackend
from tolins.physics.servo import ServoStepper

sys.path.insert(0, str(Path(__file__).resolve().parent))
from contact_profile import REGIMES, SOCKETS
from contact_profile import regime as profile_regime

#: Action ``[ux, uy, utheta, uz]`` -> ctrl/qpos order (joints ``x, y, z, theta``).
ACTION_TO_JOINT = np.array([0, 1, 3, 2])

RATIO_TARGET = 1.10
SPEEDUP_TARGET = 1.6


@dataclass(frozen=True)
class Case:
    socket_name: str
    socket: object
    regime: str
    pose: np.ndarray  # [x, y, theta, z]
    action: np.ndarray  # [ux, uy, utheta, uz]


FREE_POSE = np.array([1.0, 1.0, 0.0, 15.0])
FREE_ACTION = np.array([0.1, 0.1, 0.0, -0.5])  # descends 5 mm in 40 steps: stays in the air
PUSH_ACTION = np.array([0.0, 0.0, 0.0, -2.5])


def sockets() -> list[tuple[str, object, np.ndarray]]:
    """(name, socket, blocked pose just above the board) for each benchmarked socket."""
    circle_block = np.array([0.5, 0.0, 0.0, 0.05])  # 0.5 mm off: outside the 0.2 mm clearance
    polygon_block = np.array([0.3, 0.0, 0.0, 0.05])
    return [
        ("2*2", CircularSocket(2, 2), circle_block),
        ("2*8", CircularSocket(2, 8), circle_block),
        ("2*20", CircularSocket(2, 20), circle_block),
        ("square", PolygonSocket(4, 1.5, 1.65), polygon_block),
        ("hexagon", PolygonSocket(6, 1.2, 1.26), polygon_block),
    ]


def cases() -> list[Case]:
    out = []
    for name, socket, block in sockets():
        out.append(Case(name, socket, "free", FREE_POSE, FREE_ACTION))
        out.append(Case(name, socket, "contact", block, PUSH_ACTION))
    return out


def make_env(socket, contact_checks: int | None = None) -> InsertionEnv:
    env = InsertionEnv(socket, measurement_noise=0)
    if contact_checks is not None:
        env.backend = MujocoBackend(socket, env.control_dt, contact_checks=contact_checks)
    return env


# ---------------------------------------------------------------------------------------
# Timed loops. Each returns (seconds spent stepping, excluding resets; extra facts).
# ---------------------------------------------------------------------------------------


def run_env(env: InsertionEnv, case: Case, steps: int) -> tuple[float, dict]:
    """``steps`` control steps of ``env``; resets (untimed) whenever an episode ends."""
    options = {"pose": case.pose}
    action = case.action
    step = env.step
    clock = time.perf_counter
    elapsed = 0.0
    collisions = 0
    errors = 0
    done = steps
    env.reset(options=options)
    while done > 0:
        # One episode (or the rest of the budget), timed as a block.
        n = 0
        t0 = clock()
        while done > 0:
            _, _, terminated, truncated, info = step(action)
            n += 1
            done -= 1
            collisions += info["collision"]
            if terminated or truncated:
                break
        elapsed += clock() - t0
        errors += "error" in info
        if done > 0:
            env.reset(options=options)
    return elapsed, {
        "collisions": collisions,
        "errors": errors,
        "last_pose": info["pose"],
    }


_SENSORS_OFF = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)


def bare_steps(model: mujoco.MjModel, data: mujoco.MjData, nstep: int, checks: int = 5) -> None:
    """One control step's physics as the backend runs it: ``checks`` chunks, each all but
    its last physics step with the sensors off (only the last one's are read)."""
    flags = model.opt.disableflags
    chunk = nstep // checks
    for _ in range(checks):
        model.opt.disableflags = flags | _SENSORS_OFF
        mujoco.mj_step(model, data, nstep=chunk - 1)
        model.opt.disableflags = flags
        mujoco.mj_step(model, data)


def bare_reset(model: mujoco.MjModel, data: mujoco.MjData, pose: np.ndarray) -> None:
    mujoco.mj_resetData(model, data)
    data.qpos[:] = pose[ACTION_TO_JOINT]
    data.act[:] = data.qpos
    mujoco.mj_forward(model, data)


def run_bare(
    model: mujoco.MjModel, data: mujoco.MjData, case: Case, steps: int, horizon: int, nstep: int
) -> tuple[float, dict]:
    """The same control loop with nothing but MuJoCo: act <- qpos, ctrl, one mj_step call."""
    ctrl = case.action[ACTION_TO_JOINT]
    pose = case.pose
    act, qpos, data_ctrl = data.act, data.qpos, data.ctrl
    clock = time.perf_counter
    elapsed = 0.0
    done = steps
    bare_reset(model, data, pose)
    while done > 0:
        n = min(horizon, done)
        t0 = clock()
        for _ in range(n):
            act[:] = qpos
            data_ctrl[:] = ctrl
            bare_steps(model, data, nstep)
        elapsed += clock() - t0
        done -= n
        if done > 0:
            bare_reset(model, data, pose)
    return elapsed, {"last_pose": qpos[ACTION_TO_JOINT].copy()}


# ---------------------------------------------------------------------------------------
# Part 1: env vs bare.
# ---------------------------------------------------------------------------------------


@dataclass
class Result:
    case: Case
    block: int  # control steps per timed block
    blocks: int  # timed blocks per variant
    env: float  # best (fastest) block, seconds per control step
    bare: float
    cc1: float
    collisions: int  # over all env blocks
    collisions_cc1: int
    errors: int
    match: bool

    @property
    def steps(self) -> int:
        return self.block * self.blocks


def measure_case(case: Case, block: int, repeats: int, min_time: float) -> Result:
    """Env, bare and cc=1 blocks of ``block`` control steps, interleaved; best block kept.

    Each block starts from a reset, so every block of every variant simulates the same
    trajectory. The variants run in turn (rotating who goes first), so a slow period
    of the machine hits all three alike; the fastest block of each is the estimate.
    """
    env = make_env(case.socket)
    env_cc1 = make_env(case.socket, contact_checks=1)
    model = env.backend.model
    data = mujoco.MjData(model)
    nstep = env.backend.substeps
    horizon = env.horizon

    # Warm-up: one block of each loop, also a first estimate of the cost of a block.
    t_env, _ = run_env(env, case, block)
    run_env(env_cc1, case, block)
    run_bare(model, data, case, block, horizon, nstep)
    # Cheap cases get more blocks, so that each variant runs at least min_time in all.
    blocks = max(repeats, math.ceil(min_time / t_env)) if t_env > 0 else repeats

    variants = {
        "env": lambda: run_env(env, case, block),
        "bare": lambda: run_bare(model, data, case, block, horizon, nstep),
        "cc1": lambda: run_env(env_cc1, case, block),
    }
    names = list(variants)
    best = dict.fromkeys(names, math.inf)
    facts: dict[str, dict] = {}
    collisions = dict.fromkeys(names, 0)
    errors = 0
    for i in range(blocks):
        for k in range(len(names)):
            name = names[(i + k) % len(names)]
            t, facts[name] = variants[name]()
            best[name] = min(best[name], t)
            collisions[name] += facts[name].get("collisions", 0)
            errors += facts[name].get("errors", 0)
    match = bool(np.array_equal(facts["env"]["last_pose"], facts["bare"]["last_pose"]))
    return Result(
        case=case,
        block=block,
        blocks=blocks,
        env=best["env"] / block,
        bare=best["bare"] / block,
        cc1=best["cc1"] / block,
        collisions=collisions["env"],
        collisions_cc1=collisions["cc1"],
        errors=errors,
        match=match,
    )


def print_results(results: list[Result]) -> None:
    header = (
        f"{'socket':<8} {'regime':<8} {'blocks':>6} {'env st/s':>9} {'bare st/s':>10} "
        f"{'env/bare':>9} {'ovh us':>7} {'cc=1 st/s':>10} {'cc1/bare':>9} "
        f"{'coll':>9} {'match':>6}"
    )
    print(header)
    print("-" * len(header))
    for r in results:
        ratio = r.env / r.bare
        ratio1 = r.cc1 / r.bare
        flag = " " if ratio <= RATIO_TARGET else "!"
        flag1 = " " if ratio1 <= RATIO_TARGET else "!"
        coll = f"{r.collisions}/{r.steps}"
        print(
            f"{r.case.socket_name:<8} {r.case.regime:<8} {r.blocks:>6} {1 / r.env:>9.0f} "
            f"{1 / r.bare:>10.0f} {ratio:>8.3f}{flag} {(r.env - r.bare) * 1e6:>7.1f} "
            f"{1 / r.cc1:>10.0f} {ratio1:>8.3f}{flag1} {coll:>9} {'yes' if r.match else 'NO':>6}"
        )
    print(
        "st/s: control steps per second (one control step = 250 physics steps of 1 ms); "
        "env/bare: time ratio;\n"
        "ovh us: env time minus bare time per control step (microseconds); "
        "cc=1: env with MujocoBackend(..., contact_checks=1);\n"
        "blocks: timed blocks per variant; coll: env steps with info['collision'] / all "
        "timed env steps;\nmatch: bare loop ends at the env's pose; !: above the target"
    )


def check_regimes(results: list[Result]) -> list[str]:
    problems = []
    for r in results:
        name = f"{r.case.socket_name} {r.case.regime}"
        if r.errors:
            problems.append(f"{name}: simulator errors during the run")
        if r.case.regime == "contact" and r.collisions != r.steps:
            problems.append(f"{name}: only {r.collisions}/{r.steps} steps were in contact")
        if r.case.regime == "free" and r.collisions:
            problems.append(f"{name}: {r.collisions} steps touched the board")
        if not r.match:
            problems.append(f"{name}: the bare loop did not reproduce the env's trajectory")
    return problems


# ---------------------------------------------------------------------------------------
# Part 2: old vs new model.
# ---------------------------------------------------------------------------------------


#: Part 2's variants: (contact_pairs, lazy_sensors).
VARIANTS = {"old": (False, False), "new": (False, True), "pairs": (True, True)}


def model_stepper(socket, contact_pairs: bool, lazy_sensors: bool) -> ServoStepper:
    """The env's control step on ``make_mjcf(socket, contact_pairs=...)``."""
    model = mujoco.MjModel.from_xml_string(make_mjcf(socket, contact_pairs=contact_pairs))
    stepper = ServoStepper(model, mujoco.MjData(model))
    stepper.lazy_sensors = lazy_sensors
    return stepper


def run_stepper(stepper: ServoStepper, pose, action, steps: int) -> float:
    """CPU seconds of this thread for ``steps`` control steps from a reset at ``pose``
    (reset untimed; CPU time, which a busy machine disturbs less than the wall clock)."""
    stepper.reset(np.array(pose, dtype=float))
    action = np.array(action, dtype=float)
    t0 = time.thread_time()
    for _ in range(steps):
        stepper.step(action, 250)
    return time.thread_time() - t0


def measure_models(
    socket_name: str, regime_name: str, steps: int, repeats: int, min_time: float
) -> tuple[dict[str, float], bool]:
    """Seconds per control step of each variant (blocks rotating, fastest kept), and
    whether all end at the same state."""
    case = profile_regime(socket_name, regime_name)
    socket = SOCKETS[socket_name]
    steppers = {name: model_stepper(socket, *v) for name, v in VARIANTS.items()}
    first = run_stepper(steppers["old"], case.pose, case.action, steps)
    for name in list(VARIANTS)[1:]:
        run_stepper(steppers[name], case.pose, case.action, steps)
    blocks = max(repeats, math.ceil(min_time / first)) if first > 0 else repeats
    names = list(VARIANTS)
    best = dict.fromkeys(names, math.inf)
    for i in range(blocks):
        for k in range(len(names)):
            name = names[(i + k) % len(names)]
            t = run_stepper(steppers[name], case.pose, case.action, steps)
            best[name] = min(best[name], t)
    old = steppers["old"].data
    same = all(
        np.array_equal(getattr(old, f), getattr(s.data, f))
        for s in steppers.values()
        for f in ("qpos", "qvel", "sensordata")
    )
    return {name: t / steps for name, t in best.items()}, same


def print_models(steps: int, repeats: int, min_time: float) -> list[str]:
    """Part 2's table; the problems found."""
    header = (
        f"{'socket':<8} {'regime':<12} {'old st/s':>9} {'new st/s':>9} {'new x':>6} "
        f"{'pairs st/s':>10} {'pairs x':>7} {'same':>5}"
    )
    print(header)
    print("-" * len(header))
    problems = []
    for socket_name in SOCKETS:
        for regime_name in REGIMES:
            t, same = measure_models(socket_name, regime_name, steps, repeats, min_time)
            print(
                f"{socket_name:<8} {regime_name:<12} {1 / t['old']:>9.1f} {1 / t['new']:>9.1f} "
                f"{t['old'] / t['new']:>6.2f} {1 / t['pairs']:>10.1f} "
                f"{t['old'] / t['pairs']:>7.2f} {'yes' if same else 'NO':>5}"
            )
            if not same:
                problems.append(f"{socket_name} {regime_name}: the variants' states differ")
    print(
        "old: sensors in every physics step (the eager-sensor step); new: sensors only before each "
        "read (the default);\npairs: new on make_mjcf(socket, contact_pairs=True); x: old "
        "time / variant time, blocks rotating"
    )
    return problems


# ---------------------------------------------------------------------------------------
# Part 3: threads.
# ---------------------------------------------------------------------------------------


def step_envs(envs: list[InsertionEnv], case: Case, steps: int) -> None:
    """``steps`` control steps of every env, round-robin; resets (timed) at episode ends."""
    options = {"pose": case.pose}
    action = case.action
    for env in envs:
        env.reset(options=options)
    for _ in range(steps):
        for env in envs:
            _, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                env.reset(options=options)


def step_bare(
    sims: list[tuple[mujoco.MjModel, mujoco.MjData]],
    case: Case,
    steps: int,
    horizon: int,
    nstep: int,
) -> None:
    """The work of :func:`step_envs` as bare MuJoCo loops: what threads can gain at best."""
    ctrl = case.action[ACTION_TO_JOINT]
    for model, data in sims:
        bare_reset(model, data, case.pose)
    for k in range(1, steps + 1):
        for model, data in sims:
            data.act[:] = data.qpos
            data.ctrl[:] = ctrl
            bare_steps(model, data, nstep)
            if k % horizon == 0:
                bare_reset(model, data, case.pose)


def measure_threads(
    case: Case, n_envs: int, n_threads: int, steps: int, repeats: int
) -> dict[str, tuple[float, float]]:
    """Best seconds of one thread and of ``n_threads`` threads doing the same work.

    ``{"env": (one, many), "bare": (one, many)}``; the four runs alternate in each repeat.
    """
    envs = [make_env(case.socket) for _ in range(n_envs)]
    horizon, nstep = envs[0].horizon, envs[0].backend.substeps
    sims = [(env.backend.model, mujoco.MjData(env.backend.model)) for env in envs]
    work = {"env": (step_envs, envs, ()), "bare": (step_bare, sims, (horizon, nstep))}
    clock = time.perf_counter
    best = {(kind, way): math.inf for kind in work for way in ("one", "many")}
    with concurrent.futures.ThreadPoolExecutor(max_workers=n_threads) as pool:

        def one(kind: str, n: int) -> None:
            fn, items, extra = work[kind]
            fn(items, case, n, *extra)

        def many(kind: str, n: int) -> None:
            fn, items, extra = work[kind]
            groups = [items[i::n_threads] for i in range(n_threads)]
            for f in [pool.submit(fn, g, case, n, *extra) for g in groups]:
                f.result()

        for kind in work:  # warm-up; also starts the pool's threads
            one(kind, 2)
            many(kind, 2)
        for _ in range(repeats):
            for kind in work:
                for way, run in (("one", one), ("many", many)):
                    t0 = clock()
                    run(kind, steps)
                    best[kind, way] = min(best[kind, way], clock() - t0)
    return {kind: (best[kind, "one"], best[kind, "many"]) for kind in work}


# ---------------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--steps",
        type=int,
        default=40,
        help="control steps per timed block (default 40: one episode)",
    )
    parser.add_argument(
        "--repeats", type=int, default=3, help="least timed blocks (runs) per variant; best kept"
    )
    parser.add_argument(
        "--min-time",
        type=float,
        default=1.0,
        help="cheap cases get more blocks until each variant has run this long (s)",
    )
    parser.add_argument(
        "--thread-steps", type=int, default=80, help="control steps per env in the thread test"
    )
    parser.add_argument("--envs", type=int, default=8, help="envs in the thread test")
    parser.add_argument("--threads", type=int, default=2, help="threads in the thread test")
    parser.add_argument("--quick", action="store_true", help="a few seconds: tiny runs")
    parser.add_argument(
        "--models-only", action="store_true", help="only part 2 (old vs new control step)"
    )
    parser.add_argument(
        "--against",
        metavar="REV",
        help="only the single env on this tree against revision REV, side by side "
        "(benchmarks/env_versions.py)",
    )
    parser.add_argument(
        "--versions",
        action="store_true",
        help="only -v1 against -v2, side by side (benchmarks/physics_versions.py)",
    )
    args = parser.parse_args(argv)
    if args.versions:
        import physics_versions  # beside this script

        return physics_versions.main([])
    if args.against:
        import env_versions  # beside this script

        env_versions.main(["--rev", args.against, "--steps", str(args.steps)])
        return 0
    if args.quick:
        args.steps, args.repeats, args.min_time, args.thread_steps = 4, 2, 0.02, 16
    if min(args.steps, args.repeats, args.thread_steps, args.envs, args.threads) < 1:
        parser.error("--steps, --repeats, --thread-steps, --envs and --threads must be >= 1")

    start = time.perf_counter()
    if args.quick:
        print("--quick: short runs, a smoke test; its figures are rough")
    print(
        f"python {platform.python_version()}, mujoco {mujoco.__version__}, numpy "
        f"{np.__version__}, {os.cpu_count()} CPUs, {platform.processor() or platform.machine()}"
    )
    print(
        f"blocks of {args.steps} control steps from a reset, at least {args.repeats} "
        f"and {args.min_time} s per variant, fastest block kept; resets excluded\n"
    )

    if args.models_only:
        print(f"Old vs new model: blocks of {args.steps} control steps, alternating")
        problems = print_models(args.steps, args.repeats, args.min_time)
        for p in problems:
            print(f"WARNING: {p}")
        print(f"total time {time.perf_counter() - start:.1f} s")
        return 1 if problems else 0
    results = [measure_case(c, args.steps, args.repeats, args.min_time) for c in cases()]
    print_results(results)
    problems = check_regimes(results)
    print(f"\nOld vs new model: blocks of {args.steps} control steps, alternating")
    problems += print_models(args.steps, args.repeats, args.min_time)
    for p in problems:
        print(f"WARNING: {p}")

    print(
        f"\nThreads: {args.envs} envs of 2*2, {args.thread_steps} control steps each, "
        f"1 thread vs {args.threads} threads (resets included), best of {args.repeats}"
    )
    header = (
        f"{'regime':<8} {'1 thread st/s':>14} {f'{args.threads} threads st/s':>15} "
        f"{'speed-up':>9} {'bare speed-up':>14}"
    )
    print(header)
    print("-" * len(header))
    speedups = []
    for name, socket, block in sockets()[:1]:
        for regime, pose, action in (
            ("free", FREE_POSE, FREE_ACTION),
            ("contact", block, PUSH_ACTION),
        ):
            case = Case(name, socket, regime, pose, action)
            times = measure_threads(case, args.envs, args.threads, args.thread_steps, args.repeats)
            one, many = times["env"]
            bare_one, bare_many = times["bare"]
            total = args.envs * args.thread_steps
            speedup = one / many
            speedups.append(speedup)
            flag = " " if speedup >= SPEEDUP_TARGET else "!"
            print(
                f"{regime:<8} {total / one:>14.0f} {total / many:>15.0f} {speedup:>8.2f}{flag} "
                f"{bare_one / bare_many:>14.2f}"
            )
    print(
        f"bare speed-up: the same work as bare MuJoCo loops, 1 vs {args.threads} threads "
        "(the ceiling this machine allows)"
    )

    worst = max(r.env / r.bare for r in results)
    worst1 = max(r.cc1 / r.bare for r in results)
    print(
        f"\nworst env/bare ratio {worst:.3f} (target <= {RATIO_TARGET}): "
        f"{'met' if worst <= RATIO_TARGET else 'NOT met'}; "
        f"with contact_checks=1 {worst1:.3f}: {'met' if worst1 <= RATIO_TARGET else 'NOT met'}"
    )
    low = min(speedups)
    print(
        f"lowest thread speed-up {low:.2f} (target >= {SPEEDUP_TARGET}): "
        f"{'met' if low >= SPEEDUP_TARGET else 'NOT met'}"
    )
    print(f"total time {time.perf_counter() - start:.1f} s")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
