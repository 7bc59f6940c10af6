"""Cheaper physics-step variants, bit-identical or not: speed-up and deviation.

Usage::

    python benchmarks/step_variants.py                         # all variants, ~10 min
    python benchmarks/step_variants.py --variants libccd --sockets 2*2 --regimes blocked

Each variant edits today's model (``make_mjcf(socket)``, lazy sensors) or its stepping:

* ``island-off``: ``<flag island="disable"/>`` (one monolithic constraint solve);
* ``midphase-off``: ``<flag midphase="disable"/>`` (all-to-all geom pairs, no BVH walk);
* ``pairs``: ``make_mjcf(socket, contact_pairs=True)``;
* ``world-board``: ``make_mjcf(socket, board_body=False)`` (the board's pieces in the
  world body: no bounding box and covariance of them in the broadphase);
* ``threadpool``: ``mujoco.mju_threadpool(data, 2)`` (narrowphase tasks on 2 threads);
* ``libccd``: ``<flag nativeccd="disable"/>`` (libccd's GJK/EPA instead of MuJoCo's own);
* ``dt2``, ``dt5``: timestep 2 or 5 ms (125 or 50 physics steps per control step; solref
  left at 0.002). Only meant for free space: the issue's "larger step while no pin can
  reach the board"; in contact it is the wrong physics of "Why 1 ms";
* ``libccd+dt5``: both.

For each socket and regime of ``contact_profile.py``, blocks of ``--steps`` control steps
of today's step and of each variant rotate (``--repeats`` rounds, fastest block kept;
the main thread's CPU time, which a busy machine disturbs less than wall time, except
for ``threadpool``, timed by the wall clock). ``x``: today's time / the variant's.
``dev``: the largest deviation of the pose from today's over the block, as the largest
of ``|dx|, |dy|`` (µm) and of ``|dtheta|`` (µrad); 0 means bit for bit.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

import mujoco
import numpy as np
from contact_profile import REGIMES, SOCKETS, regime

from tolins import make_mjcf
from tolins.physics.servo import ServoStepper

CONTROL_DT = 0.25


def _flag(xml: str, flag: str) -> str:
    return xml.replace('<flag multiccd="disable"', f'<flag multiccd="disable" {flag}', 1)


def _timestep(xml: str, dt: float) -> str:
    return xml.replace('timestep="0.001"', f'timestep="{dt:g}"', 1)


#: name -> (edit of the MJCF, number of threads of the pool or 0)
VARIANTS: dict[str, tuple[Callable[[str], str] | None, int]] = {
    "island-off": (lambda x: _flag(x, 'island="disable"'), 0),
    "midphase-off": (lambda x: _flag(x, 'midphase="disable"'), 0),
    "pairs": (None, 0),
    "world-board": (None, 0),
    "threadpool": (lambda x: x, 2),
    "libccd": (lambda x: _flag(x, 'nativeccd="disable"'), 0),
    "dt2": (lambda x: _timestep(x, 0.002), 0),
    "dt5": (lambda x: _timestep(x, 0.005), 0),
    "libccd+dt5": (lambda x: _timestep(_flag(x, 'nativeccd="disable"'), 0.005), 0),
}


def build(socket, variant: str | None) -> tuple[ServoStepper, int]:
    """A stepper of today's model or of ``variant``, and its physics steps per control step."""
    if variant == "pairs":
        xml = make_mjcf(socket, contact_pairs=True)
    elif variant == "world-board":
        xml = make_mjcf(socket, board_body=False)
    else:
        xml = make_mjcf(socket)
        if variant is not None:
            xml = VARIANTS[variant][0](xml)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    if variant is not None and VARIANTS[variant][1]:
        mujoco.mju_threadpool(data, VARIANTS[variant][1])
    return ServoStepper(model, data), round(CONTROL_DT / model.opt.timestep)


def block(stepper: ServoStepper, nstep: int, case, steps: int, clock) -> tuple[float, np.ndarray]:
    """Time of ``steps`` control steps from ``case``'s pose, and the poses after each."""
    stepper.reset(np.array(case.pose, dtype=float))
    action = np.array(case.action, dtype=float)
    poses = []
    t0 = clock()
    for _ in range(steps):
        poses.append(stepper.step(action, nstep).pose)
    return clock() - t0, np.array(poses)


def compare(socket_name: str, regime_name: str, variants: list[str], steps: int, repeats: int):
    """``{variant: (speed-up, dev µm, dev µrad)}`` against today's step."""
    socket, case = SOCKETS[socket_name], regime(socket_name, regime_name)
    runs = {"today": build(socket, None), **{v: build(socket, v) for v in variants}}
    clocks = {v: time.perf_counter if v == "threadpool" else time.thread_time for v in runs}
    best, poses = dict.fromkeys(runs, math.inf), {}
    names = list(runs)
    for i in range(repeats):
        for k in range(len(names)):
            name = names[(i + k) % len(names)]
            stepper, nstep = runs[name]
            t, poses[name] = block(stepper, nstep, case, steps, clocks[name])
            best[name] = min(best[name], t)
    out = {}
    for v in variants:
        diff = np.abs(poses[v] - poses["today"])
        out[v] = (best["today"] / best[v], 1e3 * diff[:, [0, 1, 3]].max(), 1e6 * diff[:, 2].max())
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--sockets", nargs="+", default=list(SOCKETS), choices=list(SOCKETS))
    parser.add_argument("--regimes", nargs="+", default=list(REGIMES), choices=list(REGIMES))
    parser.add_argument("--steps", type=int, default=4, help="control steps per block")
    parser.add_argument("--repeats", type=int, default=5, help="rounds of blocks; fastest kept")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    print(f"mujoco {mujoco.__version__}; x = today's time / variant's; dev = max |Δpose|")
    print(
        "| socket | regime | " + " | ".join(f"{v} x / dev µm, µrad" for v in args.variants) + " |"
    )
    print("|---|---|" + "---|" * len(args.variants))
    for socket_name in args.sockets:
        for regime_name in args.regimes:
            r = compare(socket_name, regime_name, args.variants, args.steps, args.repeats)
            cells = [f"{r[v][0]:.2f} / {r[v][1]:.3g}, {r[v][2]:.3g}" for v in args.variants]
            print(f"| {socket_name} | {regime_name} | " + " | ".join(cells) + " |", flush=True)
    print(f"total {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
