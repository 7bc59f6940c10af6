"""``-v2`` physics against ``-v1``: the same seeded episodes on both, outcome for outcome.

Usage::

    python benchmarks/v2_equivalence.py                          # every case, default counts
    python benchmarks/v2_equivalence.py --episodes 20 --other-episodes 5   # a short run
    python benchmarks/v2_equivalence.py --only Circle2x2 Circle2x2Fit20 --json out.json

**Cases.** The 2*2 (``Circle2x2``, ``--episodes`` per regime, default 500); every other
paper preset (``--other-episodes``, default 100, as for every case below); the 50 and
20 µm grades ``Circle2x2Fit50``, ``Circle2x2Fit20``, ``SquareFit20``; each defect kind
on the 2*2 (``defects=(kind, sigma)`` at the robustness table's scales: pitch 2 %, burr
0.05 mm, short 0.5 mm, a blocked hole; bent pins are ``Circle2x1Defective``); and the
2*2 with ``randomization="default"``. ``--only NAME ...`` runs those cases.

**Regimes.** The safe and the efficient expert, a uniformly random policy (the env's
``action_space`` seeded with the episode's seed) and π_n, a nominal policy: ``--policy``
(a ``policy.pt`` or a run folder), else a BC policy trained once at the start as by
``tolins train bc --env tolins/Circle2x2-v1`` (default configs, seed 0, about 10 s) and
acted with on every case.

**Comparison.** Episode ``i`` of a case and regime is ``reset(seed=i)`` then the policy
until the episode ends, on ``-v1`` and on ``-v2`` (unwrapped envs, one pair per worker
and case). Compared per episode: success, steps, collisions (steps with
``info["collision"]``) and the return, exactly; and the true pose ``info["pose"]`` at
every control step's end (position in µm, theta in µrad). An episode whose outcome
differs, or whose pose drifts more than 0.1 µm, is printed with the step where it
diverged, each version's peak force and flags there, the deviation before it, and
whether ``-v2`` took a longer step there or one run read a collision the other read as
0 N from the same pose. More than 0.1 % differing episodes: not safe.

**Control** (``--no-control`` skips it). Every episode once more on ``-v1``, its start
moved :data:`NUDGE_MM` in x after the reset: how many outcomes ``-v1`` itself changes for
a difference the size of free flight's rounding.

**Speed.** The thread CPU time (``time.thread_time``) of every ``env.step``, summed per
version; ``-v2``'s physics step of every control step
(``env.unwrapped.backend.stepper.step_factor`` and ``step_window``). Each worker runs an
episode on ``-v1`` then on ``-v2``, so a busy machine slows both alike. ``--workers``
processes (default 2) take chunks of episodes, the costliest cases first.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import multiprocessing
import os
import platform
import subprocess
import sys
import tempfile
import time
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np

import tolins
from tolins.policies import EXPERTS

ROOT = Path(__file__).resolve().parents[1]
REGIMES = ("safe", "efficient", "random", "pi_n")
#: Largest pose deviation (µm) still counted as the same trajectory.
POSE_BOUND_UM = 0.1
#: Pose deviation (µm) up to which two runs enter a control step in the same state: a
#: collision flag that differs there with one peak force read as 0 is a contact that one
#: run's touch sensors did not count, not a motion that differs.
SAME_POSE_UM = 1e-6
#: The control's offset (mm): ``-v1`` against itself from an x this much off, the size of
#: the rounding that ``-v2``'s longer steps leave at a control step's end.
NUDGE_MM = 1e-12
#: Largest share of differing episodes that is safe.
SAFE_SHARE = 0.001
#: The speed-up the team asks for on the 2*2, per regime.
SPEED_GOALS = {"safe": 2.5, "efficient": 2.5, "random": 1.5}
OTHER_PAPER = (
    "Circle2x1",
    "Circle2x4",
    "Circle2x8",
    "Circle2x1Defective",
    "Square",
    "Pentagon",
    "Hexagon",
)
GRADES = ("Circle2x2Fit50", "Circle2x2Fit20", "SquareFit20")
DEFECTS = {"pitch": 0.02, "burr": 0.05, "short": 0.5, "blocked": None}


@dataclass(frozen=True)
class Case:
    """One env configuration: a preset and the keywords added on both versions."""

    name: str
    preset: str
    kwargs: dict[str, Any] = field(default_factory=dict)
    cost: float = 1.0  # relative cost per episode, to schedule the dearest first


def all_cases() -> list[Case]:
    """Every case in the order of the report."""
    cases = [Case("Circle2x2", "Circle2x2")]
    cases += [Case(name, name, cost=8.0 if name == "Circle2x8" else 1.0) for name in OTHER_PAPER]
    cases += [Case(name, name, cost=4.0) for name in GRADES]
    cases += [
        Case(f"Circle2x2 {kind}", "Circle2x2", {"defects": (kind, sigma)})
        for kind, sigma in DEFECTS.items()
    ]
    cases.append(Case("Circle2x2 randomised", "Circle2x2", {"randomization": "default"}))
    return cases


# --- worker ----------------------------------------------------------------------------

_envs: dict[tuple[str, int], gym.Env] = {}
_policies: dict[str, Any] = {}


def _init_worker() -> None:
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    import torch

    torch.set_num_threads(1)


def _env(case: Case, version: int) -> gym.Env:
    key = (case.name, version)
    if key not in _envs:
        _envs[key] = gym.make(f"tolins/{case.preset}-v{version}", **case.kwargs).unwrapped
    return _envs[key]


def _policy(regime: str, env: gym.Env, seed: int, policy_path: str | None):
    if regime in EXPERTS:
        return EXPERTS[regime]()
    if regime == "random":
        env.action_space.seed(seed)
        return lambda _obs: env.action_space.sample()
    if policy_path not in _policies:
        from tolins.learning.imitation.policy import load_policy

        _policies[policy_path] = load_policy(policy_path, kind="nominal")[0].bind()
    return _policies[policy_path]


def _episode(env: gym.Env, act, seed: int, nudge: float = 0.0) -> dict[str, Any]:
    """One episode's per-step record and the thread CPU seconds of its steps; ``nudge``
    (mm) moves the workpiece in x after the reset."""
    obs, _ = env.reset(seed=seed)
    if nudge:
        backend = env.backend
        backend.data.qpos[backend.stepper.layout.pose_joint[0]] += nudge
        mujoco.mj_forward(backend.model, backend.data)
    timestep = env.backend.model.opt.timestep
    rows: dict[str, list] = {k: [] for k in ("pose", "reward", "collision", "success", "peak")}
    rows.update(factor=[], window=[])
    cpu, done = 0.0, False
    while not done:
        action = act(obs)
        start = time.thread_time()
        obs, reward, terminated, truncated, info = env.step(action)
        cpu += time.thread_time() - start
        for key, value in (
            ("pose", info["pose"].tolist()),
            ("reward", float(reward)),
            ("collision", bool(info["collision"])),
            ("success", bool(info["success"])),
            ("peak", float(info["peak_force"])),
            ("factor", env.backend.stepper.step_factor),
            ("window", env.backend.stepper.step_window),
        ):
            rows[key].append(value)
        done = terminated or truncated
    return {**rows, "cpu": cpu, "timestep": timestep, "error": info.get("error")}


def _outcome(run: dict[str, Any]) -> dict[str, Any]:
    return {
        "success": bool(run["success"][-1]),
        "steps": len(run["reward"]),
        "collisions": int(sum(run["collision"])),
        "reward": float(sum(run["reward"])),
        "error": run["error"],
    }


def _deviation(a: dict[str, Any], b: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Per common step: position deviation (µm) and theta deviation (µrad)."""
    n = min(len(a["pose"]), len(b["pose"]))
    diff = np.abs(np.array(a["pose"][:n]) - np.array(b["pose"][:n]))
    return diff[:, [0, 1, 3]].max(axis=1) * 1e3, diff[:, 2] * 1e6


