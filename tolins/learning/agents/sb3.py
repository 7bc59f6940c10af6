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
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from tolins.atomic import atomic_write
from tolins.envs.wrappers import agent_env
from tolins.learning.agents.sb3_config import (
    ALGORITHM_NAMES,
    CURVES,
    HYPERPARAMETERS,
    MODEL,
    PPO_ROLLOUT,
    Sb3Config,
)
from tolins.learning.artefacts import single_threaded_torch
from tolins.learning.curves import write_curves_csv

try:
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.logger import Logger
    from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
    from stable_baselines3.common.vec_env import VecMonitor

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
    log: Callable[[str], None] | None = None,
    **overrides,
) -> list[dict[str, float]]:
    """Train ``config`` into ``out`` (``model.zip``, ``curves.csv``); the curve's rows.
    ``overrides``: keywords of the SB3 algorithm (for experiments)."""
    out = Path(out)
    model = make_model(config, **overrides)
    began, learning_s, history = time.perf_counter(), 0.0, []
    with single_threaded_torch():
        while model.num_timesteps < config.env_steps:
            chunk = min(config.curve_every, config.env_steps - model.num_timesteps)
            start = time.perf_counter()
            model.learn(chunk, reset_num_timesteps=model.num_timesteps == 0)
            learning_s += time.perf_counter() - start
            trained = model.num_timesteps  # PPO ends on whole rollouts: may pass the chunk
            row = {"point": len(history), "env_steps": trained, **curve_point(model, config)}
            row["train_steps_per_s"] = trained / learning_s
            row["wall_s"] = time.perf_counter() - began
            history.append(row)
            write_curves_csv(out / CURVES, history)
            if log is not None:
                log(
                    f"{config.algorithm} {trained} steps ({row['train_steps_per_s']:.0f} steps/s "
                    f"training): reward {row['reward']:.2f}, success {row['success']:.2f}, "
                    f"collisions {row['collisions']:.2f}"
                )
    atomic_write(out / MODEL, model.save)
    return history
