"""RS-GAIL (the paper's Algorithm 1): imitation of an expert plus the environment reward,
with the policy's parameters w searched by CMA-ES.

Objective of CMA-ES at iteration i (maximised; pycma minimises its negative)::

    J_i(w) = E_{τ ~ π_w} [ (1 − α_i) Σ_t D_i(s_t, a_t) + α_i Σ_t r(s_t, a_t) ]

with D_i = σ(ℓ_i) the discriminator's probability that a pair is the expert's, r the
env's reward (c(1 − k/k_max) on success, −1 per colliding step), α = 0.8 (or a linear
schedule) and the expectation estimated from ``episodes`` seeded episodes per candidate:
the paper's ``max_w (1 − α) E_π[D] + α E_π[r]``, both terms summed over the episode.
Every ``discriminator_every`` iterations D is trained
(:mod:`tolins.learning.imitation.discriminator`) on the expert's pairs against the pairs of the
current policy (the CMA-ES mean on the fixed evaluation seeds). D rather than
``imitation``'s unbounded softplus(ℓ) = −log(1 − D): with softplus, CMA-ES found pairs
that fooled D between updates (D(student) 0.98) and the env reward fell from 14 to −5 in
8 iterations; D ≤ 1 per step bounds the imitation term by (1 − α)·k_max = 8.

CMA-ES variant: separable (``CMA_diagonal``). Measured ask + tell at population 16:
1,476 parameters (π_n) 1.3 ms diagonal, 1.8 ms VkD, 128 ms full covariance; 580 (φ2)
0.7 / 1.1 / 24 ms with a 4.7 s eigendecomposition spike for full. Full covariance also
could not learn an n × n matrix from 100 × 16 samples; the diagonal adapts one step size
per weight, which is what so few samples support (docs/learning.md).

Reproducibility: every candidate's episode is seeded from (seed, iteration, candidate,
episode) and a reset makes it independent of the env's earlier episodes, so the result
does not depend on ``workers`` nor on the pool (vector envs or Ray actors,
:mod:`tolins.rollouts.pool`). pycma
samples from a private ``RandomState`` (its ``randn`` option; numpy's global RNG is left
alone). The checkpoint, written after every iteration beside D and its optimiser, holds
no pickle (a checkpoint is data: docs/security.md): the start ``x0`` and every fitness
told to CMA-ES (arrays). ``resume=True`` rebuilds the strategy from the config and
replays its ``ask``/``tell`` (deterministic, about 2 ms per iteration), checks that it
passes through the stored means, and continues to the identical result.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cma
import numpy as np
import torch
from tqdm import tqdm

from tolins.learning.artefacts import (
    RunRefused,
    atomic_torch_save,
    load_payload,
    single_threaded_torch,
)
from tolins.learning.curves import write_curves_csv
from tolins.learning.imitation.config import RSGailConfig
from tolins.learning.imitation.demonstrations import pairs
from tolins.learning.imitation.discriminator import Discriminator
from tolins.learning.imitation.policy import Policy
from tolins.rollouts.episodes import Episode
from tolins.rollouts.pool import (
    CandidatePool,
    VectorPool,
    Workpiece,
    policy_rollouts,
    spread_rollouts,
)
from tolins.rollouts.runner import VectorEnvCache

CHECKPOINT = "checkpoint.pt"
FORMAT = "tolins.rs_gail_run/2"
_EVAL = 0xE7A1


@dataclass(frozen=True)
class RSGailResult:
    """The trained policy (the CMA-ES mean), one row per iteration, and the stop reason."""

    policy: Policy
    history: list[dict[str, float]]
    stopped: str
    final: dict[str, float]
    """Reward, success, collisions and D(student) of the returned policy on the eval seeds."""
    means: np.ndarray
    """``(iterations + 1, size)``: the CMA-ES mean evaluated in each history row, then the
    last mean (the trajectories over training, the paper's Fig. 4a)."""
    selected: int
    """Index into ``means`` of the returned policy: the last, or the best with ``keep_best``."""


def episode_seed(*key: int) -> int:
    """A 32-bit seed of the key (seed, iteration, candidate, episode)."""
    return int(np.random.SeedSequence([int(k) for k in key]).generate_state(1)[0])


class _Rollouts:
    """Runs a policy's episodes over the workpieces in fresh vector envs."""

    def __init__(self, workpieces: list[Workpiece], backend: str) -> None:
        self.workpieces, self.backend = workpieces, backend

    def run(self, policy: Policy, seeds: list[int]) -> list[Episode]:
        envs = VectorEnvCache(self.backend)
        try:
            return policy_rollouts(envs, policy, self.workpieces, seeds)
        finally:
            envs.close()


@contextlib.contextmanager
def _candidate_pool(pool: CandidatePool | None, workers: int) -> Iterator[CandidatePool]:
    """``pool``, or a :class:`~tolins.rollouts.pool.VectorPool` stepping on ``workers``
    threads, closed after the block."""
    if pool is not None:
        yield pool
        return
    own = VectorPool(num_threads=workers)
    try:
        yield own
    finally:
        own.close()


def _objective(episodes: list[Episode], discriminator: Discriminator, alpha: float) -> float:
    imitation = [discriminator.probability(r.observations, r.actions).sum() for r in episodes]
    reward = [r.reward for r in episodes]
    return float((1 - alpha) * np.mean(imitation) + alpha * np.mean(reward))


def _make_es(start: np.ndarray, config: RSGailConfig, seed: int) -> cma.CMAEvolutionStrategy:
    # A private RandomState (not numpy's global one that the ``seed`` option reseeds): a
    # resumed run rebuilds it and replays its draws (_replay), as an uninterrupted one does.
    options = {
        "randn": np.random.RandomState(episode_seed(seed, 0xC3A)).randn,
        "popsize": config.popsize,
        "CMA_diagonal": True,
        "verb_log": 0,
        "verbose": -9,
        "maxiter": 10**9,
        "tolfun": 0,
        "tolx": 0,
        "tolflatfitness": 10**9,
    }
    return cma.CMAEvolutionStrategy(start, config.sigma0, options)


def _stop_rule(history: list[dict[str, float]], patience: int) -> bool:
    """Reward has not beaten its earlier best for ``patience`` rows, and D(student) stayed
    within 40-60 % in those rows."""
    if len(history) <= patience:
        return False
    recent, earlier = history[-patience:], history[:-patience]
    stalled = max(r["reward"] for r in recent) <= max(r["reward"] for r in earlier)
    return stalled and all(0.4 <= r["d_expert"] <= 0.6 for r in recent)


def train_rs_gail(
    policy: Policy,
    workpieces: list[Workpiece],
    expert: list[Episode],
    config: RSGailConfig,
    *,
    seed: int,
    backend: str,
    out: str | Path,
    metadata: dict[str, Any],
    resume: bool = False,
    progress: bool = True,
    on_iteration: Callable[[int, dict[str, float]], None] | None = None,
    pool: CandidatePool | None = None,
) -> RSGailResult:
    """Run RS-GAIL from ``policy`` (its trainable part is searched), writing
    ``out/checkpoint.pt`` and ``out/curves.csv`` after every iteration. The candidates'
    episodes run on ``pool`` (default: a :class:`~tolins.rollouts.pool.VectorPool` on
    ``config.workers`` threads); the result does not depend on it."""
    out = Path(out)
    path = out / CHECKPOINT
    runner = _Rollouts(workpieces, backend)
    expert_pairs = pairs(expert)
    discriminator = Discriminator(config.discriminator_hidden, seed=seed)
    if path.exists() and not resume:
        raise RunRefused(f"{path} exists; pass resume=True (--resume) or choose another out")
    if resume and path.exists():
        state = _load(path, metadata, discriminator, config, seed)
        es, start, history = state["es"], state["iteration"], state["history"]
        means, told, x0 = state["means"], state["told"], state["x0"]
    else:
        x0 = np.array(policy.get_flat(), dtype=float)
        es, start, history, means, told = _make_es(x0, config, seed), 0, [], [], []
    eval_seeds = [episode_seed(seed, _EVAL, e) for e in range(config.eval_episodes)]
    stopped = "iterations"
    bar = tqdm(total=config.iterations, initial=start, desc="RS-GAIL", disable=not progress)
    with single_threaded_torch(), _candidate_pool(pool, config.workers) as candidate_pool:
        for i in range(start, config.iterations):
            began = time.perf_counter()
            alpha = config.alpha_at(i)
            means.append(np.array(es.mean, dtype=float))
            current = spread_rollouts(
                candidate_pool, policy, workpieces, backend, es.mean, eval_seeds
            )
            if i % config.discriminator_every == 0:
                discriminator.update(expert_pairs, pairs(current), config.discriminator_steps)
            candidates = es.ask()

            seeds = [
                [episode_seed(seed, i, c, e) for e in range(config.episodes)]
                for c in range(len(candidates))
            ]
            episodes = candidate_pool.rollouts(policy, workpieces, backend, candidates, seeds)
            fitness = [_objective(e, discriminator, alpha) for e in episodes]
            told.append([-f for f in fitness])
            es.tell(candidates, told[-1])
            row = _row(i, alpha, current, discriminator, fitness, es, episodes, began)
            history.append(row)
            _save(path, x0, told, history, means, discriminator, metadata)
            write_curves_csv(out / "curves.csv", history)
            bar.set_postfix(
                reward=f"{row['reward']:.1f}",
                success=f"{row['success']:.2f}",
                D=f"{row['d_expert']:.2f}",
            )
            bar.update()
            if on_iteration is not None:
                on_iteration(i, row)
            if config.stop_rule and _stop_rule(history, config.patience):
                stopped = "stop rule"
                break
    bar.close()
    snapshots = np.array([*means[: len(history)], es.mean])
    policy.set_flat(snapshots[-1])
    with single_threaded_torch():
        final = _summary(runner.run(policy, eval_seeds), discriminator)
    selected = len(history)
    if config.keep_best:
        rewards = [row["reward"] for row in history] + [final["reward"]]
        selected = int(np.argmax(rewards))  # the first of equals: the earliest
        if selected < len(history):
            policy.set_flat(snapshots[selected])
            with single_threaded_torch():
                final = _summary(runner.run(policy, eval_seeds), discriminator)
    return RSGailResult(policy, history, stopped, final, snapshots, selected)


def _summary(current: list[Episode], discriminator: Discriminator) -> dict[str, float]:
    return {
        "reward": float(np.mean([r.reward for r in current])),
        "success": float(np.mean([r.success for r in current])),
        "collisions": float(np.mean([r.collisions for r in current])),
        "d_expert": discriminator.expert_probability(*pairs(current)),
    }


def _row(i, alpha, current, discriminator, fitness, es, episodes, began) -> dict[str, float]:
    steps = sum(len(r.actions) for group in [current, *episodes] for r in group)
    return {
        "iteration": i,
        "alpha": alpha,
        **_summary(current, discriminator),
        "objective_best": float(np.max(fitness)),
        "objective_mean": float(np.mean(fitness)),
        "sigma": float(es.sigma),
        "env_steps": steps,
        "wall_s": time.perf_counter() - began,
    }


def _save(path, x0, told, history, means, discriminator, metadata) -> None:
    atomic_torch_save(
        path,
        {
            "format": FORMAT,
            "metadata": metadata,
            "iteration": len(told),
            "history": history,
            "means": torch.as_tensor(np.array(means)),
            "x0": torch.as_tensor(x0),
            "told": torch.as_tensor(np.array(told, dtype=float)),
            "discriminator": discriminator.full_state(),
        },
    )


def check_resumable(out: str | Path, metadata: dict[str, Any]) -> None:
    """Raise :class:`~tolins.learning.artefacts.RunRefused` if ``out``'s checkpoint (when
    there is one) cannot be read or was written by a run with other ``metadata``: what a
    caller checks before it spends time on demonstrations."""
    path = Path(out) / CHECKPOINT
    if path.exists():
        _check_metadata(path, _payload(path), metadata)


def _payload(path: Path) -> dict[str, Any]:
    try:
        return load_payload(path, FORMAT)
    except ValueError as error:
        if "'tolins.rs_gail_run/1'" not in str(error):
            raise RunRefused(f"{error}; delete it to start the run afresh") from None
        raise RunRefused(
            f"{error} (tolins ≤ 0.3.0 pickled its CMA-ES state, and unpickling could run code "
            f"from the file: not loaded); delete {path} to start the run afresh"
        ) from None


def _check_metadata(path: Path, payload: dict[str, Any], metadata: dict[str, Any]) -> None:
    stored = {k: v for k, v in payload["metadata"].items() if k != "tolins_version"}
    wanted = {k: v for k, v in metadata.items() if k != "tolins_version"}
    if stored != wanted:
        differ = sorted(k for k in stored.keys() | wanted.keys() if stored.get(k) != wanted.get(k))
        raise RunRefused(
            f"{path} was written by another run configuration (differs in: "
            f"{', '.join(differ)}); cannot resume it; allowed: --resume with the same options, "
            "or another --out"
        )


def _load(
    path: Path,
    metadata: dict[str, Any],
    discriminator: Discriminator,
    config: RSGailConfig,
    seed: int,
) -> dict[str, Any]:
    payload = _payload(path)
    _check_metadata(path, payload, metadata)
    try:
        iteration = int(payload["iteration"])
        x0 = payload["x0"].numpy().astype(float)
        told = payload["told"].numpy().astype(float).reshape(iteration, -1)
        means = list(payload["means"].numpy().astype(float).reshape(iteration, x0.size))
        history = list(payload["history"])[:iteration]
        if len(history) != iteration or not np.isfinite(told).all():
            raise ValueError("history or fitness values incomplete")
        discriminator.load_full_state(payload["discriminator"])
    except (KeyError, AttributeError, TypeError, ValueError, RuntimeError) as error:
        raise RunRefused(
            f"{path}: not a complete RS-GAIL checkpoint ({type(error).__name__}: {error}); "
            "allowed: a checkpoint this tolins wrote; delete it to start the run afresh"
        ) from error
    return {
        "es": _replay(path, x0, told, means, config, seed),
        "iteration": iteration,
        "history": history,
        "means": means,
        "told": [list(row) for row in told],
        "x0": x0,
    }


def _replay(
    path: Path,
    x0: np.ndarray,
    told: np.ndarray,
    means: list[np.ndarray],
    config: RSGailConfig,
    seed: int,
) -> cma.CMAEvolutionStrategy:
    """The strategy after ``told`` (one row of fitness values per iteration), rebuilt from
    the config: the same draws and updates as the interrupted run. :class:`RunRefused`
    unless it passes through every stored mean (a checkpoint of another start or edited)."""
    es = _make_es(x0, config, seed)
    for i, fitness in enumerate(told):
        if not np.array_equal(es.mean, means[i]) or len(fitness) != config.popsize:
            raise RunRefused(
                f"{path}: its CMA-ES state does not replay (iteration {i}); allowed: a "
                "checkpoint this tolins wrote for this config; delete it to start afresh"
            )
        es.tell(es.ask(), [float(f) for f in fitness])
    return es
