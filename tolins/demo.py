"""``tolins demo``: both experts in every preset environment, as a table."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import gymnasium as gym
from tqdm import tqdm

from tolins.envs.tasks import TASKS, Task
from tolins.policies.experts import EXPERTS
from tolins.rollouts.episodes import Summary, run_episode, summarise


@dataclass(frozen=True)
class DemoRow:
    """One expert in one environment."""

    env_id: str
    expert: str
    summary: Summary


def _evaluate(task: Task, expert: str, episodes: int, seed: int, backend: str) -> DemoRow:
    env = gym.make(task.gym_id, backend=backend).unwrapped
    policy = EXPERTS[expert]()
    results = [run_episode(env, policy, seed=seed + i) for i in range(episodes)]
    env.close()
    return DemoRow(task.gym_id, expert, summarise(results))


def run_demo(
    episodes: int = 20,
    seed: int = 0,
    workers: int = 2,
    backend: str = "mujoco",
    progress: bool = True,
) -> list[DemoRow]:
    """Roll out both experts for ``episodes`` episodes (seeds ``seed``, ``seed + 1``, ...)
    in every preset environment, on ``workers`` threads. Results do not depend on
    ``workers``: each job owns its environment and seeds."""
    if episodes < 1 or workers < 1:
        raise ValueError(f"episodes={episodes!r}, workers={workers!r}; allowed: both ≥ 1")
    jobs = [(task, expert) for task in TASKS for expert in EXPERTS]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(_evaluate, t, e, episodes, seed, backend) for t, e in jobs]
        bar = tqdm(total=len(futures), desc="demo", unit="env×expert", disable=not progress)
        rows = []
        for future in futures:
            rows.append(future.result())
            bar.update()
        bar.close()
    return rows


def format_table(rows: list[DemoRow]) -> str:
    """A Markdown table of the rows: mean ± std of Table 1's figures."""
    lines = [
        "| env | expert | success rate | reward | steps | collisions |",
        "|---|---|---|---|---|---|",
    ]
    for row in rows:
        s = row.summary
        lines.append(
            f"| {row.env_id} | {row.expert} | {s.success_mean:.2f} ± {s.success_std:.2f} "
            f"| {s.reward_mean:.2f} ± {s.reward_std:.2f} | {s.steps_mean:.2f} ± {s.steps_std:.2f} "
            f"| {s.collisions_mean:.2f} ± {s.collisions_std:.2f} |"
        )
    return "\n".join(lines)
