"""Every Panda id (or every delicate id) through the checks the suite runs on a few of
them: gymnasium's ``check_env``, determinism, and the vector env on 1 and 2 threads
against single envs.

Usage::

    python benchmarks/conformance.py [--steps 10] [--tasks robot|delicate]

For each registered id of the tasks of a tag (``robot``: every paper workpiece and 50 µm
grade with the Panda, ``-v2`` and ``-v3``, and the delicate ones with the Panda;
``delicate``: the round-pin workpieces with pins that bend, with the free body and the
Panda):
``check_env`` on the unwrapped env; two envs from the same seed give the same
observations bit for bit over ``--steps`` steps of fixed actions; a vector env of three
simulations on 1 thread and on 2 threads gives, per simulation, the single env's
observations bit for bit. Prints one row per id and exits 1 if any check failed.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings

import gymnasium as gym
import numpy as np
from gymnasium.utils.env_checker import check_env

import tolins
from tolins.envs.tasks import GYM_TASKS

ACTIONS = np.array([[1.0, 0.0, 0.05, -2.5], [-1.0, 2.0, 0.0, -1.0], [0.0, 0.0, 0.0, -2.5]])
QUIET = {"measurement_noise": 0.0}


def single_run(env_id: str, seed: int, steps: int, action: np.ndarray) -> np.ndarray:
    """Observations of a single env from ``seed`` under one repeated ``action``."""
    env = gym.make(env_id, **QUIET)
    seen = [env.reset(seed=seed)[0]]
    for _ in range(steps):
        observation, _, terminated, truncated, _ = env.step(action)
        seen.append(observation)
        if terminated or truncated:
            break
    env.close()
    return np.array(seen)


def vector_matches(env_id: str, threads: int, steps: int, singles: list[np.ndarray]) -> bool:
    """Whether a vector env of three simulations on ``threads`` threads steps each as the
    single env did (up to the first episode's end in any of them)."""
    vector = tolins.make_vec(env_id, 3, num_threads=threads, **QUIET)
    observations, _ = vector.reset(seed=[5, 6, 7])
    rows = [observations]
    for _ in range(min(len(s) for s in singles) - 1):
        rows.append(vector.step(ACTIONS)[0])
    vector.close()
    return all(
        np.array_equal(np.array(rows)[:, i], single[: len(rows)])
        for i, single in enumerate(singles)
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--tasks", choices=("robot", "delicate"), default="robot")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # gymnasium's advice on Box bounds and older versions
    tasks = [task for task in GYM_TASKS if args.tasks in task.tags]
    ids = [task.gym_id_of(v) for task in tasks for v in task.physics_versions]
    print("| id | check_env | deterministic | vector, 1 thread | vector, 2 threads | s |")
    print("|---|---|---|---|---|--:|")
    failed = False
    for env_id in ids:
        began = time.perf_counter()
        env = gym.make(env_id, **QUIET)
        check_env(env.unwrapped, skip_render_check=True)
        env.close()
        singles = [single_run(env_id, 5 + i, args.steps, ACTIONS[i]) for i in range(3)]
        again = single_run(env_id, 5, args.steps, ACTIONS[0])
        checks = [
            np.array_equal(singles[0], again),
            vector_matches(env_id, 1, args.steps, singles),
            vector_matches(env_id, 2, args.steps, singles),
        ]
        failed |= not all(checks)
        marks = " | ".join("yes" if ok else "**no**" for ok in checks)
        print(f"| `{env_id}` | passed | {marks} | {time.perf_counter() - began:.0f} |", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