def _divergence(v1: dict, v2: dict, position: np.ndarray, collision_force: float) -> dict:
    """Where two episodes part: the first step whose flags differ or whose pose is off by
    more than the bound, with each version's values there."""
    n = len(position)
    flags = [
        k
        for k in range(n)
        if (v1["collision"][k], v1["success"][k], v1["reward"][k])
        != (v2["collision"][k], v2["success"][k], v2["reward"][k])
    ]
    drift = [k for k in range(n) if position[k] > POSE_BOUND_UM]
    first = min([*flags, *drift, n - 1])
    peaks = (v1["peak"][first], v2["peak"][first])
    before = float(position[first - 1]) if first else 0.0
    trace = [
        {
            "step": k + 1,
            "dev_um": float(position[k]),
            "z_mm": v1["pose"][k][3],
            "peak_n": [v1["peak"][k], v2["peak"][k]],
            "collision": [v1["collision"][k], v2["collision"][k]],
            "success": [v1["success"][k], v2["success"][k]],
            "v2_factor": v2["factor"][k],
        }
        for k in range(max(first - 2, 0), min(first + 4, n))
    ]
    return {
        "step": first + 1,
        "flags_differ_at": flags[0] + 1 if flags else None,
        "dev_before_um": before,
        "missed_read": first in flags
        and before <= SAME_POSE_UM
        and min(peaks) == 0.0 < collision_force < max(peaks),
        "in_contact": max(peaks) > 0.0,
        "v2_longer_step": v2["factor"][first] > 1,
        "collision_at_boundary": (peaks[0] > collision_force) != (peaks[1] > collision_force)
        and min(abs(p - collision_force) for p in peaks) < 0.01 * collision_force,
        "trace": trace,
    }


