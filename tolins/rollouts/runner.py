"""Many episodes at once: jobs (env id, policy, seed, collectors) run through the vector env.

:func:`run_jobs` fills the ``num_envs`` slots of one :class:`~tolins.envs.vector.
InsertionVectorEnv` per env id with jobs, steps every running slot in one batched call
(MuJoCo's native thread pool, the GIL released) and starts the next job in a slot as soon
as its episode ends (``reset_mask`` with the job's seed). Each slot's episode is an
:class:`~tolins.rollouts.episodes.EpisodeRun`, as in the single-env loop
:func:`~tolins.rollouts.episodes.run_episode`, and a job's episode is the one that loop
gives in ``gymnasium.make(env_id)`` reset with its seed, bit for bit (the vector env's
guarantee), so results depend neither on the number of slots nor on threads nor on the
order of the jobs. A stop requested by :mod:`tolins.stopping` ends the loop before its
next step.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tolins.envs.tasks import check_env_id, make_vec
from tolins.envs.vector import InsertionVectorEnv
from tolins.physics.registry import taking
from tolins.rollouts.collectors import Collector
from tolins.rollouts.episodes import Episode, EpisodeRun, Policy
from tolins.rollouts.infos import InfoRow
from tolins.stopping import raise_if_stopped


@dataclass(frozen=True)
class Job:
    """One episode to run: ``policy`` in ``env_id`` from ``reset(seed=seed)``, recorded
    by ``collectors`` (fresh ones, this job's own) beside Table 1's figures and the
    force-aware scores."""

    env_id: str
    policy: Policy
    seed: int
    collectors: tuple[Collector, ...] = ()


class VectorEnvCache:
    """Vector envs of ``num_envs`` slots on one backend, by env id, kept until :meth:`close`.

    Args:
        backend: ``"mujoco"``, ``"kinematic"`` (or ``"warp"``).
        num_envs: Slots per env id.
        num_threads: Threads of each MuJoCo batch (default: every core).
        env_kwargs: Further keywords of every env (e.g. ``defects=``, ``randomization=``).
    """

    def __init__(
        self,
        backend: str,
        num_envs: int = 16,
        num_threads: int | None = None,
        env_kwargs: dict[str, Any] | None = None,
    ) -> None:
        self.backend, self.num_envs, self.num_threads = backend, num_envs, num_threads
        self.env_kwargs = dict(env_kwargs or {})
        self._envs: dict[str, InsertionVectorEnv] = {}

    def get(self, env_id: str) -> InsertionVectorEnv:
        if env_id not in self._envs:
            kwargs = {**self.env_kwargs, "backend": self.backend, "autoreset_mode": "Disabled"}
            if self.backend in taking("num_threads"):
                kwargs["num_threads"] = self.num_threads
            self._envs[env_id] = make_vec(check_env_id(env_id), self.num_envs, **kwargs).unwrapped
        return self._envs[env_id]

    @property
    def env_ids(self) -> list[str]:
        """The ids of the envs made so far."""
        return list(self._envs)

    def close(self) -> None:
        for env in self._envs.values():
            env.close()
        self._envs.clear()


#: A running slot: its job's index and its episode.
_Slot = tuple[int, EpisodeRun]


def run_jobs(envs: VectorEnvCache, jobs: Sequence[Job]) -> list[Episode]:
    """Every job's episode, in the jobs' order."""
    results: list[Episode | None] = [None] * len(jobs)
    by_env: dict[str, list[int]] = {}
    for index, job in enumerate(jobs):
        by_env.setdefault(job.env_id, []).append(index)
    for env_id, indices in by_env.items():
        for index, episode in _run_in(envs.get(env_id), jobs, indices):
            results[index] = episode
    return results  # type: ignore[return-value]


def _run_in(
    env: InsertionVectorEnv, jobs: Sequence[Job], indices: list[int]
) -> Iterator[tuple[int, Episode]]:
    """Yield ``(job index, episode)`` for ``indices``, run in ``env``'s slots
    (:class:`~tolins.stopping.Stopped` before a step once a stop is requested)."""
    queue = deque(indices)
    slots: list[_Slot | None] = [None] * env.num_envs
    observations = _start(env, jobs, queue, slots)
    while any(slot is not None for slot in slots):
        raise_if_stopped()
        actions = np.zeros((env.num_envs, 4))
        for i, slot in enumerate(slots):
            if slot is not None:
                actions[i] = slot[1].act(observations[i].copy())
        observations, rewards, terminated, truncated, infos = env.step(actions)
        ended = False
        for i, slot in enumerate(slots):
            if slot is None:
                continue
            job, run = slot
            run.observe(observations[i], rewards[i], terminated[i], truncated[i], InfoRow(infos, i))
            if run.done:
                yield job, run.episode()
                slots[i], ended = None, True
        if ended and queue:
            observations = _start(env, jobs, queue, slots)


def _start(
    env: InsertionVectorEnv, jobs: Sequence[Job], queue: deque[int], slots: list[_Slot | None]
) -> np.ndarray:
    """Put the next queued jobs into the free slots and reset those slots with their seeds;
    every env's observation (a masked reset keeps the others' last ones)."""
    mask = np.zeros(env.num_envs, dtype=bool)
    seeds: list[int | None] = [None] * env.num_envs
    starting: dict[int, int] = {}
    for i in range(env.num_envs):
        if slots[i] is None and queue:
            starting[i] = queue.popleft()
            mask[i], seeds[i] = True, int(jobs[starting[i]].seed)
    observations, infos = env.reset(seed=seeds, options={"reset_mask": mask})
    for i, index in starting.items():
        job = jobs[index]
        run = EpisodeRun(
            job.policy, env.settings, observations[i], InfoRow(infos, i), job.collectors
        )
        slots[i] = (index, run)
    return observations
