"""Where a Panda control step's time goes, with the law compiled and in numpy, side by side.

Usage::

    python benchmarks/panda_step_cost.py [--episodes 5] [--envs Circle2x2,Circle2x2Fit50]
        [--version 3] [--vector 8] [--threads 2]

Both experts run ``--episodes`` episodes (seeds 0 …) on ``tolins/{name}Panda-v{version}``
and on the free body ``tolins/{name}-v2``. On the Panda the physics steps
(``mujoco.mj_step``) and the law's updates (125 a control step at 500 Hz) are timed apart,
once with the law compiled (:mod:`tolins.physics.compiled_law`, the default) and once in
numpy (:meth:`~tolins.physics.arm.Arm.batch_torques`, the law the ids ran before it was
compiled); the rest of ``env.step`` is the env's own work (observation, reward, faults).
Printed per row: ms per control step, the compiled step over its physics alone (goal
≤ 1.3) and the numpy step over the compiled one (goal ≥ 2.5).

Then ``--vector`` Panda envs of the first workpiece in one vector env on ``--threads``
threads against one env stepped as many times, random actions (goal ≥ 1.7× on 2 cores).
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import mujoco
import numpy as np

import tolins
from tolins.policies import EXPERTS


class Timed:
    """Wraps a callable, adding the time it takes on ``clock`` (default: wall time) to
    ``seconds``."""

    def __init__(self, function, clock=time.perf_counter) -> None:
        self.function, self.clock, self.seconds = function, clock, 0.0

    def __call__(self, *args, **kwargs):
        began = self.clock()
        try:
            return self.function(*args, **kwargs)
        finally:
            self.seconds += self.clock() - began


def run(env_id: str, expert: str, episodes: int, compiled: bool = True) -> dict[str, float]:
    """ms per control step: the whole ``env.step``, and on the Panda its physics and law."""
    env = gym.make(env_id).unwrapped
    panda = env.settings.robot == "panda"
    physics, law = Timed(mujoco.mj_step), None
    if panda:
        sims = env.backend._batch.sims
        sims.compiled = compiled
        law = sims._update_law = Timed(sims._update_law)
    whole = in_law = 0.0
    steps = 0
    for seed in range(episodes):
        policy = EXPERTS[expert]()
        observation, _ = env.reset(seed=seed)
        done = False
        while not done:
            action = policy(observation)
            law_before = 0.0 if law is None else law.seconds
            mujoco.mj_step = physics
            began = time.perf_counter()
            try:
                observation, _, terminated, truncated, info = env.step(action)
            finally:
                whole += time.perf_counter() - began
                mujoco.mj_step = physics.function
            in_law += 0.0 if law is None else law.seconds - law_before
            steps += 1
            done = terminated or truncated or "error" in info
    return {
        "whole": whole / steps * 1e3,
        "physics": physics.seconds / steps * 1e3,
        "law": in_law / steps * 1e3,
    }


def vector_rate(env_id: str, num_envs: int, threads: int, steps: int) -> tuple[float, float]:
    """Env steps per second: ``num_envs`` envs in one vector env on ``threads`` threads, and
    one env stepped ``num_envs`` times as often (random actions, seed 0)."""
    vector = tolins.make_vec(env_id, num_envs=num_envs, num_threads=threads)
    vector.reset(seed=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (steps, num_envs, 4))
    began = time.perf_counter()
    for action in actions:
        vector.step(action)
    batched = steps * num_envs / (time.perf_counter() - began)
    vector.close()
    single = gym.make(env_id)
    single.reset(seed=0)
    began = time.perf_counter()
    for action in actions.reshape(-1, 4):
        *_, terminated, truncated, _ = single.step(action)
        if terminated or truncated:  # as the vector env's autoreset does
            single.reset()
    alone = steps * num_envs / (time.perf_counter() - began)
    return batched, alone


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--envs", default="Circle2x2,Circle2x2Fit50")
    parser.add_argument("--version", type=int, default=3)
    parser.add_argument("--vector", type=int, default=8)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--vector-steps", type=int, default=40)
    args = parser.parse_args()
    print(
        "| workpiece | expert | free body | Panda, law in numpy | Panda, compiled "
        "| its physics | its law | the rest | compiled / physics | numpy / compiled |\n"
        "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|"
    )
    for name in args.envs.split(","):
        for expert in ("safe", "efficient"):
            panda = f"tolins/{name}Panda-v{args.version}"
            free = run(f"tolins/{name}-v2", expert, args.episodes)
            numpy_law = run(panda, expert, args.episodes, compiled=False)
            arm = run(panda, expert, args.episodes)
            rest = arm["whole"] - arm["physics"] - arm["law"]
            print(
                f"| {name} | {expert} | {free['whole']:.2f} | {numpy_law['whole']:.2f} "
                f"| {arm['whole']:.2f} | {arm['physics']:.2f} | {arm['law']:.2f} | {rest:.2f} "
                f"| {arm['whole'] / arm['physics']:.2f} "
                f"| {numpy_law['whole'] / arm['whole']:.1f} |",
                flush=True,
            )
    if args.vector:
        name = args.envs.split(",")[0]
        env_id = f"tolins/{name}Panda-v{args.version}"
        batched, alone = vector_rate(env_id, args.vector, args.threads, args.vector_steps)
        print(
            f"\n{args.vector} × {env_id} on {args.threads} threads: {batched:.1f} steps/s; "
            f"one env stepped {args.vector} times as often: {alone:.1f} steps/s; "
            f"ratio {batched / alone:.2f}"
        )


if __name__ == "__main__":
    main()