def _compare(a: dict, b: dict) -> dict[str, Any]:
    """The outcomes of two runs of one episode and their largest pose deviation."""
    position, theta = _deviation(a, b)
    outcomes = (_outcome(a), _outcome(b))
    return {
        "v1": outcomes[0],
        "v2": outcomes[1],
        "same": outcomes[0] == outcomes[1],
        "dev_um": float(position.max()),
        "dev_urad": float(theta.max()),
        "position": position,
    }


def run_chunk(
    case: Case, regime: str, seeds: list[int], policy_path: str | None, control: bool
) -> dict:
    """The worker's task: ``seeds`` of one case and regime on both versions (and, with
    ``control``, on ``-v1`` again from a pose :data:`NUDGE_MM` off)."""
    envs = {v: _env(case, v) for v in (1, 2)}
    cpu, factors, windowed, episodes = {1: 0.0, 2: 0.0}, Counter(), 0, []
    for seed in seeds:
        runs = {
            v: _episode(e, _policy(regime, e, seed, policy_path), seed) for v, e in envs.items()
        }
        for v, run in runs.items():
            cpu[v] += run["cpu"]
        step_ms = runs[2]["timestep"] * 1e3
        factors.update(f"{f * step_ms:g} ms" for f in runs[2]["factor"])
        windowed += sum(w > 0 for w in runs[2]["window"])
        row = {"seed": seed, **_compare(runs[1], runs[2])}
        position = row.pop("position")
        if not row["same"] or row["dev_um"] > POSE_BOUND_UM:
            collision_force = envs[1].settings.collision_force
            row["divergence"] = _divergence(runs[1], runs[2], position, collision_force)
        if control:
            policy = _policy(regime, envs[1], seed, policy_path)
            nudged = _compare(runs[1], _episode(envs[1], policy, seed, NUDGE_MM))
            row["control"] = {k: nudged[k] for k in ("same", "dev_um", "dev_urad")}
        episodes.append(row)
    return {
        "case": case.name,
        "regime": regime,
        "cpu": cpu,
        "factors": dict(factors),
        "windowed": windowed,
        "episodes": episodes,
    }


# --- driver ----------------------------------------------------------------------------


