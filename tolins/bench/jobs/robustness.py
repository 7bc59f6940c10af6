"""The robustness stages of ``tolins bench``: one per policy of the robustness table
(:mod:`tolins.bench.table.robustness`) and training seed, ``robust-{policy}-seed{s}``,
and the same for any other :class:`~tolins.bench.table.robustness.ConditionTable` (the
Panda's, ``robot-{policy}-seed{s}``: :mod:`tolins.bench.table.robot`).

A stage's config names the trained policy's stage (name and key, as the evaluation stages
do) so that a retrained policy re-runs it; it evaluates the policy on every condition,
from the evaluation seeds of the table's rows (:func:`tolins.bench.table.seeds.eval_seeds`,
the profile's ``robustness_episodes`` of them; so the 200 µm cell repeats the first
episodes of C2.1, C1.1, C2.3), through :func:`tolins.bench.jobs.policy_episodes.evaluate`
(the vector env; one env after another for π_φ* and for blocked holes on MuJoCo, which
the MuJoCo batch lacks). Its folder holds ``robustness.json``: condition id -> episodes.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from tolins.atomic import atomic_json
from tolins.bench.jobs.policy_episodes import episodes_to_json, evaluate, stage_actor
from tolins.bench.store.cache import Stage, StageCache
from tolins.bench.store.integrity import StageFileError, checked_episodes, read_json
from tolins.bench.table.robustness import (
    ROBUSTNESS,
    Condition,
    ConditionTable,
    RobustPolicy,
    SeedEpisodes,
    robustness_table,
)
from tolins.bench.table.rows import CIRCLE_2X2, seeded
from tolins.envs.tasks import DEFECT_SIGMA
from tolins.learning.agents.actors import PolicyRef

#: The file of a stage: condition id -> its episodes.
EPISODES = "robustness.json"
#: The stage-name prefix of the robustness table's stages.
PREFIX = ROBUSTNESS.prefix


@dataclass(frozen=True)
class RobustnessSpec:
    """What one robustness stage runs.

    Attributes:
        policy: The table's line.
        seed: The training seed (of the policy; it picks the evaluation seeds).
        backend: ``mujoco`` or ``kinematic``.
        seeds: The evaluation seeds of every condition.
        policy_stage: The trained policy's stage folder (``name-key``); ``None`` for an
            expert.
        table: The table whose line it is (the robustness table by default).
    """

    policy: RobustPolicy
    seed: int
    backend: str
    seeds: tuple[int, ...]
    policy_stage: str | None
    table: ConditionTable = ROBUSTNESS


def stage_name(policy: RobustPolicy, seed: int, table: ConditionTable = ROBUSTNESS) -> str:
    return seeded(f"{table.prefix}{policy.id}", seed)


def robustness_stage(spec: RobustnessSpec) -> Stage[RobustnessSpec]:
    """The stage of ``spec``. Its config: the policy, its training stage, the conditions,
    the evaluation seeds, the backend and the tolins version."""
    import tolins

    config = {
        "policy": asdict(spec.policy),
        "policy_stage": spec.policy_stage,
        "conditions": [asdict(c) for c in spec.table.conditions],
        "backend": spec.backend,
        "seeds": list(spec.seeds),
        "tolins_version": tolins.__version__,
    }
    return Stage(stage_name(spec.policy, spec.seed, spec.table), config, spec)


def evaluate_conditions(
    policy: RobustPolicy,
    policy_path: Path | None,
    backend: str,
    seeds: list[int],
    conditions: tuple[Condition, ...] = ROBUSTNESS.conditions,
) -> SeedEpisodes:
    """``policy``'s episodes on each of ``conditions`` from ``seeds``: condition id ->
    episodes.

    A trained policy is bound to the paper's 2*2 (200 µm): the circle embedding of π_φ
    covers hole radii of 0.45–0.6 mm only, so π_φ sees every condition as the workpiece it
    was trained for (what a graded hole or a defect changes, it meets by contact)."""
    entry: Any = policy.agent
    if policy_path is not None:
        from tolins.envs.tasks import task_of

        entry = stage_actor(PolicyRef(policy.agent, policy_path), task_of(CIRCLE_2X2).socket)
    return {
        c.id: evaluate(
            entry,
            c.env_id,
            backend,
            seeds,
            inference=policy.inference,
            vectorized=c.vectorizable(backend),
            env_kwargs=c.env_kwargs,
            inference_sigma=DEFECT_SIGMA if policy.inference else None,
        )
        for c in conditions
    }


def robustness_job(root: Path, stage: Stage[RobustnessSpec], path: Path | None) -> Path:
    """A job of :mod:`tolins.bench.pipeline.executor`: the robustness ``stage`` in the
    cache under ``root`` (``path``: the trained policy file, ``None`` for an expert); its
    folder."""
    spec = stage.spec

    def build(folder: Path) -> None:
        seeds, conditions = list(spec.seeds), spec.table.conditions
        episodes = evaluate_conditions(spec.policy, path, spec.backend, seeds, conditions)
        atomic_json(folder / EPISODES, {k: episodes_to_json(v) for k, v in episodes.items()})

    return StageCache(root).run_stage(stage, build)


def read_stage(
    folder: Path, count: int, conditions: tuple[Condition, ...] = ROBUSTNESS.conditions
) -> SeedEpisodes:
    """The episodes of the stage in ``folder`` (``count`` per condition of
    ``conditions``), checked."""
    path = folder / EPISODES
    data = read_json(path)
    if not isinstance(data, dict) or set(data) != {c.id for c in conditions}:
        raise StageFileError(path, "not a stage of this table")
    return {c.id: checked_episodes(path, data[c.id], count) for c in conditions}


def robustness_results(
    stage_folders: dict[str, Path], count: int, seeds: int, table: ConditionTable = ROBUSTNESS
) -> dict[str, Any] | None:
    """``results.json[table.key]`` (:func:`~tolins.bench.table.robustness.
    robustness_table`) from the finished stages in ``stage_folders`` (stage name ->
    folder; ``count`` episodes per condition); a policy counts when its stages of every
    training seed are there."""
    episodes = {}
    for policy in table.policies:
        folders = [stage_folders.get(stage_name(policy, s, table)) for s in range(seeds)]
        if all(folder is not None for folder in folders):
            episodes[policy.id] = [
                read_stage(folder, count, table.conditions) for folder in folders
            ]
    return robustness_table(episodes, count, seeds, table)
