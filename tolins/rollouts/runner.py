"""Many episodes at once: jobs (env id, policy, seed) run through the vector env.

:func:`run_jobs` fills the ``num_envs`` slots of one :class:`~tolins.envs.vector.
InsertionVectorEnv` per env id with jobs, steps every running slot in one batched call
(MuJoCo's native thread pool, the GIL released) and starts the next job in a slot as soon
as its episode ends (``reset_mask`` with the job's seed). A job's episode is the one
:func:`~tolins.rollouts.episodes.rollout` gives in ``gymnasium.make(env_id)`` reset with
its seed, bit for bit (the vector env's guarantee), so results depend neither on the
number of slots nor on threads nor on the order of the jobs.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from tolins.envs.episode import check_action
from tolins.envs.tasks import make_vec
from tolins.envs.vector import InsertionVectorEnv
from tolins.rollouts.episodes import Episode, Policy, Rollout, check_env_id
from tolins.rollouts.forces import ForceTracker


@dataclass(frozen=True)
class Job:
    """One episode to run: ``policy`` in ``env_id`` from ``reset(seed=seed)``."""

    env_id: str
    policy: Policy
    seed: int


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
            if self.backend == "mujoco":
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


class _Slot:
    """The episode a slot runs: its job's index and what it has recorded so far."""

    def __init__(self, job: int, forces: ForceTracker) -> None:
        self.job, self.total, self.forces = job, 0.0, forces
        self.observations: list[np.ndarray] = []
        self.actions: list[np.ndarray] = []


def run_jobs(envs: VectorEnvCache, jobs: Sequence[Job]) -> list[tuple[Rollout, Episode]]:
    """Every job's episode, in the jobs' order: its :class:`Rollout` (pairs kept) and its
    :class:`Episode` (Table 1's record, with ``steps`` and any fault)."""
    results: list[tuple[Rollout, Episode] | None] = [None] * len(jobs)
    by_env: dict[str, list[int]] = {}
    for index, job in enumerate(jobs):
        by_env.setdefault(job.env_id, []).append(index)
    for env_id, indices in by_env.items():
        for index, result in _run_in(envs.get(env_id), jobs, indices):
            results[index] = result
    return results  # type: ignore[return-value]


def _run_in(env: InsertionVectorEnv, jobs: Sequence[Job], indices: list[int]):
    """Yield ``(job index, result)`` for ``indices``, run in ``env``'s slots."""
    queue = deque(indices)
    slots: list[_Slot | None] = [None] * env.num_envs
    observations = _start(env, jobs, queue, slots)
    while any(slot is not None for slot in slots):
        actions = np.zeros((env.num_envs, 4))
        for i, slot in enumerate(slots):
            if slot is not None:
                observation = observations[i].copy()
                actions[i] = check_action(jobs[slot.job].policy(observation))
                slot.observations.append(observation)
                slot.actions.append(actions[i].copy())
        observations, rewards, terminated, truncated, infos = env.step(actions)
        ended = False
        for i, slot in enumerate(slots):
            if slot is None:
                continue
            slot.total += rewards[i]
            slot.forces.step(infos["peak_force"][i], infos["pose"][i][3])
            if terminated[i] or truncated[i]:
                yield slot.job, _finish(slot, infos, i)
                slots[i], ended = None, True
        if ended and queue:
            observations = _start(env, jobs, queue, slots)


def _start(env, jobs, queue, slots) -> np.ndarray:
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
    for i, job in starting.items():
        slots[i] = _Slot(job, ForceTracker.of(env.settings, {"pose": infos["pose"][i]}))
    return observations


def _finish(slot: _Slot, infos: dict, i: int) -> tuple[Rollout, Episode]:
    success, collisions = bool(infos["success"][i]), int(infos["n_collisions"][i])
    has_error = "error" in infos and infos["_error"][i]
    error = str(infos["error"][i]) if has_error else None
    total = float(slot.total)
    rollout = Rollout(
        np.array(slot.observations).reshape(-1, 8),
        np.array(slot.actions).reshape(-1, 4),
        total,
        success,
        collisions,
    )
    steps = int(infos["step"][i])
    forces = slot.forces
    episode = Episode(total, success, steps, collisions, error, forces.scores(), forces.profile())
    return rollout, episode
