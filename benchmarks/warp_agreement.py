"""Does the MuJoCo Warp backend insert, block and push as C MuJoCo does?

Usage::

    python benchmarks/warp_agreement.py                 # full run on Warp's CPU device
    python benchmarks/warp_agreement.py --quick         # a smoke run
    python benchmarks/warp_agreement.py --device cuda:0 --probes 256

Every measurement runs the same poses and commands through ``MujocoBatch`` (C MuJoCo,
float64, solver tolerance 1e-10) and ``WarpBatch`` (float32, tolerance clamped to 1e-6)
in one batch each:

* **outcomes**: the near-boundary probes of ``benchmarks/physics_vs_geometry.py``
  (``make_probes``: random directions, offsets uniform in ±``--band-max`` µm), dropped
  0.05 mm above the board and pushed straight down at 2.5 mm/s for 5 control steps;
  outcome ``in`` (:func:`~tolins.geometry.workspace.in_holes` 1 mm deep) or not. Reported:
  agreement of Warp with C MuJoCo and with the geometry, outside ±``--band`` µm.
* **capture**: the 2*2 socket offset in x by 0.1960 … 0.2060 mm in 0.5 µm steps
  (clearance 0.2 mm), in theta by 0.0494 … 0.0512 rad in 0.1 mrad steps (geometric
  0.0499), the square peg in x by 0.1050 … 0.1100 mm (geometric 0.1061), pushed down at
  2.5 mm/s: the largest offset that inserts, less the geometric limit, per backend.
* **forces**: two blocked pushes held for 4 control steps (down onto the board 0.25 mm
  off the holes; sideways at 2.5 mm/s against a hole wall, pins 0.5 mm deep): largest
  difference of the wrench ``[Fx, Fy, q_theta, Fz]`` and of ``peak_force`` (N, N·mm).
* **episodes**: ``--episodes`` safe-expert episodes (seeds 0 …) of
  ``tolins/Circle2x2-v1`` through ``tolins.make_vec(..., backend=...)``: success and
  step count per seed.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import sys
import time
from pathlib import Path

import numpy as np

import tolins
from tolins import CircularSocket, PolygonSocket
from tolins.geometry.workspace import in_holes
from tolins.physics.mujoco import MujocoBatch
from tolins.policies import EXPERTS

FAST = 2.5
PUSH_STEPS = 5
START_HEIGHT = 0.05
DEPTH = 1.0
CLEARANCE_OFFSETS = np.round(np.arange(0.1960, 0.20601, 0.0005), 4)


def physics_vs_geometry():
    """``benchmarks/physics_vs_geometry.py`` as a module (its probes and sockets)."""
    path = Path(__file__).resolve().parent / "physics_vs_geometry.py"
    spec = importlib.util.spec_from_file_location("physics_vs_geometry", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look the module up
    spec.loader.exec_module(module)
    return module


def batches(socket, n: int, device: str):
    """``{"mujoco": MujocoBatch, "warp": WarpBatch}`` of ``n`` copies of ``socket``."""
    from tolins.physics.warp import WarpBatch

    return {"mujoco": MujocoBatch(socket, n, 0.25), "warp": WarpBatch(socket, n, 0.25, device)}


def push_down(batch, socket, poses: np.ndarray, steps: int = PUSH_STEPS) -> np.ndarray:
    """Drop ``poses`` ``(n, 3)`` 0.05 mm above the board and push down at 2.5 mm/s; whether
    each inserted (1 mm deep) within ``steps`` control steps. Inserted worlds stop."""
    n = len(poses)
    ids = np.arange(n)
    batch.reset(ids, np.column_stack([poses, np.full(n, START_HEIGHT)]))
    inserted = np.zeros(n, dtype=bool)
    for _ in range(steps):
        running = ids[~inserted]
        if not len(running):
            break
        state = batch.step(running, np.tile([0.0, 0.0, 0.0, -FAST], (len(running), 1)))
        inserted[running] = [in_holes(socket, p, DEPTH) for p in state.pose]
    return inserted


def outcomes(pvg, name: str, spec, n: int, seed: int, band_max: float, device: str) -> dict:
    """Warp against C MuJoCo and against the geometry on ``n`` near-boundary probes."""
    sock = pvg.Socket(name, "", spec)
    probes = pvg.make_probes(sock, n, seed, band_max, 32)
    poses = np.array([p.pose for p in probes])
    result = {}
    for backend, batch in batches(spec, n, device).items():
        start = time.perf_counter()
        result[backend] = push_down(batch, spec, poses)
        result[f"{backend}_s"] = time.perf_counter() - start
        batch.close()
    distance = np.array([p.distance_um for p in probes])
    inside = np.array([p.inside for p in probes])
    return {"distance_um": distance, "inside": inside, **result}


def summarise(r: dict, band: float) -> dict:
    """Agreement outside ±``band`` µm of the boundary (and in all)."""
    outside = np.abs(r["distance_um"]) > band
    same = r["warp"] == r["mujoco"]
    geometry = r["warp"] == r["inside"]
    differ = np.abs(r["distance_um"][~same])
    return {
        "probes": len(same),
        "outside_band": int(outside.sum()),
        "warp_vs_c_outside": float(same[outside].mean()) if outside.any() else float("nan"),
        "warp_vs_geometry_outside": float(geometry[outside].mean())
        if outside.any()
        else float("nan"),
        "c_vs_geometry_outside": float((r["mujoco"] == r["inside"])[outside].mean())
        if outside.any()
        else float("nan"),
        "warp_vs_c_all": float(same.mean()),
        "disagreements": int((~same).sum()),
        "max_disagreement_distance_um": float(differ.max()) if len(differ) else 0.0,
        "mujoco_s": r["mujoco_s"],
        "warp_s": r["warp_s"],
    }


#: (case, socket, pose axis, offsets, geometric limit) of the capture measurement.
CAPTURE_CASES = (
    ("2*2, x", CircularSocket(2, 2), 0, CLEARANCE_OFFSETS, 0.2),
    (
        "2*2, theta",
        CircularSocket(2, 2),
        2,
        np.round(np.arange(0.0494, 0.05121, 0.0001), 4),
        0.0499,
    ),
    (
        "square, x",
        PolygonSocket(4, 1.5, 1.65),
        0,
        np.round(np.arange(0.1050, 0.11001, 0.0005), 4),
        0.1061,
    ),
)


def capture(device: str, cases=CAPTURE_CASES) -> dict:
    """Per case: the largest offset along the axis that inserts, the smallest that
    blocks, and the first less the geometric limit (µm, or mrad for theta)."""
    result = {}
    for case, spec, axis, offsets, limit in cases:
        poses = np.zeros((len(offsets), 3))
        poses[:, axis] = offsets
        result[case] = {"limit": limit}
        for backend, batch in batches(spec, len(offsets), device).items():
            inserted = push_down(batch, spec, poses)
            top = float(offsets[inserted].max()) if inserted.any() else None
            result[case][backend] = {
                "inserted_up_to": top,
                "blocked_from": float(offsets[~inserted].min()) if (~inserted).any() else None,
                "beyond_limit_um_or_mrad": None if top is None else round((top - limit) * 1e3, 2),
                "inserted_pattern": "".join("i" if x else "." for x in inserted),
            }
            batch.close()
    return result


#: (name, start pose [x, y, theta, z], velocity) of the blocked pushes.
PUSHES = (
    ("down onto the board", [0.25, 0.0, 0.0, START_HEIGHT], [0.0, 0.0, 0.0, -FAST]),
    ("sideways against a hole wall", [0.0, 0.0, 0.0, -0.5], [FAST, 0.0, 0.0, 0.0]),
)


def forces(device: str, steps: int = 4) -> dict:
    """Wrench and peak force of each push after ``steps`` control steps, both backends."""
    spec = CircularSocket(2, 2)
    ids = np.arange(len(PUSHES))
    poses = np.array([p for _, p, _ in PUSHES])
    velocities = np.array([u for _, _, u in PUSHES])
    states = {}
    for backend, batch in batches(spec, len(PUSHES), device).items():
        batch.reset(ids, poses)
        for _ in range(steps):
            states[backend] = batch.step(ids, velocities)
        batch.close()
    c, w = states["mujoco"], states["warp"]
    return {
        name: {
            "c_wrench": c.wrench[i].round(6).tolist(),
            "warp_wrench": w.wrench[i].round(6).tolist(),
            "max_wrench_difference": float(np.abs(c.wrench[i] - w.wrench[i]).max()),
            "c_peak": float(c.peak_force[i]),
            "warp_peak": float(w.peak_force[i]),
            "pose_difference_um": float(np.abs(c.pose[i] - w.pose[i])[[0, 1, 3]].max() * 1e3),
        }
        for i, (name, _, _) in enumerate(PUSHES)
    }


def expert_episodes(seeds: list[int], device: str, env_id: str = "tolins/Circle2x2-v1") -> dict:
    """Success and steps of the safe expert's episode of each seed, per backend (all
    seeds in one vector env per backend)."""
    result = {}
    for backend in ("mujoco", "warp"):
        kwargs = {"device": device} if backend == "warp" else {}
        env = tolins.make_vec(env_id, len(seeds), backend=backend, **kwargs)
        experts = [EXPERTS["safe"]() for _ in seeds]
        obs, _ = env.reset(seed=list(seeds))
        defective = [bool(socket.is_defective) for socket in env.unwrapped.sockets]
        done = np.zeros(len(seeds), dtype=bool)
        steps = np.zeros(len(seeds), dtype=int)
        success = np.zeros(len(seeds), dtype=bool)
        start = time.perf_counter()
        while not done.all():
            actions = np.array([e(o) for e, o in zip(experts, obs, strict=True)])
            obs, _, terminated, truncated, info = env.step(actions)
            ended = (terminated | truncated) & ~done
            steps[~done] += 1
            success[ended] = np.asarray(info["success"])[ended]
            done |= ended
        env.close()
        result[backend] = {
            "steps": steps.tolist(),
            "success": success.tolist(),
            "defective": defective,
            "s": time.perf_counter() - start,
        }
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--probes", type=int, default=96, help="probes per socket")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--band", type=float, default=10.0, help="µm")
    parser.add_argument("--band-max", type=float, default=50.0, help="µm")
    parser.add_argument("--episodes", type=int, default=4)
    parser.add_argument("--quick", action="store_true", help="8 probes, 2 episodes")
    parser.add_argument("--json", type=Path, help="write the figures here too")
    parser.add_argument(
        "--parts",
        nargs="+",
        default=["outcomes", "capture", "forces", "episodes"],
        choices=["outcomes", "capture", "forces", "episodes"],
    )
    args = parser.parse_args(argv)
    if args.quick:
        args.probes, args.episodes = 8, 2
    start = time.perf_counter()
    pvg = physics_vs_geometry()
    sockets = [
        ("2*2", CircularSocket(2, 2)),
        ("2*8", CircularSocket(2, 8)),
        ("square", PolygonSocket(4, 1.5, 1.65)),
        ("hexagon", PolygonSocket(6, 1.2, 1.26)),
    ]
    report: dict = {"device": args.device, "probes_per_socket": args.probes}
    for name, spec in sockets if "outcomes" in args.parts else []:
        r = outcomes(pvg, name, spec, args.probes, args.seed, args.band_max, args.device)
        report[f"outcomes {name}"] = summarise(r, args.band)
        print(name, json.dumps(report[f"outcomes {name}"]), flush=True)
    parts = {
        "capture": lambda: capture(args.device),
        "forces": lambda: forces(args.device),
        "episodes": lambda: expert_episodes(list(range(args.episodes)), args.device),
    }
    for part, measure in parts.items():
        if part in args.parts:
            report[part] = measure()
            print(part, json.dumps(report[part], indent=1), flush=True)
    report["seconds"] = time.perf_counter() - start
    print(f"total {report['seconds']:.0f} s")
    if args.json:
        args.json.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
