"""RS-GAIL's candidate episodes on Ray actors (``pip install 'tolins[ray]'``).

:meth:`RayPool.start` places one :class:`RolloutWorker` actor on every CPU of every node
of the connected cluster; each keeps its envs between calls (and between trainings).
The actors reserve no CPU (``num_cpus=0``, pinned to their node): the stage tasks that
drive them hold the CPUs, and they mostly wait on the actors. Any number of trainings
share the actors through :class:`RayPool`, which sends one candidate at a time to each
idle actor (``ray.util.ActorPool``) and returns the episodes in the candidates' order.
"""

from __future__ import annotations

import dataclasses
import os
import socket
from collections.abc import Sequence
from typing import Any

import numpy as np

from tolins.rollouts.episodes import Episode
from tolins.rollouts.pool import candidate_jobs, run_grouped
from tolins.rollouts.runner import VectorEnvCache


class RolloutWorker:
    """The state of one actor: a vector env per backend and env id (one thread: an actor
    per CPU), kept between calls."""

    def __init__(self, num_envs: int = 4) -> None:
        import torch

        torch.set_num_threads(1)  # the policies run one at a time beside the batch
        self.num_envs = num_envs
        self._envs: dict[str, VectorEnvCache] = {}

    def candidate(
        self,
        policy: Any,
        workpieces: Sequence[Any],
        backend: str,
        flat: np.ndarray,
        seeds: Sequence[int],
        first: int = 0,
    ) -> list[Episode]:
        """The episodes of one candidate (:func:`~tolins.rollouts.pool.candidate_jobs`) in
        this actor's vector envs."""
        if backend not in self._envs:
            self._envs[backend] = VectorEnvCache(backend, self.num_envs, num_threads=1)
        # writable copies: Ray hands arrays out read-only (and torch warns about those)
        pieces = [_writable(piece) for piece in workpieces]
        groups = candidate_jobs(policy, pieces, [np.array(flat)], [seeds], [first])
        return run_grouped(self._envs[backend], groups)[0]

    def env_ids(self) -> list[tuple[str, str]]:
        """``(backend, env id)`` of every env this actor keeps."""
        return [(b, e) for b, cache in self._envs.items() for e in cache.env_ids]

    def where(self) -> dict[str, Any]:
        """The Ray node id, host name and process id of this actor."""
        import ray

        node = ray.get_runtime_context().get_node_id()
        return {"node": node, "host": socket.gethostname(), "pid": os.getpid()}


def _writable(piece: Any) -> Any:
    if getattr(piece, "embedding", None) is None:
        return piece
    return dataclasses.replace(piece, embedding=np.array(piece.embedding))


class RayPool:
    """A :class:`~tolins.rollouts.pool.CandidatePool` over Ray actor handles (picklable: pass
    it to the Ray tasks that train)."""

    def __init__(self, workers: Sequence[Any]) -> None:
        if not workers:
            raise ValueError("a RayPool needs at least one RolloutWorker actor")
        self.workers = list(workers)

    @classmethod
    def start(cls) -> RayPool:
        """One actor per CPU of every alive node of the cluster ``ray.init`` connected to."""
        import ray
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        actor = ray.remote(RolloutWorker)
        workers = []
        for node in ray.nodes():
            cpus = int(node.get("Resources", {}).get("CPU", 0)) if node.get("Alive") else 0
            strategy = NodeAffinitySchedulingStrategy(node["NodeID"], soft=False)
            options = {"num_cpus": 0, "scheduling_strategy": strategy}
            workers += [actor.options(**options).remote() for _ in range(cpus)]
        return cls(workers)

    def rollouts(
        self, policy, workpieces, backend, candidates, seeds, first=None
    ) -> list[list[Episode]]:
        import ray
        from ray.util import ActorPool

        shared = ray.put(policy), ray.put(list(workpieces))
        first = [0] * len(candidates) if first is None else first
        jobs = zip(candidates, seeds, first, strict=True)
        pool = ActorPool(self.workers)
        return list(pool.map(lambda a, job: a.candidate.remote(*shared, backend, *job), list(jobs)))

    def where(self) -> list[dict[str, Any]]:
        """:meth:`RolloutWorker.where` of every actor."""
        import ray

        return ray.get([w.where.remote() for w in self.workers])

    def close(self) -> None:
        """Nothing: the actors outlive one training; :meth:`shutdown` ends them."""

    def shutdown(self) -> None:
        """End every actor (and its envs)."""
        import ray

        for worker in self.workers:
            ray.kill(worker)
