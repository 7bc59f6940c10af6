"""Where RS-GAIL's candidate episodes run: one interface (:class:`CandidatePool`), two
implementations: :class:`ThreadPool` (threads of this process, the default) and
:class:`tolins.learning.ray_pool.RayPool` (Ray actors on a cluster).

Both run :func:`candidate_rollouts`: a candidate's episodes are seeded from its key
``(seed, iteration, candidate)`` and each pool returns them in the candidates' order, so
the search does not depend on the pool, its size or the machine that ran an episode.
Both keep their envs between iterations (:class:`EnvCache`): ``reset(seed)`` makes an
episode independent of the env's earlier ones (tested).
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from tolins.learning.demonstrations import Rollout, make_env, rollout

if TYPE_CHECKING:
    from tolins.learning.policy import Policy
    from tolins.learning.rs_gail import Workpiece


class EnvCache:
    """Unwrapped envs of one backend by id, made on first use and kept until :meth:`close`."""

    def __init__(self, backend: str) -> None:
        self.backend = backend
        self._envs: dict[str, Any] = {}

    def get(self, env_id: str) -> Any:
        if env_id not in self._envs:
            self._envs[env_id] = make_env(env_id, self.backend)
        return self._envs[env_id]

    @property
    def env_ids(self) -> list[str]:
        """The ids of the envs made so far."""
        return list(self._envs)

    def close(self) -> None:
        for env in self._envs.values():
            env.close()
        self._envs.clear()


def policy_rollouts(
    envs: EnvCache,
    policy: Policy,
    workpieces: Sequence[Workpiece],
    seeds: Sequence[int],
    first: int = 0,
) -> list[Rollout]:
    """Episode ``e`` of ``policy`` from ``seeds[e]`` on workpiece ``(first + e) %
    len(workpieces)``."""
    episodes = []
    for e, seed in enumerate(seeds):
        piece = workpieces[(first + e) % len(workpieces)]
        episodes.append(rollout(envs.get(piece.env_id), policy.bind(piece.embedding), seed))
    return episodes


def spread_rollouts(
    pool: CandidatePool,
    policy: Policy,
    workpieces: Sequence[Workpiece],
    backend: str,
    flat: np.ndarray,
    seeds: Sequence[int],
) -> list[Rollout]:
    """The episodes of one parameter vector, one job per episode on ``pool`` (the same
    episodes as :func:`candidate_rollouts` of all ``seeds`` in one env)."""
    n = len(seeds)
    groups = pool.rollouts(policy, workpieces, backend, [flat] * n, [[s] for s in seeds], range(n))
    return [episode for group in groups for episode in group]


def candidate_rollouts(
    envs: EnvCache,
    policy: Policy,
    workpieces: Sequence[Workpiece],
    flat: np.ndarray,
    seeds: Sequence[int],
    first: int = 0,
) -> list[Rollout]:
    """The episodes of one CMA-ES candidate: ``policy`` with trainable parameters ``flat``
    (``first``: :func:`policy_rollouts`'s)."""
    return policy_rollouts(envs, policy.with_flat(flat), workpieces, seeds, first)


class CandidatePool(Protocol):
    """Runs the episodes of a population of candidates."""

    def rollouts(
        self,
        policy: Policy,
        workpieces: Sequence[Workpiece],
        backend: str,
        candidates: Sequence[np.ndarray],
        seeds: Sequence[Sequence[int]],
        first: Sequence[int] | None = None,
    ) -> list[list[Rollout]]:
        """:func:`candidate_rollouts` of every ``candidates[c]`` from ``seeds[c]`` (and
        ``first[c]``, default 0), in order."""
        ...

    def close(self) -> None:
        """Release the workers (and their envs)."""
        ...


class ThreadPool:
    """:class:`CandidatePool` on ``workers`` threads (mj_step releases the GIL); each thread
    keeps its own envs."""

    def __init__(self, workers: int) -> None:
        if not isinstance(workers, int) or workers < 1:
            raise ValueError(f"workers={workers!r}; allowed: an integer ≥ 1")
        self._executor = ThreadPoolExecutor(max_workers=workers)
        self._local = threading.local()
        self._caches: list[EnvCache] = []
        self._lock = threading.Lock()

    def _envs(self, backend: str) -> EnvCache:
        caches = self._local.__dict__.setdefault("caches", {})
        if backend not in caches:
            caches[backend] = EnvCache(backend)
            with self._lock:
                self._caches.append(caches[backend])
        return caches[backend]

    def rollouts(
        self, policy, workpieces, backend, candidates, seeds, first=None
    ) -> list[list[Rollout]]:
        def one(job: tuple[np.ndarray, Sequence[int], int]) -> list[Rollout]:
            return candidate_rollouts(self._envs(backend), policy, workpieces, *job)

        first = [0] * len(candidates) if first is None else first
        return list(self._executor.map(one, zip(candidates, seeds, first, strict=True)))

    def close(self) -> None:
        self._executor.shutdown()
        with self._lock:
            for cache in self._caches:
                cache.close()
            self._caches.clear()
