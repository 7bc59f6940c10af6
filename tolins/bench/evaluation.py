"""Evaluation of one Table 1 row: episodes on held-out seeds, the first ones recorded."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import gymnasium as gym

from tolins.bench.table import Row
from tolins.learning.actors import make_actor
from tolins.rollout import Episode, Policy, run_episode

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
    """:func:`evaluate` ``row``'s policy (``policy_path``: the trained one, ``None`` for an
    expert row) on its eval env; a π_φ* row with inference in the loop."""
    entry = row.agent if policy_path is None else f"{row.agent}={policy_path}"
    return evaluate(
        entry,
        row.eval_env,
        backend,
        seeds,
        inference=row.inference,
        record=record,
        recorded=recorded,
        policy_name=f"{row.id} {row.policy}",
    )


def evaluate(
    entry: str | Policy,
    env_id: str,
    backend: str,
    seeds: list[int],
    *,
    inference: bool = False,
    record: Path | None = None,
    recorded: int = 0,
    policy_name: str | None = None,
) -> list[Episode]:
    """Run the policy ``entry`` (a name for :func:`tolins.learning.actors.make_actor`, or
    an actor ``observation -> action``) on ``env_id`` from each seed; the first
    ``recorded`` episodes go through :class:`tolins.record.RerunRecorder` into ``record``
    (an ``.rrd``).

    ``inference=True`` wraps the policy in
    :class:`tolins.inference.adaptive.InferenceGuidedPolicy` with binary outcomes (the
    paper's π_φ*), reset before every episode.
    """
    env = gym.make(env_id, backend=backend)
    actor = make_actor(entry, env.unwrapped.nominal_socket) if isinstance(entry, str) else entry
    wrapper = None
    if inference:
        from tolins.inference.adaptive import InferenceGuidedPolicy

        wrapper = actor = InferenceGuidedPolicy(actor, env, contact=False)
    recorder = None
    if record is not None and recorded > 0:
        from tolins.record import RerunRecorder

        name = policy_name or (entry.split("=")[0] if isinstance(entry, str) else "policy")
        recorder = RerunRecorder(env, record, policy_name=name)
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