def train_pi_n(folder: Path) -> Path:
    """π_n of ``tolins train bc --env tolins/Circle2x2-v1`` (default configs, seed 0)."""
    from tolins.learning.imitation.config import BCConfig, TaskConfig
    from tolins.learning.imitation.runs import run_bc

    result = run_bc("tolins/Circle2x2-v1", TaskConfig(), BCConfig(), folder)
    print(f"π_n: BC on the 2*2, held-out loss {result.held_out_loss:.4f}, {folder}", flush=True)
    return folder / "policy.pt"


def schedule(cases: list[tuple[Case, int]], regimes: list[str], chunk: int):
    """The tasks ``(case, regime, seeds)``, the dearest first."""
    tasks = []
    for case, n in cases:
        for regime in regimes:
            for start in range(0, n, chunk):
                tasks.append((case, regime, list(range(start, min(start + chunk, n)))))
    return sorted(tasks, key=lambda t: -t[0].cost)


def summarise(results: list[dict]) -> dict[tuple[str, str], dict]:
    """Per case and regime: the chunks' figures merged."""
    rows: dict[tuple[str, str], dict] = {}
    for r in results:
        row = rows.setdefault(
            (r["case"], r["regime"]),
            {"cpu": {1: 0.0, 2: 0.0}, "factors": Counter(), "windowed": 0, "episodes": []},
        )
        for v in (1, 2):
            row["cpu"][v] += r["cpu"][v]
        row["factors"].update(r["factors"])
        row["windowed"] += r["windowed"]
        row["episodes"] += r["episodes"]
    for row in rows.values():
        row["episodes"].sort(key=lambda e: e["seed"])
    return rows


def _factor_cell(factors: Counter, windowed: int) -> str:
    total = sum(factors.values())
    order = sorted(factors, key=lambda k: float(k.split()[0]))
    shares = ", ".join(f"{k} {100 * factors[k] / total:.1f} %" for k in order)
    return f"{shares}; after a window {100 * windowed / total:.1f} %"


def figures(row: dict) -> dict[str, Any]:
    """One case and regime's figures, as tabled and written to JSON."""
    eps = row["episodes"]
    out: dict[str, Any] = {"episodes": len(eps), "differ": sum(not e["same"] for e in eps)}
    for v in (1, 2):
        for key in ("success", "steps", "collisions"):
            out[f"{key}_v{v}"] = sum(e[f"v{v}"][key] for e in eps)
        out[f"cpu_v{v}"] = row["cpu"][v]
    out["max_dev_um"] = max(e["dev_um"] for e in eps)
    out["max_dev_urad"] = max(e["dev_urad"] for e in eps)
    out["speed_up"] = row["cpu"][1] / row["cpu"][2]
    out["physics_steps_v2"] = _factor_cell(row["factors"], row["windowed"])
    controls = [e["control"] for e in eps if "control" in e]
    if controls:
        out["control_differ"] = sum(not c["same"] for c in controls)
        out["control_max_dev_um"] = max(c["dev_um"] for c in controls)
    return out


def tables(rows: dict[tuple[str, str], dict], cases: list[Case]) -> str:
    """The outcome table and the speed table (markdown)."""
    outcome = [
        "| case | regime | episodes | differ | success v1 / v2 | collisions v1 / v2 | "
        "max dev µm | max dev µrad | control: differ, max dev µm |",
        "|---|---|--:|--:|--:|--:|--:|--:|--:|",
    ]
    speed = [
        "| case | regime | steps v1 / v2 | CPU s v1 / v2 | speed-up | -v2 physics step "
        "(share of control steps) |",
        "|---|---|--:|--:|--:|---|",
    ]
    for case in cases:
        for regime in REGIMES:
            if (case.name, regime) not in rows:
                continue
            f = figures(rows[case.name, regime])
            control = (
                f"{f['control_differ']}, {f['control_max_dev_um']:.2g}"
                if "control_differ" in f
                else "–"
            )
            outcome.append(
                f"| {case.name} | {regime} | {f['episodes']} | {f['differ']} | "
                f"{f['success_v1']} / {f['success_v2']} | {f['collisions_v1']} / "
                f"{f['collisions_v2']} | {f['max_dev_um']:.2g} | {f['max_dev_urad']:.2g} | "
                f"{control} |"
            )
            speed.append(
                f"| {case.name} | {regime} | {f['steps_v1']} / {f['steps_v2']} | "
                f"{f['cpu_v1']:.1f} / {f['cpu_v2']:.1f} | {f['speed_up']:.2f}× | "
                f"{f['physics_steps_v2']} |"
            )
    return "\n".join(outcome) + "\n\n" + "\n".join(speed)


