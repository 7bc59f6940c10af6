"""The evaluation stage of one Table 1 row and training seed: the row's policy on its
eval env from the seed's evaluation seeds, the first episodes recorded to rerun.

Its folder holds ``episodes.json`` (:data:`EPISODES`, read back by :func:`read_episodes`)
and, for the first training seed, ``episodes.rrd`` (:data:`RECORDING`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from tolins.atomic import atomic_json
from tolins.bench.jobs.policy_episodes import episodes_to_json, evaluate
from tolins.bench.store.cache import Stage, StageCache
from tolins.bench.store.integrity import checked_episodes, read_json
from tolins.bench.table.rows import Row, seeded
from tolins.learning.agents.actors import PolicyRef
from tolins.rollouts.episodes import Episode

#: The episodes of an evaluation stage.
EPISODES = "episodes.json"
#: The recorded episodes of an evaluation stage (the first training seed's).
RECORDING = "episodes.rrd"


@dataclass(frozen=True)
class EvaluationSpec:
    """What one evaluation stage runs.

    Attributes:
        row: The row.
        seed: The training seed (of the policy; it picks the evaluation seeds).
        backend: ``mujoco`` or ``kinematic``.
        seeds: The evaluation seeds (:func:`~tolins.bench.table.seeds.eval_seeds`).
        recorded: How many of the first episodes are recorded to rerun.
        policy_stage: The trained policy's stage folder (``name-key``); ``None`` for an
            expert.
    """

    row: Row
    seed: int
    backend: str
    seeds: tuple[int, ...]
    recorded: int
    policy_stage: str | None


def stage_name(row: Row, seed: int) -> str:
    """The stage name of ``row``'s evaluation for training seed ``seed``."""
    return seeded(f"eval-{row.id}", seed)


def evaluation_stage(spec: EvaluationSpec) -> Stage[EvaluationSpec]:
    """The stage of ``spec``. Its config: the row, the backend, the evaluation seeds, how
    many are recorded, the policy's stage and the tolins version."""
    import tolins

    config = {
        "row": asdict(spec.row),
        "backend": spec.backend,
        "seeds": list(spec.seeds),
        "recorded": spec.recorded,
        "policy_stage": spec.policy_stage,
        "tolins_version": tolins.__version__,
    }
    return Stage(stage_name(spec.row, spec.seed), config, spec)


def evaluate_row(
    row: Row,
    policy_path: Path | None,
    backend: str,
    seeds: list[int],
    *,
    record: Path | None = None,
    recorded: int = 0,
) -> list[Episode]:
    """:func:`~tolins.bench.jobs.policy_episodes.evaluate` ``row``'s policy
    (``policy_path``: the trained one, ``None`` for an expert row) on its eval env; a π_φ*
    row with inference in the loop."""
    return evaluate(
        PolicyRef(row.agent, policy_path),
        row.eval_env,
        backend,
        seeds,
        inference=row.inference,
        record=record,
        recorded=recorded,
        policy_name=f"{row.id} {row.policy}",
    )


def evaluation_job(root: Path, stage: Stage[EvaluationSpec], policy: Path | None) -> Path:
    """A job of :mod:`tolins.bench.pipeline.executor`: the evaluation ``stage`` in the
    cache under ``root`` (``policy``: the trained policy file, ``None`` for an expert);
    its folder."""
    spec = stage.spec

    def build(folder: Path) -> None:
        record = folder / RECORDING if spec.recorded else None
        episodes = evaluate_row(
            spec.row,
            policy,
            spec.backend,
            list(spec.seeds),
            record=record,
            recorded=spec.recorded,
        )
        atomic_json(folder / EPISODES, episodes_to_json(episodes))

    return StageCache(root).run_stage(stage, build)


def read_episodes(folder: Path, count: int) -> list[Episode]:
    """The ``count`` episodes of the evaluation stage in ``folder``, checked
    (:func:`~tolins.bench.store.integrity.checked_episodes`): the one reader of
    :data:`EPISODES`."""
    return checked_episodes(folder / EPISODES, read_json(folder / EPISODES), count)
