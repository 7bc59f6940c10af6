"""Where a Panda control step's time goes: MuJoCo's physics, the law in Python, the rest.

Usage::

    python benchmarks/panda_step_cost.py [--episodes 5] [--envs Circle2x2,Circle2x2Fit50]

Both experts run ``--episodes`` episodes (seeds 0 …) on ``tolins/{name}Panda-v2`` and on
the free body ``tolins/{name}-v2``. On the Panda, the physics steps (``mujoco.mj_step``)
and the law's updates (:meth:`~tolins.physics.panda.PandaSimulations._update_law`, 125 a
control step at 500 Hz) are timed apart; the rest of ``env.step`` is the env's own work
(observation, reward, faults). Printed per row: ms per control step in each, and the free
body's whole step beside them. The physics column is the floor of a law moved to C: what a
Panda step would cost with the law free.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import mujoco

import tolins  # noqa: F401  (registers the ids)
from tolins.policies import EXPERTS


class Timed:
    """Wraps a callable, adding its wall time to ``seconds``."""

    def __init__(self, function) -> None:
        self.function, self.seconds = function, 0.0

    def __call__(self, *args, **kwargs):
        began = time.perf_counter()
        try:
            return self.function(*args, **kwargs)
        finally:
            self.seconds += time.perf_counter() - began


def run(env_id: str, expert: str, episodes: int) -> dict[str, float]:
    """ms per control step: the whole ``env.step``, and on the Panda its physics and law."""
    env = gym.make(env_id).unwrapped
    panda = env.settings.robot == "panda"
    physics, law = Timed(mujoco.mj_step), None
    if panda:
        sims = env.backend._batch.sims
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--envs", default="Circle2x2,Circle2x2Fit50")
    args = parser.parse_args()
    print(
        "| workpiece | expert | free body (ms) | Panda (ms) | its physics (ms) | its law (ms) "
        "| the rest (ms) | Panda / free | physics / free |\n|---|---|--:|--:|--:|--:|--:|--:|--:|"
    )
    for name in args.envs.split(","):
        for expert in ("safe", "efficient"):
            free = run(f"tolins/{name}-v2", expert, args.episodes)
            arm = run(f"tolins/{name}Panda-v2", expert, args.episodes)
            rest = arm["whole"] - arm["physics"] - arm["law"]
            print(
                f"| {name} | {expert} | {free['whole']:.2f} | {arm['whole']:.2f} "
                f"| {arm['physics']:.2f} | {arm['law']:.2f} | {rest:.2f} "
                f"| {arm['whole'] / free['whole']:.1f} | {arm['physics'] / free['whole']:.1f} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
