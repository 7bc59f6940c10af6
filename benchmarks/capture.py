"""The capture table of docs/environments.md ("Why 1 ms"): largest offsets that insert.

Usage::

    python benchmarks/capture.py                   # 4 cases × 2 speeds, about a minute
    python benchmarks/capture.py --eager-sensors   # sensors in every physics step
    python benchmarks/capture.py --physics-version 2   # the ``-v2`` physics
    python benchmarks/capture.py --robot panda --physics-version 3  # a Franka Panda (-v2, -v3)
    python benchmarks/capture.py --physics-version 2 --pins elastic-plastic  # delicate pins

For each case (2*2 socket offset in x and in theta, square and hexagon peg offset in
x) and push speed (2.5 and 0.5 mm/s), the offset is bisected between one that inserts
and one that is blocked: ``InsertionEnv(socket, measurement_noise=0)``, reset at
``[offset, 0, 0, 0.05]`` (or ``[0, 0, offset, 0.05]``), action ``[0, 0, 0, -speed]``
until success (tips 1 mm down) or 5 control steps (fast) / 10 (slow), as in
``physics_vs_geometry.py``. The result is the largest offset found to insert, to
``--resolution`` (default 0.01 µm, 0.001 mrad); the excess over the geometric limit is
the capture.

With ``--robot panda`` the part is held by the arm (``InsertionEnv(..., robot="panda")``,
``-v2`` or ``-v3``) and the offset asked of the reset is where the robot believes the part; the
grasp moves it a little as the fingers close, so the table also gives the part's true
offset at the reset (``info["pose"]``) at the boundary found, and the capture over the
geometric limit of that true offset.

With ``--pins elastic-plastic`` the round pins bend (``docs/delicate.md``; the polygon
cases, whose pegs do not, are left out): the bracket is widened (a compliant pin slides in
from farther), and the table adds the largest permanent tip offset (µm) the push left at
the boundary found.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np

from tolins import CircularSocket, PolygonSocket
from tolins.envs import InsertionEnv
from tolins.physics.servo import ServoStepper

FAST, SLOW = 2.5, 0.5
STEPS = {FAST: 5, SLOW: 10}


@dataclass(frozen=True)
class Case:
    name: str
    socket: object
    axis: int  # 0: x, 2: theta
    limit: float  # geometric limit (mm or rad)
    inside: float  # an offset that inserts
    outside: float  # one that is blocked


CASES = [
    Case("2*2, x", CircularSocket(2, 2), 0, 0.2, 0.195, 0.22),
    Case("2*2, θ", CircularSocket(2, 2), 2, 0.0499, 0.049, 0.054),
    Case("square, x", PolygonSocket(4, 1.5, 1.65), 0, 0.1061, 0.100, 0.12),
    Case("hexagon, x", PolygonSocket(6, 1.2, 1.26), 0, 0.0520, 0.047, 0.065),
]


def inserts(env: InsertionEnv, axis: int, offset: float, speed: float) -> tuple[bool, float]:
    """Whether a push down at ``speed`` from ``offset`` on ``axis`` inserts, and the
    part's true offset on ``axis`` at the reset (``env.last_bend``: the largest permanent
    tip offset the push left, mm, with bending pins)."""
    pose = np.array([0.0, 0.0, 0.0, 0.05])
    pose[axis] = offset
    _, info = env.reset(options={"pose": pose})
    start = float(info["pose"][axis])
    went_in = False
    for _ in range(STEPS[speed]):
        *_, terminated, truncated, info = env.step([0.0, 0.0, 0.0, -speed])
        if info["success"]:
            went_in = True
            break
        if terminated or truncated:
            break
    if "pin_bend" in info:
        env.last_bend = float(np.max(np.hypot(*info["pin_bend"].T)))
    return went_in, start


def largest_inserting(
    case: Case,
    speed: float,
    resolution: float,
    physics_version: int = 1,
    robot: str = "free",
    pins: str = "rigid",
) -> tuple[float, float, float]:
    """Bisection between ``case.inside`` and ``case.outside`` (0 and 1.5 × that for the
    Panda, whose grasp moves the part): the largest offset asked of the reset that
    inserts, and the part's true offset then (:func:`inserts`); ``ValueError`` if they do
    not bracket the change. Third: the largest permanent tip offset (mm) the push from the
    offset found left (0 with rigid pins)."""
    env = InsertionEnv(
        case.socket,
        measurement_noise=0,
        physics_version=physics_version,
        robot=robot,
        pins=pins,
    )
    env.last_bend = 0.0
    lo, hi = (case.inside, case.outside) if robot == "free" else (0.0, 1.5 * case.outside)
    if pins != "rigid":
        hi += 3 * (case.outside - case.limit)
    (low_in, true_lo), (high_in, _) = (inserts(env, case.axis, v, speed) for v in (lo, hi))
    if not low_in or high_in:
        raise ValueError(f"{case.name} at {speed} mm/s: {lo}..{hi} does not bracket the change")
    while hi - lo > resolution:
        mid = (lo + hi) / 2
        went_in, true_mid = inserts(env, case.axis, mid, speed)
        lo, hi, true_lo = (mid, hi, true_mid) if went_in else (lo, mid, true_lo)
    inserts(env, case.axis, lo, speed)
    return lo, true_lo, env.last_bend


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--resolution", type=float, default=1e-5, help="mm (x) and 1/10 of it in rad (theta)"
    )
    parser.add_argument(
        "--eager-sensors", action="store_true", help="sensors in every physics step (before 19)"
    )
    parser.add_argument(
        "--physics-version",
        type=int,
        choices=(1, 2, 3),
        default=1,
        help="the env ids' -v1, -v2 or -v3 (the Panda's only)",
    )
    parser.add_argument(
        "--robot", choices=("free", "panda"), default="free", help="what holds the part"
    )
    parser.add_argument(
        "--pins",
        choices=("rigid", "elastic-plastic"),
        default="rigid",
        help="rigid pins (the paper's) or pins that bend (round pins only)",
    )
    args = parser.parse_args(argv)
    if args.robot == "panda" and args.physics_version == 1:
        parser.error("--robot panda steps the -v2 or -v3 physics; add --physics-version 2 or 3")
    if args.robot == "free" and args.physics_version == 3:
        parser.error("--physics-version 3 is the Panda's only; add --robot panda")
    ServoStepper.lazy_sensors = not args.eager_sensors
    start = time.perf_counter()
    panda = args.robot == "panda"
    bending = args.pins != "rigid"
    extra = " true offset at the reset fast / slow | its capture fast / slow |"
    bend = " permanent tip offset there fast / slow (µm) |"
    print(
        "| case | 2.5 mm/s | 0.5 mm/s | capture fast / slow (µm or mrad) |"
        + extra * panda
        + bend * bending
    )
    print("|---|---|---|---|" + "---|---|" * panda + "---|" * bending)
    cases = [case for case in CASES if not bending or isinstance(case.socket, CircularSocket)]
    for case in cases:
        step = args.resolution / (10 if case.axis == 2 else 1)
        (fast, true_fast, bend_fast), (slow, true_slow, bend_slow) = (
            largest_inserting(case, s, step, args.physics_version, args.robot, args.pins)
            for s in (FAST, SLOW)
        )
        row = (
            f"| {case.name} ({case.limit:g}) | {fast:.5f} | {slow:.5f} | "
            f"{(fast - case.limit) * 1e3:+.1f} / {(slow - case.limit) * 1e3:+.1f} |"
        )
        if panda:
            row += (
                f" {true_fast:.5f} / {true_slow:.5f} | {(true_fast - case.limit) * 1e3:+.1f} / "
                f"{(true_slow - case.limit) * 1e3:+.1f} |"
            )
        if bending:
            row += f" {bend_fast * 1e3:.1f} / {bend_slow * 1e3:.1f} |"
        print(row)
    print(f"total {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