def _control_cell(episode: dict) -> str:
    control = episode.get("control")
    if control is None:
        return "not run"
    return f"{'same' if control['same'] else 'differs'} ({control['dev_um']:.3g} µm)"


def report_divergences(rows: dict[tuple[str, str], dict], limit: int) -> list[dict]:
    """Print the episodes that differ or drift, the first ``limit`` with their steps."""
    found = [
        {"case": case, "regime": regime, **e}
        for (case, regime), row in rows.items()
        for e in row["episodes"]
        if "divergence" in e
    ]
    print(f"\n{len(found)} episodes differ or drift more than {POSE_BOUND_UM} µm")
    for e in found[:limit]:
        d = e["divergence"]
        print(
            f"- {e['case']}, {e['regime']}, seed {e['seed']}: same outcome {e['same']}, "
            f"v1 {e['v1']}, v2 {e['v2']}; max dev {e['dev_um']:.3g} µm; parts at step "
            f"{d['step']} (flags differ at {d['flags_differ_at']}), control "
            f"{_control_cell(e)}, dev before "
            f"{d['dev_before_um']:.3g} µm, a contact read by one run only {d['missed_read']}, "
            f"in contact {d['in_contact']}, -v2 longer step "
            f"{d['v2_longer_step']}, collision decided at the 0.5 N boundary "
            f"{d['collision_at_boundary']}"
        )
        for s in d["trace"]:
            print(
                f"    step {s['step']:2d}: dev {s['dev_um']:.3g} µm, z {s['z_mm']:+.6f} mm, "
                f"peak {s['peak_n'][0]:.4f} / {s['peak_n'][1]:.4f} N, collision "
                f"{s['collision'][0]} / {s['collision'][1]}, success {s['success'][0]} / "
                f"{s['success'][1]}, -v2 step ×{s['v2_factor']}"
            )
    return found


def verdicts(rows: dict[tuple[str, str], dict]) -> list[str]:
    """The goals, met or not: outcomes, pose deviation, speed on the 2*2."""
    eps = [e for row in rows.values() for e in row["episodes"]]
    differ = sum(not e["same"] for e in eps)
    drift = sum(e["dev_um"] > POSE_BOUND_UM for e in eps)
    parted = [e["divergence"] for e in eps if "divergence" in e]
    in_free_flight = sum(d["v2_longer_step"] for d in parted)
    missed = sum(d["missed_read"] for d in parted)
    share = differ / max(len(eps), 1)
    lines = [
        f"{differ} of {len(eps)} episodes differ in outcome ({100 * share:.3f} %): "
        + ("SAFE" if share <= SAFE_SHARE else f"NOT SAFE (more than {100 * SAFE_SHARE:g} %)"),
        f"{drift} episodes drift more than {POSE_BOUND_UM} µm (largest "
        f"{max((e['dev_um'] for e in eps), default=0):.3g} µm); {in_free_flight} of the "
        f"differing or drifting episodes part on a longer -v2 step; {missed} part on a "
        f"collision one run reads as 0 N from poses within {SAME_POSE_UM:g} µm",
    ]
    controls = [e["control"] for e in eps if "control" in e]
    if controls:
        parted = sum(not c["same"] for c in controls)
        drifted = sum(c["dev_um"] > POSE_BOUND_UM for c in controls)
        both = sum(not e["same"] and not e["control"]["same"] for e in eps if "control" in e)
        lines.append(
            f"control, -v1 from x {NUDGE_MM:g} mm off: {parted} of {len(controls)} episodes "
            f"differ, {drifted} drift more than {POSE_BOUND_UM} µm; {both} of the {differ} "
            "episodes that -v2 changes the control changes too"
        )
    for regime, goal in SPEED_GOALS.items():
        row = rows.get(("Circle2x2", regime))
        if row:
            x = row["cpu"][1] / row["cpu"][2]
            lines.append(
                f"2*2 {regime}: {x:.2f}× (goal ≥ {goal}×: {'met' if x >= goal else 'NOT met'})"
            )
    return lines


