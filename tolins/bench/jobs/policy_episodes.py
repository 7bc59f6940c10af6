"""A policy's episodes from given seeds, on the bench's terms: every Table 1 row, every
robustness cell and ``tolins evaluate`` run their episodes through :func:`evaluate`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym

from tolins.bench.store.integrity import stage_file
from tolins.geometry.specs import SocketSpec
from tolins.learning.agents.actors import PolicyRef, make_actor
from tolins.rollouts.episodes import Episode, Policy, episode_to_dict, run_episode
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs

#: Episodes an evaluation steps side by side (slots of its vector env).
VECTOR_SLOTS = 16


def evaluate(
    entry: str | PolicyRef | Policy,
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
    """Run the policy ``entry`` (a :class:`~tolins.learning.agents.actors.PolicyRef`, whose
    file is a stage's (:func:`stage_actor`), or a name for
    :func:`tolins.learning.agents.actors.make_actor`, or an actor ``observation ->
    action``) on ``env_id`` from each seed; the first
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
    socket = env.unwrapped.nominal_socket
    if isinstance(entry, PolicyRef):
        actor = stage_actor(entry, socket)
    else:
        actor = make_actor(entry, socket) if isinstance(entry, str) else entry
    wrapper = None
    if inference:
        from tolins.inference.adaptive import InferenceGuidedPolicy

        wrapper = actor = InferenceGuidedPolicy(actor, env, contact=False, sigma=inference_sigma)
    recorder = None
    if record is not None and recorded > 0:
        from tolins.record import RerunRecorder

        name = policy_name or _label(entry)
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
            episodes += run_jobs(envs, jobs)
        finally:
            envs.close()
    return episodes


def stage_actor(ref: PolicyRef, socket: SocketSpec) -> Policy:
    """:func:`~tolins.learning.agents.actors.make_actor` of ``ref``, whose file (if any) a
    training stage wrote: a file it cannot load is a
    :class:`~tolins.bench.store.integrity.StageFileError`."""
    if ref.path is None:
        return make_actor(ref, socket)
    with stage_file(ref.path):
        return make_actor(ref, socket)


def _label(entry: str | PolicyRef | Policy) -> str:
    """What a recording calls the policy ``entry``: its name, else ``policy``."""
    if isinstance(entry, PolicyRef):
        return entry.name
    return entry.split("=")[0] if isinstance(entry, str) else "policy"


def episodes_to_json(episodes: list[Episode]) -> list[dict]:
    """``episodes`` as the JSON rows of a stage file (read back by
    :func:`tolins.bench.store.integrity.checked_episodes`)."""
    return [episode_to_dict(e) for e in episodes]
