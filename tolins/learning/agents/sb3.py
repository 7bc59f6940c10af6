"""Deep-RL baselines: stable-baselines3 PPO and SAC on an insertion env (needs ``tolins[rl]``).

The agent sees the env through :func:`tolins.envs.wrappers.agent_env` (actions in
``[-1, 1]``, float32 observations) and learns from ``reward_mode`` (``dense`` by default,
the mode that learns: benchmarks/README.md). PPO on ``n_envs`` envs keeps SB3's rollout
of :data:`PPO_ROLLOUT` transitions per update (``n_steps = PPO_ROLLOUT / n_envs``). Its
network scales the observation by the fixed :data:`OBSERVATION_SCALE`
(:class:`ScaledObservation`, saved inside the model zip, so ``tolins evaluate --policy
model.zip`` needs no wrapper). Every ``curve_every`` env steps
the deterministic policy is scored with the paper's sparse reward on ``curve_episodes``
episodes (seeds from :data:`CURVE_SEED`, apart from the bench's evaluation seeds); the
curve ``curves.csv`` has one row per point with the env steps trained so far.

A training writes its checkpoint (``checkpoint.pt``,
:mod:`~tolins.learning.agents.sb3_checkpoint`) at the start of the first rollout after
every ``checkpoint_every`` env steps, and when SIGINT or SIGTERM arrives (then the signal
takes effect, once the checkpoint is written) or a stop is requested
(:mod:`tolins.stopping`); ``train_sb3(..., resume=True)`` continues from it to the weights
an uninterrupted training ends with, bit for bit (tested), and removes it at the end.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from tolins.atomic import atomic_write
from tolins.envs.wrappers import agent_env
from tolins.learning.agents.sb3_config import (
    ALGORITHM_NAMES,
    CHECKPOINT,
    CURVES,
    HYPERPARAMETERS,
    MODEL,
    PPO_ROLLOUT,
    Sb3Config,
)
from tolins.learning.artefacts import RunRefused, run_metadata, single_threaded_torch
from tolins.learning.curves import write_curves_csv
from tolins.stopping import DeferredSignals, raise_if_stopped, stop_requested

try:
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.logger import Logger
    from stable_baselines3.common.save_util import recursive_getattr
    from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
    from stable_baselines3.common.vec_env import VecMonitor

    from tolins.learning.agents.sb3_checkpoint import load_checkpoint, save_checkpoint, versions
    from tolins.rollouts.sb3_vec import Sb3VectorEnv
except ImportError as error:  # pragma: no cover - the rl extra is part of the test extra
    raise ImportError(
        "tolins.learning.agents.sb3 needs stable-baselines3: pip install 'tolins[rl]'"
    ) from error

ALGORITHMS = dict(zip(ALGORITHM_NAMES, (PPO, SAC), strict=True))
#: Observation ``[x̂−x*, ŷ−y*, θ̂−θ*, ẑ, F̂x, F̂y, q̂θ, F̂z]`` times this is of order 1.
OBSERVATION_SCALE = np.array([1.0, 1.0, 20.0, 0.1, 0.5, 0.5, 0.5, 0.5], dtype=np.float32)
#: First seed of the learning-curve episodes (training episodes draw from the model's seed).
CURVE_SEED = 30_000


class ScaledObservation(BaseFeaturesExtractor):
    """The observation times :data:`OBSERVATION_SCALE` (a fixed, saved part of the policy)."""

    def __init__(self, observation_space) -> None:
        super().__init__(observation_space, int(np.prod(observation_space.shape)))
        self.register_buffer("scale", torch.as_tensor(OBSERVATION_SCALE))

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        return observations.flatten(1) * self.scale


def make_model(config: Sb3Config, **overrides):
    """An untrained SB3 model of ``config`` on ``config.n_envs`` training envs stepped in one
    batch (:class:`~tolins.rollouts.sb3_vec.Sb3VectorEnv`): SB3's defaults but
    :data:`HYPERPARAMETERS` (and ``overrides``, keywords of the SB3 algorithm)."""
    env = VecMonitor(
        Sb3VectorEnv(
            config.env_id,
            config.n_envs,
            backend=config.backend,
            reward_mode=config.reward_mode,
        )
    )
    kwargs = {**HYPERPARAMETERS[config.algorithm], **overrides}
    if config.algorithm == "ppo":
        kwargs.setdefault("n_steps", max(PPO_ROLLOUT // config.n_envs, 1))
    kwargs["policy_kwargs"] = {
        "features_extractor_class": ScaledObservation,
        **kwargs.get("policy_kwargs", {}),
    }
    model = ALGORITHMS[config.algorithm]("MlpPolicy", env, seed=config.seed, device="cpu", **kwargs)
    # SB3's default logger makes a folder in the temporary directory per training and
    # writes nothing into it at verbose 0: a logger with no outputs makes none.
    model.set_logger(Logger(folder=None, output_formats=[]))
    return model


def curve_point(model, config: Sb3Config) -> dict[str, float]:
    """Mean sparse reward, success and collisions of the deterministic policy."""
    env = agent_env(config.env_id, backend=config.backend)
    rewards, successes, collisions = [], [], []
    for i in range(config.curve_episodes):
        observation, _ = env.reset(seed=CURVE_SEED + i)
        total, done = 0.0, False
        while not done:
            action, _ = model.predict(observation, deterministic=True)
            observation, reward, terminated, truncated, info = env.step(action)
            total, done = total + reward, terminated or truncated
        rewards.append(total)
        successes.append(float(info["success"]))
        collisions.append(info["n_collisions"])
    env.close()
    return {
        "reward": float(np.mean(rewards)),
        "success": float(np.mean(successes)),
        "collisions": float(np.mean(collisions)),
    }


def train_sb3(
    config: Sb3Config,
    out: str | Path,
    *,
    resume: bool = False,
    keep_checkpoint: bool = False,
    log: Callable[[str], None] | None = None,
    **overrides,
) -> list[dict[str, float]]:
    """Train ``config`` into ``out`` (``model.zip``, ``curves.csv``); the curve's rows.

    ``checkpoint.pt`` in ``out`` holds the training until it ends (module docstring), or
    with ``keep_checkpoint`` after it too, finished (for a caller that removes it once it
    has recorded the training: the bench's stage cache); with ``resume`` a training
    continues from it (a finished one only writes the model again), else it is refused
    (:class:`~tolins.learning.artefacts.RunRefused`, as are a checkpoint of another
    configuration and a training whose weights stop being finite). ``overrides``:
    keywords of the SB3 algorithm (for experiments)."""
    out = Path(out)
    run = _Run(config, out, overrides, resume=resume)
    model = run.model
    with single_threaded_torch(), DeferredSignals() as signals:
        checkpoints = _Checkpoints(run, signals)
        while model.num_timesteps < config.env_steps:
            run.learn(checkpoints)
            row = run.add_point()
            write_curves_csv(out / CURVES, run.history)
            if log is not None:
                log(
                    f"{config.algorithm} {row['env_steps']} steps ({row['train_steps_per_s']:.0f} "
                    f"steps/s training): reward {row['reward']:.2f}, success "
                    f"{row['success']:.2f}, collisions {row['collisions']:.2f}"
                )
        atomic_write(out / MODEL, model.save)
        if signals.pending is not None or keep_checkpoint:
            run.save()  # the finished training: a rerun only writes the model again
        if signals.pending is not None:
            signals.deliver()
    if not keep_checkpoint:
        run.path.unlink(missing_ok=True)
    return run.history


class _Run:
    """One training: its model, the state of its loop, and its checkpoint."""

    def __init__(
        self, config: Sb3Config, out: Path, overrides: dict[str, Any], *, resume: bool
    ) -> None:
        self.config, self.path = config, out / CHECKPOINT
        self.metadata = checkpoint_metadata(config, overrides)
        if self.path.exists() and not resume:
            raise RunRefused(
                f"{self.path} exists; allowed: resume=True to continue that training, or "
                "another folder"
            )
        for leftover in out.glob(f".{CHECKPOINT}.*.tmp"):  # of a process killed writing one
            leftover.unlink(missing_ok=True)
        self.model = make_model(config, **overrides)
        loop: dict[str, Any] = {"history": [], "learning_s": 0.0, "wall_s": 0.0, "target": None}
        if self.path.exists():
            try:
                loop = load_checkpoint(self.path, self.model, self.metadata)
            except BaseException:
                self.model.env.close()
                raise
        self.history: list[dict[str, float]] = list(loop["history"])
        self.learning_s: float = loop["learning_s"]
        self.target: int | None = loop["target"]
        self.began = time.perf_counter() - loop["wall_s"]
        self.learning_since: float | None = None

    def learn(self, callback: BaseCallback) -> None:
        """Train up to the next point of the curve (the rest of the running one after a
        resume; PPO ends on whole rollouts, so it may pass it)."""
        model, config = self.model, self.config
        if self.target is None:
            self.target = model.num_timesteps + min(
                config.curve_every, config.env_steps - model.num_timesteps
            )
        self.learning_since = time.perf_counter()
        try:
            model.learn(
                self.target - model.num_timesteps,
                callback=callback,
                reset_num_timesteps=model._last_obs is None,
            )
        except ValueError:  # torch's check of the policy's distribution, once NaN
            self.check_finite()
            raise
        self.learning_s += time.perf_counter() - self.learning_since
        self.learning_since, self.target = None, None
        self.check_finite()

    def add_point(self) -> dict[str, float]:
        """Score the policy now: the curve's next row."""
        trained = self.model.num_timesteps
        row = {
            "point": len(self.history),
            "env_steps": trained,
            **curve_point(self.model, self.config),
        }
        row["train_steps_per_s"] = trained / self.learning_s
        row["wall_s"] = time.perf_counter() - self.began
        self.history.append(row)
        return row

    def save(self) -> None:
        """Write the checkpoint (at the start of a rollout, or after the last point)."""
        self.check_finite()
        now = time.perf_counter()
        running = self.learning_since is not None
        loop = {
            "history": self.history,
            "learning_s": self.learning_s + (now - self.learning_since if running else 0.0),
            "wall_s": now - self.began,
            "target": self.model._total_timesteps if running else None,
        }
        save_checkpoint(self.path, self.model, self.metadata, loop)

    def check_finite(self) -> None:
        """:class:`RunRefused` once a weight is NaN or infinite (nothing of it is written)."""
        model = self.model
        _, variables = model._get_torch_save_params()
        tensors = [*model.policy.parameters(), *(recursive_getattr(model, v) for v in variables)]
        if not all(bool(torch.isfinite(t).all()) for t in tensors):
            raise RunRefused(
                f"{self.config.algorithm} diverged: weights not all finite after "
                f"{model.num_timesteps} env steps; no model or checkpoint of them written; "
                "allowed: other hyperparameters or another seed"
            )


class _Checkpoints(BaseCallback):
    """Writes the run's checkpoint at the start of a rollout once ``checkpoint_every`` env
    steps have passed since the last one, or a signal or a stop request is pending, and
    then lets that take effect."""

    def __init__(self, run: _Run, signals: DeferredSignals) -> None:
        super().__init__()
        self.run, self.signals = run, signals
        self.last = run.model.num_timesteps

    def _on_step(self) -> bool:
        return True

    def _on_rollout_start(self) -> None:
        steps = self.run.model.num_timesteps
        stopping = self.signals.pending is not None or stop_requested()
        if stopping or steps >= self.last + self.run.config.checkpoint_every:
            self.run.save()
            self.last = steps
        if self.signals.pending is not None:
            self.signals.deliver()
        raise_if_stopped()


def checkpoint_metadata(config: Sb3Config, overrides: dict[str, Any]) -> dict[str, Any]:
    """What a checkpoint records and a resume must match: the config (but its checkpoint
    interval), the overrides, and the versions of SB3 and torch."""
    settings = asdict(config)
    settings.pop("checkpoint_every")
    extra = {key: repr(value) for key, value in sorted(overrides.items())}
    return run_metadata(config.seed, sb3=settings, overrides=extra, versions=versions())
