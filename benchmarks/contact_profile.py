"""Where a control step's time goes, per socket and regime.

Usage::

    python benchmarks/contact_profile.py                  # every socket and regime
    python benchmarks/contact_profile.py --eager-sensors  # sensors in every physics step
    python benchmarks/contact_profile.py --contact-pairs  # make_mjcf(..., contact_pairs=True)
    python benchmarks/contact_profile.py --sockets 2*2 --regimes blocked --steps 8

For each socket (2*2, 2*8, 2*20, square, hexagon) and regime (below) it runs ``--steps``
control steps through the env's own :class:`~tolins.physics.servo.ServoStepper`
from the regime's start pose and reports:

* ``ms/step``: CPU milliseconds of the stepping thread per control step (250 physics
  steps; ``time.thread_time``, which a busy machine disturbs less than the wall clock),
  best of two uninstrumented runs;
* the split of a physics step's time by MuJoCo's own timers (``data.timer``, read with
  ``mjcb_time = time.thread_time`` in a third, instrumented run): ``broad``
  (``mjTIMER_COL_BROAD``), ``narrow`` (``mjTIMER_COL_NARROW``: midphase and narrowphase),
  ``make`` (``POS_MAKE`` + ``POS_PROJECT``: building the constraints), ``solver``
  (``mjTIMER_CONSTRAINT``), ``sensors`` (``FORWARD`` minus its timed stages) and ``rest``
  (kinematics, actuation, integration: ``STEP`` minus the above), in per cent;
* ``pairs``: narrowphase calls per physics step (``mjcb_contactfilter`` counts the geom
  pairs that reached the bitmask filter, i.e. passed the midphase's sphere and box tests;
  not with ``--contact-pairs``: explicit ``<pair>``s bypass the callback), ``contacts``:
  mean ``ncon`` at the end of each control step, ``iters``: its solver iterations.

Regimes (pose ``[x, y, theta, z]``, action ``[ux, uy, utheta, uz]``; circle offsets in mm
beside the 0.2 mm clearance, polygon offsets beside theirs):

* ``free``: far above the board, moving slowly (no contact);
* ``approaching``: off the holes, tips 0.6 mm over the board descending to 0.1 mm;
* ``blocked``: off the holes, pressed onto the board at full speed;
* ``sliding``: in the holes, pressed against a wall while descending slowly;
* ``inserted``: centred in the holes, descending inside them (no contact).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass

import mujoco
import numpy as np

from tolins import CircularSocket, PolygonSocket
from tolins.mjcf import make_mjcf
from tolins.physics.servo import ServoStepper

SUBSTEPS = 250
SOCKETS = {
    "2*2": CircularSocket(2, 2),
    "2*8": CircularSocket(2, 8),
    "2*20": CircularSocket(2, 20),
    "square": PolygonSocket(4, 1.5, 1.65),
    "hexagon": PolygonSocket(6, 1.2, 1.26),
}


@dataclass(frozen=True)
class Regime:
    pose: tuple[float, float, float, float]
    action: tuple[float, float, float, float]


#: (circle regime, polygon regime) by name.
REGIMES = {
    "free": (Regime((1, 1, 0, 15), (0.1, 0.1, 0, -0.5)),) * 2,
    "approaching": (Regime((0.5, 0, 0, 0.6), (0, 0, 0, -0.05)),) * 2,
    "blocked": (
        Regime((0.5, 0, 0, 0.05), (0, 0, 0, -2.5)),
        Regime((0.3, 0, 0, 0.05), (0, 0, 0, -2.5)),
    ),
    "sliding": (
        Regime((0.1, 0, 0, -0.5), (1, 0, 0, -0.1)),
        Regime((0.02, 0, 0, -0.5), (1, 0, 0, -0.1)),
    ),
    "inserted": (
        Regime((0.05, 0, 0, -0.5), (0, 0, 0, -0.5)),
        Regime((0.01, 0, 0, -0.5), (0, 0, 0, -0.5)),
    ),
}


def regime(socket_name: str, name: str) -> Regime:
    """The regime ``name`` for the socket ``socket_name``."""
    circle, polygon = REGIMES[name]
    return circle if isinstance(SOCKETS[socket_name], CircularSocket) else polygon


def run(stepper: ServoStepper, case: Regime, steps: int, probe=None) -> float:
    """Seconds for ``steps`` control steps from ``case``'s pose; ``probe()`` after each."""
    stepper.reset(np.array(case.pose, dtype=float))
    action = np.array(case.action, dtype=float)
    t0 = time.thread_time()
    for _ in range(steps):
        stepper.step(action, SUBSTEPS)
        if probe is not None:
            probe()
    return time.thread_time() - t0


