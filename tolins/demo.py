"""``tolins demo``: both experts in every preset environment, as a table."""

from __future__ import annotations

from dataclasses import dataclass

from tqdm import tqdm

from tolins.envs.tasks import TASKS
from tolins.policies.experts import EXPERTS
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs
from tolins.rollouts.summary import Summary, summarise


@dataclass(frozen=True)
class DemoRow:
    """One expert in one environment."""

    env_id: str
    expert: str
    summary: Summary


def run_demo(
    episodes: int = 20,
    seed: int = 0,
    workers: int = 2,
    backend: str = "mujoco",
    progress: bool = True,
) -> list[DemoRow]:
    """Roll out both experts for ``episodes`` episodes (seeds ``seed``, ``seed + 1``, ...)
    in every preset environment, side by side in one vector env per preset stepped on
    ``workers`` threads (:func:`tolins.rollouts.runner.run_jobs`). Results do not depend
    on ``workers``: each episode is the single env's from its seed."""
    if episodes < 1 or workers < 1:
        raise ValueError(f"episodes={episodes!r}, workers={workers!r}; allowed: both ≥ 1")
    experts = list(EXPERTS)
    envs = VectorEnvCache(backend, num_envs=min(2 * episodes, 32), num_threads=workers)
    rows = []
    try:
        bar = tqdm(total=len(TASKS), desc="demo", unit="env", disable=not progress)
        for task in TASKS:
            jobs = [
                Job(task.gym_id, EXPERTS[expert](), seed + i)
                for expert in experts
                for i in range(episodes)
            ]
            results = run_jobs(envs, jobs)
            for k, expert in enumerate(experts):
                mine = results[k * episodes : (k + 1) * episodes]
                rows.append(DemoRow(task.gym_id, expert, summarise(mine)))
            bar.update()
        bar.close()
    finally:
        envs.close()
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
