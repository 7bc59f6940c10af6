"""Evaluation of one Table 1 row: episodes on held-out seeds, the first ones recorded."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any

import gymnasium as gym

from tolins.bench.table import Row
from tolins.learning.actors import make_actor
from tolins.rollouts.episodes import Episode, Policy, episode_from_dict, run_episode
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs

#: Evaluation seeds start here (no training run uses them); seed index ``s`` of the
#: training gets ``FIRST_SEED + 1000 s, ...``.
FIRST_SEED = 10_000
#: Episodes an evaluation steps side by side (slots of its vector env).
VECTOR_SLOTS = 16


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
    vectorized: bool = True,
    env_kwargs: dict[str, Any] | None = None,
    inference_sigma: float | None = None,
) -> list[Episode]:
    """Run the policy ``entry`` (a name for :func:`tolins.learning.actors.make_actor`, or
    an actor ``observation -> action``) on ``env_id`` from each seed; the first
    ``recorded`` episodes go through :class:`tolins.record.RerunRecorder` into ``record``
    (an ``.rrd``).

    ``inference=True`` wraps the policy in
    :class:`tolins.inference.adaptive.InferenceGuidedPolicy` with binary outcomes (the
    paper's π_φ*), reset before every episode; its prior std of the pins' offsets is
    ``inference_sigma`` (mm; default the env's ``defect_sigma``).

    With ``vectorized`` (the default) the episodes after the recorded ones run side by
    side in a vector env (:func:`tolins.rollouts.runner.run_jobs`: the same episodes bit
    for bit); the policy must then hold no state between calls, as the experts, ``tolins
    train`` policies and SB3 models do. ``vectorized=False`` runs one episode after
    another (a policy with memory). ``env_kwargs`` go to every env made (``defects=``,
    ``randomization=``, ...).
    """
    env_kwargs = dict(env_kwargs or {})
    env = gym.make(env_id, backend=backend, **env_kwargs)
    actor = make_actor(entry, env.unwrapped.nominal_socket) if isinstance(entry, str) else entry
    wrapper = None
    if inference:
        from tolins.inference.adaptive import InferenceGuidedPolicy

        wrapper = actor = InferenceGuidedPolicy(actor, env, contact=False, sigma=inference_sigma)
    recorder = None
    if record is not None and recorded > 0:
        from tolins.record import RerunRecorder

        name = policy_name or (entry.split("=")[0] if isinstance(entry, str) else "policy")
        recorder = RerunRecorder(env, record, policy_name=name)
    # The recorded episodes, and all of π_φ*'s (its inference moves the env's goal between
    # attempts), run in the single env; the rest side by side in a vector env.
    sequential = len(seeds) if wrapper is not None or not vectorized else recorded
    episodes = []
    try:
        for i, seed in enumerate(seeds[:sequential]):
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
    rest = seeds[sequential:]
    if rest:
        envs = VectorEnvCache(backend, num_envs=min(len(rest), VECTOR_SLOTS), env_kwargs=env_kwargs)
        try:
            jobs = [Job(env_id, actor, seed) for seed in rest]
            episodes += [episode for _, episode in run_jobs(envs, jobs)]
        finally:
            envs.close()
    return episodes


def episodes_to_json(episodes: list[Episode]) -> list[dict]:
    return [asdict(e) for e in episodes]


def episodes_from_json(rows: list[dict]) -> list[Episode]:
    return [episode_from_dict(row) for row in rows]