def machine() -> dict[str, Any]:
    git = ["git", "-C", str(ROOT)]
    commit = subprocess.run([*git, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    dirty = subprocess.run([*git, "status", "--short", "tolins"], capture_output=True, text=True)
    return {
        "commit": commit.stdout.strip(),
        "tolins_changes": dirty.stdout.split("\n")[:-1],
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "tolins": tolins.__version__,
        "cpus": os.cpu_count(),
        "load_average": os.getloadavg(),
    }


def run_tasks(tasks: list, policy: str | None, workers: int, control: bool) -> list[dict]:
    """Every task on ``workers`` processes, with progress."""
    started = time.perf_counter()
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(
        workers, mp_context=context, initializer=_init_worker
    ) as pool:
        futures = [pool.submit(run_chunk, *task, policy, control) for task in tasks]
        results = []
        for i, future in enumerate(concurrent.futures.as_completed(futures), 1):
            results.append(future.result())
            if i % max(len(futures) // 20, 1) == 0 or i == len(futures):
                elapsed = time.perf_counter() - started
                print(f"  {i} / {len(futures)} tasks, {elapsed:.0f} s", flush=True)
    return results


def parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=500, help="per regime on the 2*2")
    parser.add_argument("--other-episodes", type=int, default=100, help="per regime elsewhere")
    parser.add_argument("--only", nargs="+", help="case names to run (default: all)")
    parser.add_argument("--regimes", nargs="+", choices=REGIMES, default=list(REGIMES))
    parser.add_argument("--policy", help="π_n: a policy.pt or a run folder (default: train BC)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--chunk", type=int, default=10, help="episodes per worker task")
    parser.add_argument("--show", type=int, default=20, help="divergent episodes printed")
    parser.add_argument(
        "--no-control", action="store_true", help="skip -v1 against itself from a nudged pose"
    )
    parser.add_argument("--json", type=Path, help="write every figure here")
    args = parser.parse_args(argv)
    unknown = set(args.only or ()) - {c.name for c in all_cases()}
    if unknown:
        parser.error(f"--only: unknown {sorted(unknown)}; allowed: {[c.name for c in all_cases()]}")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse(argv)
    warnings.filterwarnings("ignore", message=".*is out of date.*")
    started, meta = time.perf_counter(), machine()
    cases = [c for c in all_cases() if not args.only or c.name in args.only]
    counts = [(c, args.episodes if c.name == "Circle2x2" else args.other_episodes) for c in cases]
    print(f"-v2 against -v1: {meta}; {args.workers} workers", flush=True)
    with tempfile.TemporaryDirectory(prefix="tolins-pi-n-") as folder:
        policy = args.policy
        if "pi_n" in args.regimes and policy is None:
            policy = str(train_pi_n(Path(folder)))
        elif policy is not None and Path(policy).is_dir():
            policy = str(Path(policy) / "policy.pt")
        tasks = schedule(counts, args.regimes, args.chunk)
        results = run_tasks(tasks, policy, args.workers, not args.no_control)
    rows = summarise(results)
    print("\n" + tables(rows, cases))
    found = report_divergences(rows, args.show)
    lines = verdicts(rows)
    wall = time.perf_counter() - started
    print("\n" + "\n".join(lines) + f"\ntotal {wall:.0f} s wall, load average {os.getloadavg()}")
    if args.json:
        meta.update(
            argv=sys.argv, wall_s=wall, policy=args.policy or "BC", load_end=os.getloadavg()
        )
        table_rows = [{"case": c, "regime": r, **figures(row)} for (c, r), row in rows.items()]
        out = {"meta": meta, "rows": table_rows, "divergent": found, "verdicts": lines}
        args.json.write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
