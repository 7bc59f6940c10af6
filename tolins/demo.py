"""``tolins demo``: both experts in every preset environment, as a table."""

from __future__ import annotations

from dataclasses import dataclass

from tqdm import tqdm

from tolins.envs.tasks import ROBOT_TASKS, TASKS, Task
from tolins.policies.experts import EXPERTS
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs
from tolins.rollouts.summary import Summary, summarise

#: The largest vector env of a demo (slots per env id).
MAX_SLOTS = 32


@dataclass(frozen=True)
class DemoRow:
    """One expert in one environment."""

    env_id: str
    expert: str
    summary: Summary


def newest_id(task: Task) -> str:
    """``task``'s id of its newest physics version (``-v2``; the Panda's ``-v3``)."""
    return task.gym_id_of(max(task.physics_versions))


def robot_tasks() -> tuple[Task, ...]:
    """The Panda's tasks of the paper's workpieces (the demo's robot rows)."""
    paper = {task.name for task in TASKS}
    return tuple(task for task in ROBOT_TASKS if task.name.removesuffix("Panda") in paper)


def demo_ids(robot: bool) -> list[str]:
    """The ids a demo rolls out: every paper preset's newest, then, with ``robot``, the
    Panda's of the same workpieces."""
    tasks = TASKS + (robot_tasks() if robot else ())
    return [newest_id(task) for task in tasks]


def run_demo(
    episodes: int = 20,
    seed: int = 0,
    workers: int = 2,
    backend: str = "mujoco",
    progress: bool = True,
    robot_episodes: int = 0,
) -> list[DemoRow]:
    """Roll out both experts for ``episodes`` episodes (seeds ``seed``, ``seed + 1``, ...)
    in the newest id of every preset environment, and for ``robot_episodes`` in the
    Panda's of the paper's workpieces (none at 0; MuJoCo only, ``tolins[robot]``), side by
    side in one vector env per id stepped on ``workers`` threads
    (:func:`tolins.rollouts.runner.run_jobs`). Results do not depend on ``workers``: each
    episode is the single env's from its seed."""
    if episodes < 1 or workers < 1 or robot_episodes < 0:
        raise ValueError(
            f"episodes={episodes!r}, workers={workers!r}, robot_episodes={robot_episodes!r}; "
            "allowed: episodes and workers ≥ 1, robot_episodes ≥ 0"
        )
    if robot_episodes and backend != "mujoco":
        raise ValueError(f"robot_episodes={robot_episodes} on backend={backend!r}; allowed: mujoco")
    counts = {env_id: episodes for env_id in demo_ids(robot=False)}
    if robot_episodes:
        counts |= {newest_id(task): robot_episodes for task in robot_tasks()}
    rows = []
    bar = tqdm(total=len(counts), desc="demo", unit="env", disable=not progress)
    for count in sorted(set(counts.values()), reverse=True):
        envs = VectorEnvCache(backend, num_envs=min(2 * count, MAX_SLOTS), num_threads=workers)
        try:
            for env_id in (env_id for env_id, n in counts.items() if n == count):
                rows += _rows(envs, env_id, count, seed)
                bar.update()
        finally:
            envs.close()
    bar.close()
    order = list(counts)
    return sorted(rows, key=lambda row: order.index(row.env_id))


def _rows(envs: VectorEnvCache, env_id: str, episodes: int, seed: int) -> list[DemoRow]:
    """Both experts' rows of ``env_id``, ``episodes`` episodes each."""
    experts = list(EXPERTS)
    jobs = [Job(env_id, EXPERTS[expert](), seed + i) for expert in experts for i in range(episodes)]
    results = run_jobs(envs, jobs)
    return [
        DemoRow(env_id, expert, summarise(results[k * episodes : (k + 1) * episodes]))
        for k, expert in enumerate(experts)
    ]


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
