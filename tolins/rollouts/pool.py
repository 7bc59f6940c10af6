"""Where a population of candidate policies runs its episodes: one interface
(:class:`CandidatePool`), two implementations: :class:`VectorPool` (vector envs of this
process, the default) and :class:`tolins.rollouts.ray_pool.RayPool` (Ray actors on a
cluster, each running its share through vector envs of its own).

A candidate is a parameter vector of a :class:`ParametricPolicy` (RS-GAIL's CMA-ES
samples). Its episodes are seeded from its key ``(seed, iteration, candidate, episode)``
and every pool returns them in the candidates' order, so a search does not depend on the
pool, its size or the machine that ran an episode (:mod:`tolins.rollouts.runner`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from tolins.rollouts.collectors import Pairs
from tolins.rollouts.episodes import Episode
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs


@dataclass(frozen=True)
class Workpiece:
    """A training environment and its tolerance embedding ψ (``None`` without one)."""

    env_id: str
    embedding: np.ndarray | None = None


class ParametricPolicy(Protocol):
    """What the pools need of a policy: a copy with other parameters, and an actor."""

    def with_flat(self, flat: np.ndarray) -> ParametricPolicy:
        """A copy whose trainable parameters are ``flat``."""

    def bind(self, embedding: np.ndarray | None = None) -> Callable[[np.ndarray], np.ndarray]:
        """The actor ``observation -> action`` on a workpiece of embedding ``embedding``."""


def policy_jobs(
    policy: ParametricPolicy, workpieces: Sequence[Workpiece], seeds: Sequence[int], first: int = 0
) -> list[Job]:
    """Episode ``e`` of ``policy`` from ``seeds[e]`` on workpiece ``(first + e) %
    len(workpieces)``, its (observation, action) pairs kept."""
    jobs = []
    for e, seed in enumerate(seeds):
        piece = workpieces[(first + e) % len(workpieces)]
        jobs.append(Job(piece.env_id, policy.bind(piece.embedding), int(seed), (Pairs(),)))
    return jobs


def candidate_jobs(
    policy: ParametricPolicy,
    workpieces: Sequence[Workpiece],
    candidates: Sequence[np.ndarray],
    seeds: Sequence[Sequence[int]],
    first: Sequence[int] | None = None,
) -> list[list[Job]]:
    """The jobs of every candidate: ``policy`` with parameters ``candidates[c]`` from
    ``seeds[c]`` (``first[c]``: :func:`policy_jobs`'s, default 0)."""
    first = [0] * len(candidates) if first is None else first
    return [
        policy_jobs(policy.with_flat(np.asarray(flat)), workpieces, s, f)
        for flat, s, f in zip(candidates, seeds, first, strict=True)
    ]


def run_grouped(envs: VectorEnvCache, groups: list[list[Job]]) -> list[list[Episode]]:
    """:func:`~tolins.rollouts.runner.run_jobs` of all ``groups`` at once, regrouped."""
    flat = run_jobs(envs, [job for group in groups for job in group])
    out, k = [], 0
    for group in groups:
        out.append(flat[k : k + len(group)])
        k += len(group)
    return out


def policy_rollouts(
    envs: VectorEnvCache,
    policy: ParametricPolicy,
    workpieces: Sequence[Workpiece],
    seeds: Sequence[int],
) -> list[Episode]:
    """The episodes of :func:`policy_jobs`, run in ``envs``."""
    return run_grouped(envs, [policy_jobs(policy, workpieces, seeds)])[0]


def spread_rollouts(
    pool: CandidatePool,
    policy: ParametricPolicy,
    workpieces: Sequence[Workpiece],
    backend: str,
    flat: np.ndarray,
    seeds: Sequence[int],
) -> list[Episode]:
    """The episodes of one parameter vector, one job per episode on ``pool`` (the same
    episodes as one candidate with all ``seeds``)."""
    n = len(seeds)
    groups = pool.rollouts(policy, workpieces, backend, [flat] * n, [[s] for s in seeds], range(n))
    return [episode for group in groups for episode in group]


class CandidatePool(Protocol):
    """Runs the episodes of a population of candidates."""

    def rollouts(
        self,
        policy: ParametricPolicy,
        workpieces: Sequence[Workpiece],
        backend: str,
        candidates: Sequence[np.ndarray],
        seeds: Sequence[Sequence[int]],
        first: Sequence[int] | None = None,
    ) -> list[list[Episode]]:
        """The episodes of every :func:`candidate_jobs` group, in order."""
        ...

    def close(self) -> None:
        """Release the workers (and their envs)."""
        ...


class VectorPool:
    """:class:`CandidatePool` on this process's vector envs: every candidate's episodes in
    one batch per env id, stepped on ``num_threads`` native threads.

    Args:
        num_threads: Threads of each MuJoCo batch (default: every core).
        num_envs: Slots of each vector env (episodes stepped side by side).
    """

    def __init__(self, num_threads: int | None = None, num_envs: int = 16) -> None:
        if num_threads is not None and (not isinstance(num_threads, int) or num_threads < 1):
            raise ValueError(f"num_threads={num_threads!r}; allowed: None or an integer ≥ 1")
        self.num_threads, self.num_envs = num_threads, num_envs
        self._caches: dict[str, VectorEnvCache] = {}

    def envs(self, backend: str) -> VectorEnvCache:
        """This pool's vector envs on ``backend``."""
        if backend not in self._caches:
            self._caches[backend] = VectorEnvCache(backend, self.num_envs, self.num_threads)
        return self._caches[backend]

    def rollouts(
        self, policy, workpieces, backend, candidates, seeds, first=None
    ) -> list[list[Episode]]:
        groups = candidate_jobs(policy, workpieces, candidates, seeds, first)
        return run_grouped(self.envs(backend), groups)

    def close(self) -> None:
        for cache in self._caches.values():
            cache.close()
        self._caches.clear()
