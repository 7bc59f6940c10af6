"""Evaluation of one Table 1 row: episodes on held-out seeds, the first ones recorded."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import gymnasium as gym

from tolins.bench.table import Row
from tolins.learning.actors import make_actor
from tolins.rollout import Episode, run_episode

#: Evaluation seeds start here (no training run uses them); seed index ``s`` of the
#: training gets ``FIRST_SEED + 1000 s, ...``.
FIRST_SEED = 10_000


def eval_seeds(seed_index: int, episodes: int) -> list[int]:
    """The evaluation seeds of training seed ``seed_index``."""
    return [FIRST_SEED + 1000 * seed_index + i for i in range(episodes)]


def evaluate_row(
    row: Row,
    policy_path: Path | None,
    backend: str,
    seeds: list[int],
    *,
    record: Path | None = None,
    recorded: int = 0,
) -> list[Episode]:
    """Run ``row``'s policy on its eval env from each seed; the first ``recorded`` episodes
    go through :class:`tolins.record.RerunRecorder` into ``record`` (an ``.rrd``).

    ``policy_path`` is the trained policy (``None`` for an expert row). A π_φ* row wraps
    the policy in :class:`tolins.inference.adaptive.InferenceGuidedPolicy` with binary
    outcomes (the paper's inference), reset before every episode.
    """
    env = gym.make(row.eval_env, backend=backend)
    entry = row.agent if policy_path is None else f"{row.agent}={policy_path}"
    actor = make_actor(entry, env.unwrapped.nominal_socket)
    wrapper = None
    if row.inference:
        from tolins.inference.adaptive import InferenceGuidedPolicy

        wrapper = actor = InferenceGuidedPolicy(actor, env, contact=False)
    recorder = None
    if record is not None and recorded > 0:
        from tolins.record import RerunRecorder

        recorder = RerunRecorder(env, record, policy_name=f"{row.id} {row.policy}")
    episodes = []
    try:
        for i, seed in enumerate(seeds):
            if wrapper is not None:
                wrapper.reset(seed)
            target = recorder if recorder is not None and i < recorded else env
            episodes.append(run_episode(target, actor, seed=seed))
            if recorder is not None and i + 1 == min(recorded, len(seeds)):
                recorder.finish()
                recorder = None
    finally:
        if recorder is not None:
            recorder.abort()
        env.close()
    return episodes


def episodes_to_json(episodes: list[Episode]) -> list[dict]:
    return [asdict(e) for e in episodes]


def episodes_from_json(rows: list[dict]) -> list[Episode]:
    return [Episode(**row) for row in rows]
