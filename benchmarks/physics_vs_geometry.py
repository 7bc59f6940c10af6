"""Does the MuJoCo physics insert exactly where the tolerance model says it should?

Usage::

    python benchmarks/physics_vs_geometry.py               # full run, 2–3.5 min on 2 cores
    python benchmarks/physics_vs_geometry.py --quick       # under 30 s, a smoke test
    python benchmarks/physics_vs_geometry.py --probes 200 --seed 3 --no-slow
    python benchmarks/physics_vs_geometry.py --hole-sides 32   # experiment: finer round holes
    python benchmarks/physics_vs_geometry.py --grade 20    # 2*2, 2*8, square, hexagon at 20 µm
    python benchmarks/physics_vs_geometry.py --physics-version 2   # the ``-v2`` physics
    python benchmarks/physics_vs_geometry.py --physics-version 2 --robot panda  # the arm

``--grade UM`` probes the 2*2 and 2*8 sockets and the square and hexagon pegs with their
holes resized to a radial clearance of UM µm (``tolins.geometry.specs.with_clearance``,
the tolerance-grade presets), the band ±5 % of the clearance and the offsets
±25 % of it unless ``--band`` / ``--band-max`` say otherwise.

For each socket, ``--probes`` random poses ``[x, y, theta]`` near the boundary of the
exact tolerance (:func:`tolins.tolerance.contains`) are dropped into the MuJoCo env
(``InsertionEnv(spec, measurement_noise=0)``, start 0.05 mm above the board, push
straight down) and whether the physics inserts (``info["success"]``) is compared with
whether the geometry says the pose is inside.

**Probes.** From a centre of the tolerance (the nominal pose; for the bent-pin socket
the pose with the most slack, found by a grid search), a random direction ``u`` in
``(x, y, theta)`` (uniform on the sphere after scaling by the nominal socket's tolerance
half-extents) is followed to the boundary by bisection on ``contains``. The probe is
the boundary point moved along ``u`` by a signed offset drawn uniformly in
``±--band-max`` µm (default 50), the offset measured as the largest displacement of a
*pin point* (the centre of a round pin, a vertex of a polygon peg: the points the
tolerance constrains) between the boundary pose and the probe.

**Distance.** The reported distance of a probe from the boundary is not that offset
(a direction oblique to the boundary overstates it) but the smallest pin-point
displacement that changes ``contains``: the minimum over ``--directions`` random
directions (plus the probe's own) of the first state change along each, found by
sampling and bisection, refined around the best direction. It is an upper bound,
within a few per cent of the true distance. Sign: positive outside the tolerance
(geometry says no), negative inside.

**Physics.** Action ``[0, 0, 0, -speed]`` for up to ``STEPS[speed]`` control steps (fast:
2.5 mm/s, 5 steps = 3.1 mm of commanded travel; slow: 0.5 mm/s, 10 steps = 1.25 mm),
stopping at success (tips 1 mm below the top). Outcomes: ``in`` (success), ``surface``
(tips within 10 µm of the top) or ``stuck`` (between: pins partly in, jammed).

**Report** per socket and speed: probes, agreement outside the ±``--band`` µm band
(goal ≥ 99 %), the disagreements: how many, on which side (``capture``: physics
inserts where geometry says no; ``jam``: physics blocks where geometry says yes), the
largest ``|distance|`` and the 99th percentile of ``|distance|`` of disagreements, and
the core-seconds spent. ``--diagnose K`` prints, for the K disagreements farthest from
the boundary, the contacts at the first touch and once the tips are 20 µm deep (geom
names, normals, depths).

Threads: ``--workers`` (default 2) threads, each with its own envs (``mj_step``
releases the GIL). Every probe starts from ``reset`` (``mj_resetData``: no warm start
carried over), so results do not depend on the worker count or order.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import math
import os
import platform
import sys
import threading
import time
from dataclasses import dataclass

import mujoco
import numpy as np

import tolins
from tolins import CircularSocket, PolygonSocket
from tolins.envs import InsertionEnv
from tolins.geometry import specs as specs_module
from tolins.geometry.specs import polygon_vertices, with_clearance
from tolins.mjcf import model as model_module
from tolins.tolerance import contains, extents

FAST, SLOW = 2.5, 0.5
STEPS = {FAST: 5, SLOW: 10}
START_HEIGHT = 0.05
SURFACE_UM = 10.0
GOAL = 0.99


@dataclass(frozen=True)
class Socket:
    name: str
    family: str
    spec: object
    physics_version: int = 1
    robot: str = "free"


def graded_sockets(grade_um: float) -> list[Socket]:
    """The sockets of a tolerance grade: 2*2, 2*8, square and hexagon at ``grade_um`` µm."""
    bases = [
        ("2*2", "circle", CircularSocket(2, 2)),
        ("2*8", "circle", CircularSocket(2, 8)),
        ("square", "polygon", PolygonSocket(4, 1.5, 1.65)),
        ("hexagon", "polygon", PolygonSocket(6, 1.2, 1.26)),
    ]
    return [
        Socket(f"{name} fit{grade_um:g}", family, with_clearance(spec, grade_um * 1e-3))
        for name, family, spec in bases
    ]


def sockets(seed: int) -> list[Socket]:
    """The probed sockets; the bent-pin 2*1 is drawn from ``seed`` (redrawn while empty)."""
    rng = np.random.default_rng([seed, 12])
    while True:
        bent = tolins.sample_defects(CircularSocket(2, 1), 0.12, rng)
        if tolerance_centre(bent) is not None:
            break
    return [
        Socket("2*2", "circle", CircularSocket(2, 2)),
        Socket("2*8", "circle", CircularSocket(2, 8)),
        Socket("2*1 bent", "circle", bent),
        Socket("square", "polygon", PolygonSocket(4, 1.5, 1.65)),
        Socket("pentagon", "polygon", PolygonSocket(5, 1.5, 1.65)),
        Socket("hexagon", "polygon", PolygonSocket(6, 1.2, 1.26)),
        Socket("triangle", "polygon", PolygonSocket(3, 1.5, 1.65)),
    ]


# --- geometry: pin points, distances, probes -------------------------------------------


def pin_points(spec) -> np.ndarray:
    """The points the tolerance constrains, workpiece frame: round pins' centres, peg vertices."""
    if isinstance(spec, CircularSocket):
        return spec.pin_centers
    return polygon_vertices(spec.sides, spec.pin_circumradius)


