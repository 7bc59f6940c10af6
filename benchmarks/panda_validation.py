"""The Panda ids against the free body: both experts, success, collisions, limits, slip, cost.

Usage::

    python benchmarks/panda_validation.py [--episodes 20] [--envs Circle2x2,Circle2x8,Square]
        [--rates 250,500,1000] [--version 2]

For each preset and its 50 µm grade, each expert runs ``--episodes`` episodes (seeds 0 …)
on ``tolins/{name}-v2`` (the free body on its servos) and on ``tolins/{name}Panda-v2`` (a
Franka Panda holding the part, :mod:`tolins.physics.panda`; ``--version 3``: the ``-v3``
ids, a firm grip and a law stiff sideways). Printed per row: success,
steps, collisions and reward (means), simulator faults (a part lost from the hand among
them); for the Panda also the largest slip of the part in the hand during an episode (its
true pose against the robot's belief, less the offset the grasp settled at), the share of
law updates with a motor at its torque limit, the closest approach of any joint to its
limit, and the wall time per control step against the free body's (goal ≤ 2×).

Then, on the 2*2, the same for the law updated at each of ``--rates`` Hz, and a press: the
part 1 mm beside the holes, 1 mm over the board, commanded down at full speed for six
control steps, where the free body's servos stop at the first contact and the arm's law
presses on: per step the board's push (true), the wrist's reading, the part's true height
and the robot's belief of it.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.physics.panda import LAW_RATE, PandaBackend, PandaSimulations
from tolins.policies import EXPERTS


class LimitWatch:
    """Counts the law's updates with a motor at its torque limit (wraps every simulation's
    law update and reads the torques it set)."""

    def __init__(self) -> None:
        self.updates = self.saturated = 0
        self._law = PandaSimulations._update_law
        watch = self

        def counted(sims, i, *args, **kwargs):
            watch._law(sims, i, *args, **kwargs)
            tau = sims.datas[i].ctrl[sims.arm.motors]
            watch.updates += 1
            watch.saturated += int(np.any(np.abs(tau) >= sims.arm.limit * (1 - 1e-9)))

        PandaSimulations._update_law = counted

    def close(self) -> None:
        PandaSimulations._update_law = self._law


def run(env_id: str, expert: str, episodes: int, law_rate: int | None = None) -> dict[str, float]:
    env = gym.make(env_id).unwrapped
    if law_rate is not None:
        version = env.settings.physics_version
        env.backend = PandaBackend(env.nominal_socket, env.control_dt, version, law_rate=law_rate)
    panda = env.settings.robot == "panda"
    rows, slips, margins, steps_total, wall = [], [], [], 0, 0.0
    for seed in range(episodes):
        policy = EXPERTS[expert]()
        observation, info = env.reset(seed=seed)
        settled = None if not panda else info["sensed_pose"] - info["pose"]
        slip, margin, done, reward = 0.0, np.inf, False, 0.0
        while not done:
            action = policy(observation)
            began = time.perf_counter()
            observation, r, terminated, truncated, info = env.step(action)
            wall += time.perf_counter() - began
            steps_total += 1
            reward += r
            done = terminated or truncated or "error" in info
            if panda and "error" not in info:
                offset = info["sensed_pose"] - info["pose"] - settled
                slip = max(slip, float(np.max(np.abs(offset[[0, 1, 3]]))))
                arm = env.backend._batch.arm
                q = env.backend.data.qpos[arm.qpos]
                room = np.minimum(q - arm.range[:, 0], arm.range[:, 1] - q)
                margin = min(margin, float(room.min()))
        rows.append((info["success"], info["step"], info["n_collisions"], reward, "error" in info))
        slips.append(slip)
        margins.append(margin)
    columns = (np.array(c, dtype=float) for c in zip(*rows, strict=True))
    success, steps, collisions, reward, errors = columns
    return {
        "success": success.mean(),
        "steps": steps.mean(),
        "collisions": collisions.mean(),
        "reward": reward.mean(),
        "faults": int(errors.sum()),
        "slip_mm": max(slips),
        "joint_margin_rad": min(margins),
        "ms_per_step": wall / steps_total * 1e3,
    }


def press(env_id: str) -> list[tuple[float, float, float, float]]:
    """Per control step of the press (see the module docstring): the board's push Fz (N),
    the sensed Fz, the true and the believed height of the pin tips (mm)."""
    env = gym.make(env_id, measurement_noise=0.0).unwrapped
    env.reset(seed=0, options={"pose": [1.0, 0.0, 0.0, 1.0]})
    rows = []
    for _ in range(6):
        _, _, _, _, info = env.step(np.array([0.0, 0.0, 0.0, -2.5]))
        sensed = info.get("sensed_wrench", info["wrench"])[3]
        belief = info.get("sensed_pose", info["pose"])[3]
        rows.append((info["wrench"][3], sensed, info["pose"][3], belief))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--envs", default="Circle2x2,Circle2x8,Square")
    parser.add_argument("--rates", default="250,500,1000", help="law updates per second (Hz)")
    parser.add_argument("--version", type=int, choices=(2, 3), default=2, help="the Panda ids'")
    args = parser.parse_args()
    arm = f"Panda-v{args.version}"
    print(
        "| env | expert | robot | success | steps | collisions | reward | faults | "
        "largest slip (mm) | closest joint to its limit (rad) | torque-limited updates | "
        "ms per control step | ratio |\n|---|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
    )
    for name in args.envs.split(","):
        for preset in (name, f"{name}Fit50"):
            for expert in EXPERTS:
                free = run(f"tolins/{preset}-v2", expert, args.episodes)
                watch = LimitWatch()
                try:
                    panda = run(f"tolins/{preset}{arm}", expert, args.episodes)
                finally:
                    watch.close()
                share = watch.saturated / max(watch.updates, 1)
                for robot, r in (("free", free), ("panda", panda)):
                    extra = (
                        f"{r['slip_mm']:.3f} | {r['joint_margin_rad']:.2f} | {share:.2%}"
                        if robot == "panda"
                        else "– | – | –"
                    )
                    print(
                        f"| {preset} | {expert} | {robot} | {r['success']:.2f} | {r['steps']:.1f} "
                        f"| {r['collisions']:.2f} | {r['reward']:.2f} | {r['faults']} | {extra} "
                        f"| {r['ms_per_step']:.2f} "
                        f"| {r['ms_per_step'] / free['ms_per_step']:.1f} |",
                        flush=True,
                    )

    print(
        "\n| law rate (Hz) | expert | success | steps | collisions | reward | faults | "
        "ms per control step |\n|--:|---|--:|--:|--:|--:|--:|--:|"
    )
    for rate in (int(r) for r in args.rates.split(",")):
        for expert in EXPERTS:
            default = " (default)" if rate == LAW_RATE else ""
            try:
                r = run(f"tolins/Circle2x2{arm}", expert, args.episodes, law_rate=rate)
            except ValueError as error:  # a rate the version's law is unstable at
                print(f"| {rate}{default} | {expert} | refused: {error} |||||")
                continue
            print(
                f"| {rate}{default} | {expert} | {r['success']:.2f} | {r['steps']:.1f} "
                f"| {r['collisions']:.2f} | {r['reward']:.2f} | {r['faults']} "
                f"| {r['ms_per_step']:.2f} |",
                flush=True,
            )
    print(
        "\n| robot | step | board's push Fz (N) | sensed Fz (N) | tips' true z (mm) "
        "| believed z (mm) |\n|---|--:|--:|--:|--:|--:|"
    )
    for robot, env_id in (("free", "tolins/Circle2x2-v2"), ("panda", f"tolins/Circle2x2{arm}")):
        for k, (true, sensed, z, belief) in enumerate(press(env_id), start=1):
            print(f"| {robot} | {k} | {true:.2f} | {sensed:.2f} | {z:.3f} | {belief:.3f} |")


if __name__ == "__main__":
    main()
