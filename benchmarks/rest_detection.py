"""Rest detection: what stopping a control step's physics once the workpiece rests would
save, and what it would change in the state the step reports.

Usage::

    python benchmarks/rest_detection.py                      # 2*2, 30 episodes per regime
    python benchmarks/rest_detection.py --env tolins/Circle2x8-v2 --episodes 10
    python benchmarks/rest_detection.py --json rest.json

**What is measured.** Seeded episodes of four regimes: the safe and the efficient expert,
a uniformly random policy, and ``press`` (straight down at full speed from the start pose,
so that a misaligned workpiece lands on the board's top and is pushed into it). They run
through ``env.step`` as usual. Before each control step the simulation's whole state is
saved; after it, the step is replayed on a second ``MjData`` from that state one 1 ms
physics step at a time (the servos re-anchored as the stepper does, the same command),
recording every joint's speed, the servos' forces, the pins' summed normal force, the
board's wrench and the contacts. The replay must end where ``env.step`` ended, bit for bit
(counted as ``replay_mismatch`` otherwise: the stepper's ``mj_step(nstep=k)`` is k single
steps, and sensors do not act on the state). Control steps that ``-v2`` ran on its longer
free-flight step are left out: rest needs contact, and contact runs on the 1 ms step.

**The rule.** The workpiece is *at rest* from the first physics step after which, for
``--hold`` consecutive steps, every joint's speed is below ``v`` (mm/s for x, y, z; rad/s for
theta, i.e. mm/s 1 mm from its axis) and every servo either has no command or
pushes at its force limit in the commanded direction (so its force cannot change while
the set-point runs on). Skipping the rest of the control step would report the state at
that point: pose, wrench, the pins' force for every remaining peak-force read, the
contacts. Against the reference (the step run through) the script reports, per threshold
``v``: the share of contact physics steps that would be skipped, and the largest
deviations of the reported pose (µm, µrad), the wrench and the peak force (mN), and the
control steps whose contact set differs.

The issue's bound is ≤ 0.1 µm and ≤ 1 mN on everything reported.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass

import gymnasium as gym
import mujoco
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.mjcf.layout import FORCE_SCALE
from tolins.paper import A_MAX
from tolins.physics.schedule import contact_chunks
from tolins.physics.servo import board_wrench
from tolins.policies import EXPERTS

#: The "press" regime's action: straight down at full speed, [ux, uy, utheta, uz].
PRESS = A_MAX * [0.0, 0.0, 0.0, -1.0]
THRESHOLDS = (1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
STATE = mujoco.mjtState.mjSTATE_INTEGRATION


@dataclass
class Trace:
    """One control step replayed physics step by physics step (row i: after step i + 1)."""

    speed: np.ndarray  # (n,) the largest joint speed
    servo_steady: np.ndarray  # (n,) every servo idle or at its limit
    pose: np.ndarray  # (n, 4) [x, y, theta, z]
    wrench: np.ndarray  # (n, 4) board wrench, model units
    touch: np.ndarray  # (n,) summed pin normal force, model units
    contacts: list[frozenset]  # (n,) the geom pairs in contact


def replay(model, scratch, saved, ctrl, nstep: int, layout) -> Trace:
    """The control step from the saved state, one physics step at a time."""
    mujoco.mj_setState(model, scratch, saved, STATE)
    scratch.ctrl[:] = ctrl
    scratch.act[:] = scratch.qpos
    mujoco.mj_forward(model, scratch)
    limit = model.actuator_forcerange[:, 1]
    rows = {k: [] for k in ("speed", "servo_steady", "pose", "wrench", "touch", "contacts")}
    for _ in range(nstep):
        mujoco.mj_step(model, scratch)
        force = scratch.actuator_force
        idle = ctrl == 0
        pushing = (np.abs(force) >= limit * (1 - 1e-9)) & (np.sign(force) == np.sign(ctrl))
        rows["speed"].append(np.max(np.abs(scratch.qvel)))
        rows["servo_steady"].append(bool(np.all(idle | pushing)))
        rows["pose"].append(scratch.qpos[layout.pose_joint].copy())
        theta = scratch.qpos[layout.pose_joint[2]]
        force_sensor = scratch.sensordata[layout.force].tolist()
        rows["wrench"].append(
            board_wrench(theta, force_sensor, scratch.sensordata[layout.torque_z]) / FORCE_SCALE
        )
        rows["touch"].append(float(np.sum(scratch.sensordata[layout.touch])))
        n = scratch.ncon
        pairs = zip(scratch.contact.geom1[:n], scratch.contact.geom2[:n], strict=True)
        rows["contacts"].append(frozenset(pairs))
    return Trace(
        np.array(rows["speed"]),
        np.array(rows["servo_steady"]),
        np.array(rows["pose"]),
        np.array(rows["wrench"]),
        np.array(rows["touch"]),
        rows["contacts"],
    )


def rest_start(trace: Trace, threshold: float, hold: int) -> int | None:
    """The index of the first physics step from which the workpiece is at rest (the state
    reported if the rest were skipped), ``None`` if it never is."""
    calm = (trace.speed < threshold) & trace.servo_steady
    run = 0
    for i, ok in enumerate(calm):
        run = run + 1 if ok else 0
        if run == hold:
            return i
    return None


@dataclass
class Deviation:
    """What skipping from the rest on would change, over all control steps of a run."""

    threshold: float
    contact_steps: int = 0
    skipped_steps: int = 0
    control_steps_at_rest: int = 0
    pose_um: float = 0.0
    theta_urad: float = 0.0
    wrench_mN: float = 0.0
    peak_mN: float = 0.0
    contact_set_differs: int = 0

    def add(self, trace: Trace, reads: list[int], hold: int) -> None:
        n = len(trace.speed)
        self.contact_steps += n
        rest = rest_start(trace, self.threshold, hold)
        if rest is None:
            return
        self.control_steps_at_rest += 1
        self.skipped_steps += n - 1 - rest
        delta = trace.pose[-1] - trace.pose[rest]
        self.pose_um = max(self.pose_um, 1e3 * float(np.max(np.abs(delta[[0, 1, 3]]))))
        self.theta_urad = max(self.theta_urad, 1e6 * abs(float(delta[2])))
        wrench = float(np.max(np.abs(trace.wrench[-1] - trace.wrench[rest])))
        self.wrench_mN = max(self.wrench_mN, wrench)
        true_peak = max(trace.touch[i] for i in reads)
        skipped_peak = max([trace.touch[i] for i in reads if i <= rest] + [trace.touch[rest]])
        self.peak_mN = max(self.peak_mN, abs(true_peak - skipped_peak))
        self.contact_set_differs += trace.contacts[-1] != trace.contacts[rest]


def run(env_id: str, regime: str, episodes: int, hold: int) -> tuple[list[Deviation], dict]:
    env = gym.make(env_id).unwrapped
    deviations = [Deviation(t) for t in THRESHOLDS]
    counts = {"control_steps": 0, "free_flight_steps": 0, "replay_mismatch": 0}
    for seed in range(episodes):
        obs, _ = env.reset(seed=seed)
        # a defective workpiece is a new model every reset: read the simulation afresh
        backend = env.backend
        stepper, model, data = backend.stepper, backend.model, backend.data
        scratch = mujoco.MjData(model)
        saved = np.empty(mujoco.mj_stateSize(model, STATE))
        nstep = backend.substeps
        chunks = contact_chunks(nstep, stepper.checks)
        reads = [sum(chunks[: k + 1]) - 1 for k in range(len(chunks))]
        if regime == "random":
            env.action_space.seed(seed)
            act = lambda _obs: env.action_space.sample()  # noqa: E731
        elif regime == "press":
            act = lambda _obs: PRESS  # noqa: E731
        else:
            act = EXPERTS[regime]()
        done = False
        while not done:
            mujoco.mj_getState(model, data, saved, STATE)
            obs, _, terminated, truncated, _ = env.step(act(obs))
            done = terminated or truncated
            counts["control_steps"] += 1
            if stepper.step_factor > 1:
                counts["free_flight_steps"] += 1
                continue
            trace = replay(model, scratch, saved, data.ctrl.copy(), nstep, stepper.layout)
            if not np.array_equal(scratch.qpos, data.qpos):
                counts["replay_mismatch"] += 1
                continue
            for deviation in deviations:
                deviation.add(trace, reads, hold)
    return deviations, counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", default="tolins/Circle2x2-v2")
    parser.add_argument("--episodes", type=int, default=30)
    parser.add_argument("--hold", type=int, default=3, help="physics steps at rest in a row")
    parser.add_argument("--regimes", nargs="+", default=["safe", "efficient", "random", "press"])
    parser.add_argument("--json")
    args = parser.parse_args()
    report = {"env": args.env, "episodes": args.episodes, "hold": args.hold, "regimes": {}}
    print(f"{args.env}, {args.episodes} episodes per regime, rest held {args.hold} steps")
    print(
        "regime     v (mm/s)  at rest  skipped   pose µm  theta µrad  wrench mN  peak mN  contacts"
    )
    for regime in args.regimes:
        start = time.perf_counter()
        deviations, counts = run(args.env, regime, args.episodes, args.hold)
        for d in deviations:
            share = d.skipped_steps / max(d.contact_steps, 1)
            print(
                f"{regime:10s} {d.threshold:8.0e}  {d.control_steps_at_rest:7d}  {share:7.1%}"
                f"  {d.pose_um:8.4f}  {d.theta_urad:10.4f}  {d.wrench_mN:9.3f}"
                f"  {d.peak_mN:7.3f}  {d.contact_set_differs:8d}"
            )
        print(f"  {counts} ({time.perf_counter() - start:.0f} s)")
        rows = [asdict(d) for d in deviations]
        report["regimes"][regime] = {"counts": counts, "deviations": rows}
    if args.json:
        with open(args.json, "w") as file:
            json.dump(report, file, indent=1)


if __name__ == "__main__":
    main()
