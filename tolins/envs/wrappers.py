"""What a deep-RL library (e.g. stable-baselines3) needs around the insertion env.

The env keeps the paper's physical units: actions in mm/s and rad/s within ``±a_max``,
float64 observations. SB3's PPO and SAC squash or clip their actions to ``[-1, 1]`` and
store float32 observations, so :func:`agent_env` adds two standard gymnasium wrappers:

* ``RescaleAction(-1, 1)``: ``a = a_max · u`` for the agent's ``u`` in ``[-1, 1]`` (a
  float32 ``Box``);
* :class:`Float32Observation`: the same 8 observations, as float32.

Both are recovered from an SB3 zip's own spaces, so ``tolins evaluate --policy
model.zip`` scores such a model on the unwrapped env without them
(:func:`tolins.learning.agents.external.load_sb3`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np


class Float32Observation(gym.ObservationWrapper):
    """The observations as float32 (gymnasium's ``DtypeObservation`` without its warnings
    about the infinite bounds)."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        shape = env.observation_space.shape
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape, dtype=np.float32)

    def observation(self, observation: np.ndarray) -> np.ndarray:
        return np.asarray(observation, dtype=np.float32)


def agent_env(env: gym.Env | str, **kwargs: Any) -> gym.Env:
    """``env`` (or ``gymnasium.make(env, **kwargs)`` for an id) with actions in ``[-1, 1]``
    and float32 observations, ready for ``stable_baselines3.PPO("MlpPolicy", env)``."""
    if isinstance(env, str):
        env = gym.make(env, **kwargs)
    elif kwargs:
        raise ValueError(f"keywords {sorted(kwargs)} given with an env object; allowed: an env id")
    env = gym.wrappers.RescaleAction(env, -1.0, 1.0)
    env.action_space = gym.spaces.Box(-1.0, 1.0, env.action_space.shape, dtype=np.float32)
    return Float32Observation(env)