def profile(
    model: mujoco.MjModel, case: Regime, steps: int, count_pairs: bool, lazy_sensors: bool
) -> dict:
    """One socket and regime: timing, timer split and counts (see the module docstring)."""
    data = mujoco.MjData(model)
    stepper = ServoStepper(model, data)
    stepper.lazy_sensors = lazy_sensors
    seconds = min(run(stepper, case, steps) for _ in range(2))
    contacts, iters, pairs = [], [], [0]

    def probe() -> None:
        contacts.append(data.ncon)
        iters.append(int(data.solver_niter[0]))

    def count(m, d, g1, g2) -> int:
        pairs[0] += 1
        return int(
            not (
                m.geom_contype[g1] & m.geom_conaffinity[g2]
                or m.geom_contype[g2] & m.geom_conaffinity[g1]
            )
        )

    mujoco.set_mjcb_time(time.thread_time)
    if count_pairs:
        mujoco.set_mjcb_contactfilter(count)
    try:
        stepper.reset(np.array(case.pose, dtype=float))
        for timer in data.timer:
            timer.duration, timer.number = 0.0, 0
        run(stepper, case, steps, probe)
    finally:
        mujoco.set_mjcb_time(None)
        mujoco.set_mjcb_contactfilter(None)
    timer = {
        t.name[len("mjTIMER_") :]: data.timer[t].duration
        for t in mujoco.mjtTimer.__members__.values()
        if t.name != "mjNTIMER"
    }
    forward = timer["FORWARD"]
    sensors = forward - sum(timer[k] for k in ("POSITION", "VELOCITY", "ACTUATION", "CONSTRAINT"))
    split = {
        "broad": timer["COL_BROAD"],
        "narrow": timer["COL_NARROW"],
        "make": timer["POS_MAKE"] + timer["POS_PROJECT"],
        "solver": timer["CONSTRAINT"],
        "sensors": sensors,
    }
    split["rest"] = timer["STEP"] - sum(split.values())
    total = timer["STEP"]
    return {
        "ms": seconds / steps * 1e3,
        "split": {k: 100 * v / total for k, v in split.items()},
        "pairs": pairs[0] / (steps * SUBSTEPS) if count_pairs else math.nan,
        "contacts": float(np.mean(contacts)),
        "iters": float(np.mean(iters)),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sockets", nargs="+", default=list(SOCKETS), choices=list(SOCKETS))
    parser.add_argument("--regimes", nargs="+", default=list(REGIMES), choices=list(REGIMES))
    parser.add_argument("--steps", type=int, default=20, help="control steps per run")
    parser.add_argument(
        "--eager-sensors", action="store_true", help="sensors in every physics step (before 19)"
    )
    parser.add_argument(
        "--contact-pairs", action="store_true", help="make_mjcf(..., contact_pairs=True)"
    )
    args = parser.parse_args(argv)
    print(
        f"mujoco {mujoco.__version__}; contact_pairs={args.contact_pairs}, "
        f"lazy_sensors={not args.eager_sensors}"
    )
    parts = ("broad", "narrow", "make", "solver", "sensors", "rest")
    header = f"{'socket':<8} {'regime':<12} {'ms/step':>8} " + " ".join(f"{p:>7}" for p in parts)
    header += f" {'pairs':>7} {'contacts':>8} {'iters':>6}"
    print(header)
    for name in args.sockets:
        xml = make_mjcf(SOCKETS[name], contact_pairs=args.contact_pairs)
        model = mujoco.MjModel.from_xml_string(xml)
        for reg in args.regimes:
            r = profile(
                model,
                regime(name, reg),
                args.steps,
                count_pairs=not args.contact_pairs,
                lazy_sensors=not args.eager_sensors,
            )
            split = " ".join(f"{r['split'][p]:>6.0f}%" for p in parts)
            print(
                f"{name:<8} {reg:<12} {r['ms']:>8.2f} {split} {r['pairs']:>7.1f} "
                f"{r['contacts']:>8.1f} {r['iters']:>6.1f}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
