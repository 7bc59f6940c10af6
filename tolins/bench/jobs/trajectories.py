"""The trajectories stage of ``tolins bench`` (the paper's Fig. 4a): one episode of π_n
(the safe expert's, on the 2*2, training seed 0) at iterations across its RS-GAIL
training, beside the expert's, all from the first evaluation seed.

Its folder holds ``trajectories.json`` (:data:`TRAJECTORIES`): the label and the
workpiece poses ``[x, y, theta, z]`` of each episode, read back by
:func:`read_trajectories`; ``trajectories.png`` is drawn from it.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tolins.atomic import atomic_json
from tolins.bench.store.cache import Stage, StageCache
from tolins.bench.store.integrity import StageFileError, read_array, read_json, stage_file
from tolins.bench.table.rows import TRAININGS, seeded
from tolins.bench.table.seeds import FIRST_SEED

#: The training whose iterations are drawn, with its training seed.
TRAINING, SEED = "pi_n_safe", 0
#: The stage's name.
NAME = seeded(f"trajectories-{TRAINING}", SEED)
#: The file of the stage.
TRAJECTORIES = "trajectories.json"
#: Iterations of π_n drawn (at most; the expert's episode besides).
POINTS = 5


@dataclass(frozen=True)
class TrajectorySpec:
    """What the trajectories stage runs.

    Attributes:
        env_id: The env of the episodes (the training's).
        expert: The expert drawn beside π_n (the one it imitates).
        backend: ``mujoco`` or ``kinematic``.
        seed: The episodes' seed.
        points: Iterations drawn, evenly spaced from the first (π_bc) to the last.
        policy_stage: π_n's stage folder (``name-key``).
    """

    env_id: str
    expert: str
    backend: str
    seed: int
    points: int
    policy_stage: str


def trajectory_stage(policy_stage: str, backend: str) -> Stage[TrajectorySpec]:
    """The stage drawing π_n from its stage folder ``policy_stage`` on ``backend``. Its
    config: :class:`TrajectorySpec`'s fields and the tolins version."""
    import tolins

    training = TRAININGS[TRAINING]
    spec = TrajectorySpec(
        training.env_ids[0], training.expert, backend, FIRST_SEED, POINTS, policy_stage
    )
    return Stage(NAME, {**asdict(spec), "tolins_version": tolins.__version__}, spec)


def trajectory_job(root: Path, stage: Stage[TrajectorySpec], policy: Path) -> Path:
    """A job of :mod:`tolins.bench.pipeline.executor`: the trajectories ``stage`` in the
    cache under ``root`` from π_n's policy file ``policy`` (beside it, the CMA-ES means of
    every iteration; without them no episode is drawn); its folder."""

    def build(folder: Path) -> None:
        atomic_json(folder / TRAJECTORIES, {"trajectories": _episodes(stage.spec, policy)})

    return StageCache(root).run_stage(stage, build)


def _episodes(spec: TrajectorySpec, policy_path: Path) -> list[dict[str, Any]]:
    """The label and poses of each episode: the expert's, then π_n's at each pick, in one
    env one after another."""
    import gymnasium as gym

    from tolins.learning.imitation.policy import load_policy
    from tolins.learning.imitation.runs import MEANS
    from tolins.policies import EXPERTS
    from tolins.rollouts.episodes import episode_poses

    if not (policy_path.parent / MEANS).is_file():
        return []
    with stage_file(policy_path):
        policy, _ = load_policy(policy_path, kind="nominal")
    means = _means(policy_path.parent / MEANS, policy.size)
    last = len(means) - 1
    picks = sorted(set(np.linspace(0, last, spec.points).round().astype(int).tolist()))
    env = gym.make(spec.env_id, backend=spec.backend)
    try:
        episodes = [
            (f"expert ({spec.expert})", episode_poses(env, EXPERTS[spec.expert](), spec.seed))
        ]
        for k in picks:
            label = "π_bc (iteration 0)" if k == 0 else f"iteration {k}"
            actor = policy.with_flat(means[k]).bind()
            episodes.append((label, episode_poses(env, actor, spec.seed)))
    finally:
        env.close()
    return [{"label": label, "poses": poses.tolist()} for label, poses in episodes]


def _means(path: Path, size: int) -> np.ndarray:
    """The CMA-ES means of every iteration in ``path``, ``(iterations, size)``, finite."""
    means = read_array(path)
    if means.ndim != 2 or len(means) == 0 or means.shape[1] != size:
        raise StageFileError(path, f"shape {means.shape}; allowed: (iterations ≥ 1, {size})")
    if not np.isfinite(means).all():
        raise StageFileError(path, "not all finite")
    return means


def read_trajectories(folder: Path) -> dict[str, np.ndarray]:
    """The episodes of the trajectories stage in ``folder``: label -> poses
    ``(steps + 1, 4)``, checked."""
    path = folder / TRAJECTORIES
    document = read_json(path)
    episodes = document.get("trajectories") if isinstance(document, dict) else None
    if not isinstance(episodes, list):
        raise StageFileError(path, "not a trajectories stage")
    trajectories = {}
    for i, episode in enumerate(episodes):
        label = episode.get("label") if isinstance(episode, dict) else None
        poses = episode.get("poses") if isinstance(episode, dict) else None
        if not isinstance(label, str) or not _poses(poses):
            raise StageFileError(path, f"episode {i} is not a label and [x, y, theta, z] poses")
        trajectories[label] = np.array(poses, dtype=float)
    return trajectories


def _poses(poses: Any) -> bool:
    """Whether ``poses`` is a non-empty list of four finite numbers each."""
    return (
        isinstance(poses, list)
        and bool(poses)
        and all(
            isinstance(p, list)
            and len(p) == 4
            and all(isinstance(v, int | float) and math.isfinite(v) for v in p)
            for p in poses
        )
    )