def moved(points: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """``points`` ``(k, 2)`` moved by ``poses`` ``(..., 3)``: ``(..., k, 2)``."""
    c, s = np.cos(poses[..., 2:3]), np.sin(poses[..., 2:3])
    x = c * points[:, 0] - s * points[:, 1] + poses[..., 0:1]
    y = s * points[:, 0] + c * points[:, 1] + poses[..., 1:2]
    return np.stack([x, y], axis=-1)


def displacement(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Largest displacement (mm) of a pin point between poses ``a`` and ``b`` ``(..., 3)``."""
    return np.max(np.linalg.norm(moved(points, b) - moved(points, a), axis=-1), axis=-1)


def unit_steps(points: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """``directions`` ``(n, 3)`` scaled so that a unit step moves the farthest pin point 1 mm
    (to first order about the identity)."""
    perp = np.stack([-points[:, 1], points[:, 0]], axis=1)
    speed = directions[:, None, :2] + directions[:, None, 2:3] * perp
    return directions / np.max(np.linalg.norm(speed, axis=-1), axis=-1, keepdims=True)


def first_change(
    spec, start: np.ndarray, directions: np.ndarray, reach: float, samples: int = 24
) -> np.ndarray:
    """Step ``t`` (in units of ``directions``) of the first change of ``contains`` along
    each direction from ``start`` (``inf`` if none within ``reach``); 40 bisections."""
    state = bool(contains(spec, start))
    ts = reach * np.arange(1, samples + 1) / samples
    grid = contains(spec, start + ts[:, None, None] * directions)  # (samples, n)
    changed = grid != state
    found = changed.any(axis=0)
    first = np.where(found, changed.argmax(axis=0), 0)
    hi = ts[first]
    lo = np.where(first > 0, ts[np.maximum(first - 1, 0)], 0.0)
    for _ in range(40):
        mid = (lo + hi) / 2
        flip = contains(spec, start + mid[:, None] * directions) != state
        hi, lo = np.where(flip, mid, hi), np.where(flip, lo, mid)
    return np.where(found, hi, np.inf)


def boundary_distance(spec, pose: np.ndarray, rng, directions: int, hint: np.ndarray) -> float:
    """Signed smallest pin-point displacement (mm) that changes ``contains`` at ``pose``
    (positive outside). Direction search, an upper bound on the true distance."""
    points = pin_points(spec)
    reach = 0.2  # mm of pin displacement; probes lie within 0.05 mm of the boundary
    raw = rng.normal(size=(directions, 3))
    raw[:, 2] /= np.max(np.linalg.norm(points, axis=1))  # rotations on a par with shifts
    candidates = unit_steps(points, np.vstack([hint, -hint, raw]))
    best_t, best_d = math.inf, None
    for spread in (None, 0.3, 0.1, 0.03):
        if spread is not None:
            if best_d is None:
                break
            jitter = rng.normal(size=(max(directions // 4, 8), 3)) * spread
            jitter[:, 2] /= np.max(np.linalg.norm(points, axis=1))
            candidates = unit_steps(points, best_d + jitter)
        t = first_change(spec, pose, candidates, reach)
        k = int(np.argmin(t))
        if t[k] < best_t:
            best_t, best_d = float(t[k]), candidates[k]
    if best_d is None:
        return math.inf
    target = pose + best_t * best_d
    distance = float(displacement(points, pose, target))
    return distance if not contains(spec, pose) else -distance


def tolerance_centre(spec) -> np.ndarray | None:
    """A pose deep inside the tolerance: the nominal pose of a nominal socket, else the
    grid pose (refined twice) with the largest slack; ``None`` if the tolerance is empty."""
    if not (isinstance(spec, CircularSocket) and spec.is_defective):
        return np.zeros(3)
    pins, holes, clearance = spec.pin_centers, spec.hole_centers, spec.clearance
    centre, half = np.zeros(3), np.array([0.5, 0.5, 0.15])
    best = -math.inf
    for _ in range(4):
        axes = [np.linspace(c - h, c + h, 41) for c, h in zip(centre, half, strict=True)]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        gap = np.linalg.norm(moved(pins, grid) - holes, axis=-1)
        slack = clearance - gap.max(axis=-1)
        k = int(np.argmax(slack))
        centre, best, half = grid[k], float(slack[k]), half / 8
    return centre if best > 0 else None


@dataclass(frozen=True)
class Probe:
    socket: str
    index: int
    pose: np.ndarray  # [x, y, theta]
    offset_um: float  # along the probe direction, signed (positive outward)
    distance_um: float  # signed distance from the boundary (positive outside)
    inside: bool  # contains(spec, pose)


def make_probes(
    sock: Socket,
    n: int,
    seed: int,
    band_max_um: float,
    directions: int,
    offsets_um: np.ndarray | None = None,
) -> list[Probe]:
    """``n`` probes near the boundary of ``sock``'s tolerance (see the module docstring);
    ``offsets_um`` ``(n,)`` replaces the random offsets along the probe directions."""
    spec = sock.spec
    rng = np.random.default_rng([seed, sum(map(ord, sock.name))])
    centre = tolerance_centre(spec)
    nominal = spec.nominal() if isinstance(spec, CircularSocket) else spec
    ext = extents(nominal)
    scale = np.array([ext.x[1], ext.y[1], ext.theta[1]])
    points = pin_points(spec)
    probes = []
    for i in range(n):
        u = rng.normal(size=3)
        u = unit_steps(points, (u / np.linalg.norm(u) * scale)[None])[0]
        t = first_change(spec, centre, u[None], reach=1.0, samples=64)[0]
        boundary = centre + t * u
        offset = rng.uniform(-band_max_um, band_max_um) * 1e-3
        if offsets_um is not None:
            offset = float(offsets_um[i]) * 1e-3
        # Exact pin displacement `offset` along u from the boundary (u is first-order).
        lo, hi = 0.0, 2 * abs(offset) + 1e-12
        for _ in range(50):
            mid = (lo + hi) / 2
            big = displacement(points, boundary, boundary + math.copysign(mid, offset) * u)
            lo, hi = (lo, mid) if big > abs(offset) else (mid, hi)
        pose = boundary + math.copysign(lo, offset) * u
        distance = boundary_distance(spec, pose, rng, directions, u)
        probes.append(
            Probe(sock.name, i, pose, offset * 1e3, distance * 1e3, bool(contains(spec, pose)))
        )
    return probes


# --- physics -------------------------------------------------------------------------

_local = threading.local()


def env_for(sock: Socket) -> InsertionEnv:
    """This thread's env of ``sock`` (made once per thread)."""
    envs = getattr(_local, "envs", None)
    if envs is None:
        envs = _local.envs = {}
    key = (sock.name, sock.physics_version, sock.robot)
    if key not in envs:
        envs[key] = InsertionEnv(
            sock.spec,
            measurement_noise=0,
            physics_version=sock.physics_version,
            robot=sock.robot,
        )
    return envs[key]


def push(sock: Socket, pose: np.ndarray, speed: float) -> tuple[str, float, float, np.ndarray]:
    """Drop ``sock``'s workpiece at ``pose`` and push down: (outcome, final z, seconds,
    the part's true ``[x, y, theta]`` at the reset: ``pose`` itself but for the Panda,
    whose closing fingers move the part in the hand)."""
    start = time.perf_counter()
    env = env_for(sock)
    _, info = env.reset(options={"pose": [*pose, START_HEIGHT]})
    true = np.asarray(info["pose"])[:3].copy()
    for _ in range(STEPS[speed]):
        _, _, terminated, truncated, info = env.step([0.0, 0.0, 0.0, -speed])
        if terminated or truncated:
            break
    z = float(info["pose"][3])
    if info["success"]:
        outcome = "in"
    elif z > -SURFACE_UM * 1e-3:
        outcome = "surface"
    else:
        outcome = "stuck"
    return outcome, z, time.perf_counter() - start, true


def at_true_poses(sock: Socket, probes: list[Probe], results, seed: int, directions: int):
    """``probes`` judged again where the part truly was at the reset (``results[k][3]``):
    the Panda's probes, whose grasp moved the part from the pose asked."""
    rng = np.random.default_rng([seed, 7, sum(map(ord, sock.name))])
    hint = np.array([1.0, 0.0, 0.0])
    judged = []
    for probe, result in zip(probes, results, strict=True):
        pose = result[3]
        distance = boundary_distance(sock.spec, pose, rng, directions, hint)
        inside = bool(contains(sock.spec, pose))
        judged.append(
            dataclasses.replace(probe, pose=pose, distance_um=distance * 1e3, inside=inside)
        )
    return judged


def run_chunk(sock: Socket, chunk: list[Probe], speed: float) -> list[tuple]:
    return [push(sock, p.pose, speed) for p in chunk]


def run_physics(pool, sock: Socket, probes: list[Probe], speed: float, chunk: int = 8):
    """Outcomes of ``probes`` in order, computed in chunks on ``pool``."""
    futures = [
        pool.submit(run_chunk, sock, probes[i : i + chunk], speed)
        for i in range(0, len(probes), chunk)
    ]
    return [result for future in futures for result in future.result()]


# --- diagnosis -----------------------------------------------------------------------


def describe_contacts(sock: Socket, pose: np.ndarray, speed: float) -> list[str]:
    """The contacts when the pins' descent is decided: at the first physics step with
    contact, and at the first step where the tips are 20 µm below the top (if any)."""
    env = InsertionEnv(sock.spec, measurement_noise=0, physics_version=sock.physics_version)
    env.reset(options={"pose": [*pose, START_HEIGHT]})
    m, d = env.backend.model, env.backend.data
    stepper = env.backend.stepper
    stepper.command(np.array([0.0, 0.0, 0.0, -speed]))
    lines, seen_first, seen_deep = [], False, False
    for step in range(STEPS[speed] * env.backend.substeps):
        if step % env.backend.substeps == 0:
            d.act[:] = d.qpos
        mujoco.mj_step(m, d)
        z = d.qpos[2]
        if (d.ncon and not seen_first) or (z < -0.02 and not seen_deep):
            seen_first = seen_first or d.ncon > 0
            seen_deep = seen_deep or z < -0.02
            lines.append(
                f"    t={d.time * 1e3:.0f} ms z={z * 1e3:+.2f} µm "
                f"pose x={d.qpos[0]:+.5f} y={d.qpos[1]:+.5f} th={d.qpos[3]:+.5f}"
            )
            for c in d.contact[: d.ncon]:
                names = sorted(
                    mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in (c.geom1, c.geom2)
                )
                n = c.frame[:3]
                lines.append(
                    f"      {names[0]:>14} / {names[1]:<6} normal ({n[0]:+.3f}, {n[1]:+.3f}, "
                    f"{n[2]:+.3f}) depth {-c.dist * 1e3:.2f} µm at ({c.pos[0]:+.4f}, "
                    f"{c.pos[1]:+.4f}, {c.pos[2] * 1e3:+.1f} µm)"
                )
            if seen_deep:
                break
    return lines


# --- report --------------------------------------------------------------------------


def summarise(probes: list[Probe], results, band_um: float) -> dict:
    distance = np.array([p.distance_um for p in probes])
    inside = np.array([p.inside for p in probes])
    inserted = np.array([r[0] == "in" for r in results])
    disagree = inserted != inside
    outside_band = np.abs(distance) > band_um
    dis_abs = np.abs(distance[disagree])
    return {
        "probes": len(probes),
        "inside": int(inside.sum()),
        "outside_band": int(outside_band.sum()),
        "agree_rate": float(1 - disagree[outside_band].mean()) if outside_band.any() else math.nan,
        "disagree": int(disagree.sum()),
        "disagree_out": int((disagree & outside_band).sum()),
        "capture": int((disagree & ~inside).sum()),
        "jam": int((disagree & inside).sum()),
        "max_um": float(dis_abs.max()) if dis_abs.size else 0.0,
        "p99_um": float(np.percentile(dis_abs, 99)) if dis_abs.size else 0.0,
        "capture_max_um": float(distance[disagree & ~inside].max(initial=0.0)),
        "jam_max_um": float(max(0.0, -distance[disagree & inside].min(initial=0.0))),
        "stuck": int(sum(r[0] == "stuck" for r in results)),
        "seconds": float(sum(r[2] for r in results)),
        "disagreements": [
            (p, r) for p, r, bad in zip(probes, results, disagree, strict=True) if bad
        ],
    }


def table(rows: list[tuple[str, str, dict]], band_um: float) -> str:
    head = (
        f"| socket | push | probes | agree outside ±{band_um:g} µm | disagree (out of band) | "
        "capture / jam | max |d| µm | p99 |d| µm | capture max µm | jam max µm | stuck | "
        "core-s |\n|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
    )
    lines = [head]
    for name, push_name, s in rows:
        rate = f"{100 * s['agree_rate']:.2f} % ({s['outside_band']})"
        lines.append(
            f"| {name} | {push_name} | {s['probes']} | {rate} | {s['disagree']} "
            f"({s['disagree_out']}) | {s['capture']} / {s['jam']} | {s['max_um']:.1f} | "
            f"{s['p99_um']:.1f} | {s['capture_max_um']:.1f} | {s['jam_max_um']:.1f} | "
            f"{s['stuck']} | {s['seconds']:.1f} |"
        )
    return "\n".join(lines)


def apply_model_changes(hole_sides: int | None) -> None:
    """Experiment: round holes as ``hole_sides``-gons (face distance = hole radius)."""
    if hole_sides is not None:
        specs_module.CIRCLE_HOLE_SIDES = hole_sides  # read by CircularSocket.hole_circumradius
        model_module.CIRCLE_HOLE_SIDES = hole_sides  # read by tolins.mjcf.model.hole_shape


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--probes", type=int, default=400, help="probes per socket")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--quick", action="store_true", help="a smoke test (< 30 s)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--band", type=float, help="half-width (µm) of the band (default 10)")
    parser.add_argument("--band-max", type=float, help="largest offset (µm) (default 50)")
    parser.add_argument("--grade", type=float, help="radial clearance (µm) of graded sockets")
    parser.add_argument("--directions", type=int, default=96, help="for the distance search")
    parser.add_argument("--no-slow", action="store_true", help="skip the 0.5 mm/s push")
    parser.add_argument("--only", nargs="*", help="socket names to run (default: all)")
    parser.add_argument("--diagnose", type=int, default=0, help="print contacts of K cases")
    parser.add_argument("--hole-sides", type=int, help="experiment: round holes as n-gons")
    parser.add_argument(
        "--physics-version",
        type=int,
        choices=(1, 2, 3),
        default=1,
        help="the env ids' -v1, -v2 or -v3 (the Panda's only)",
    )
    parser.add_argument(
        "--robot",
        choices=("free", "panda"),
        default="free",
        help="what holds the part (panda: probes judged at the part's true pose at the reset)",
    )
    args = parser.parse_args(argv)
    if args.robot == "panda" and args.physics_version == 1:
        parser.error("--robot panda steps the -v2 or -v3 physics; add --physics-version 2 or 3")
    if args.robot == "free" and args.physics_version == 3:
        parser.error("--physics-version 3 is the Panda's only; add --robot panda")
    if args.robot == "panda" and args.diagnose:
        parser.error("--diagnose reads the free body's servos; allowed: --robot free")
    if args.quick:
        args.probes, args.directions, args.no_slow = min(args.probes, 24), 32, True
    if args.band is None:
        args.band = 10.0 if args.grade is None else 0.05 * args.grade
    if args.band_max is None:
        args.band_max = 50.0 if args.grade is None else 0.25 * args.grade
    apply_model_changes(args.hole_sides)
    started = time.perf_counter()
    print(
        f"physics vs geometry: {args.probes} probes per socket, seed {args.seed}, "
        f"{args.workers} workers, band ±{args.band:g} µm, offsets ±{args.band_max:g} µm, "
        f"round holes {specs_module.CIRCLE_HOLE_SIDES}-gons, physics -v{args.physics_version}, "
        f"robot {args.robot}; "
        f"Python "
        f"{platform.python_version()}, MuJoCo {mujoco.__version__}, NumPy {np.__version__}, "
        f"{os.cpu_count()} CPUs"
    )
    pool_of = sockets(args.seed) if args.grade is None else graded_sockets(args.grade)
    selected = [
        dataclasses.replace(s, physics_version=args.physics_version, robot=args.robot)
        for s in pool_of
        if not args.only or s.name in args.only
    ]
    speeds = [FAST] if args.no_slow else [FAST, SLOW]
    rows, all_ok = [], True
    with concurrent.futures.ThreadPoolExecutor(args.workers) as pool:
        for sock in selected:
            t0 = time.perf_counter()
            probes = make_probes(sock, args.probes, args.seed, args.band_max, args.directions)
            t_geom = time.perf_counter() - t0
            for speed in speeds:
                t1 = time.perf_counter()
                results = run_physics(pool, sock, probes, speed)
                judged = probes
                if sock.robot != "free":
                    judged = at_true_poses(sock, probes, results, args.seed, args.directions)
                s = summarise(judged, results, args.band)
                name = f"{speed:g} mm/s"
                rows.append((sock.name, name, s))
                ok = not s["agree_rate"] < GOAL
                all_ok &= ok
                print(
                    f"{sock.name:>9} {name:>8}: agree {100 * s['agree_rate']:6.2f} % outside "
                    f"the band ({s['outside_band']} probes), {s['disagree']} disagreements "
                    f"(capture {s['capture']}, jam {s['jam']}, max |d| {s['max_um']:.1f} µm), "
                    f"probes {t_geom:.1f} s, physics {time.perf_counter() - t1:.1f} s wall",
                    flush=True,
                )
                worst = sorted(s["disagreements"], key=lambda pr: -abs(pr[0].distance_um))
                for probe, result in worst[: args.diagnose]:
                    print(
                        f"  disagreement: pose {np.array2string(probe.pose, precision=6)} "
                        f"distance {probe.distance_um:+.1f} µm (offset {probe.offset_um:+.1f}) "
                        f"geometry {'in' if probe.inside else 'out'}, physics {result[0]} "
                        f"z={result[1]:+.4f}"
                    )
                    print("\n".join(describe_contacts(sock, probe.pose, speed)))
    print()
    print(table(rows, args.band))
    print()
    verdict = "met" if all_ok else "NOT met"
    print(f"goal >= {100 * GOAL:g} % agreement outside ±{args.band:g} µm: {verdict}")
    print(f"total {time.perf_counter() - started:.0f} s wall")
    return 0


if __name__ == "__main__":
    sys.exit(main())
