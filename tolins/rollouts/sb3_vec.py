"""stable-baselines3's ``VecEnv`` over the batched insertion env (needs ``tolins[rl]``).

``Sb3VectorEnv(env_id, n_envs)`` is what ``PPO("MlpPolicy", env)`` takes: the agent's view
of :func:`tolins.envs.wrappers.agent_env` (actions in ``[-1, 1]``, float32 observations,
gymnasium's ``RescaleAction`` applied to each env's action) on one
:class:`~tolins.envs.vector.InsertionVectorEnv` in ``SameStep`` autoreset, with SB3's
conventions: ``TimeLimit.truncated`` in every info, ``terminal_observation`` in the ended
envs', seeds from :meth:`seed` used at the next reset. It steps as SB3's ``DummyVecEnv``
of ``n_envs`` such single envs would, episode for episode (tested).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from tolins.envs.tasks import make_vec
from tolins.envs.vector import check_actions_shape
from tolins.rollouts.infos import info_dict


class Sb3VectorEnv(VecEnv):
    """``n_envs`` envs of ``env_id`` in one batch, for stable-baselines3.

    Args:
        env_id: A tolins id.
        n_envs: Number of envs.
        **kwargs: Keywords of :func:`tolins.make_vec` (``backend``, ``num_threads``,
            ``reward_mode``, …).
    """

    def __init__(self, env_id: str, n_envs: int = 1, **kwargs: Any) -> None:
        vector = make_vec(env_id, n_envs, autoreset_mode="SameStep", **kwargs)
        vector = gym.wrappers.vector.RescaleAction(vector, -1.0, 1.0)
        self.vector = vector
        action_space = gym.spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        observation_space = gym.spaces.Box(-np.inf, np.inf, (8,), dtype=np.float32)
        super().__init__(n_envs, observation_space, action_space)
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        observations, infos = self.vector.reset(seed=seeds, options=self._options[0] or None)
        self.reset_infos = [info_dict(infos, i) for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return observations.astype(np.float32)

    def step_async(self, actions: np.ndarray) -> None:
        """Hold ``actions`` ``(n_envs, 4)`` (each in ``[-1, 1]``) for :meth:`step_wait`;
        ``ValueError`` for another shape, before anything steps."""
        check_actions_shape(actions, self.num_envs, "one action in [-1, 1]^4 per env")
        self._actions = np.asarray(actions)

    def step_wait(self):
        observations, rewards, terminated, truncated, infos = self.vector.step(self._actions)
        dones = terminated | truncated
        rows = []
        for i in range(self.num_envs):
            row = info_dict(infos, i)
            limit = bool(truncated[i] and not terminated[i])
            if dones[i]:
                reset_info = {k: v for k, v in row.items() if not k.startswith("final_")}
                row = {
                    **row["final_info"],
                    "TimeLimit.truncated": limit,
                    "terminal_observation": np.asarray(row["final_obs"], np.float32),
                }
                self.reset_infos[i] = reset_info
            else:
                row["TimeLimit.truncated"] = limit
            rows.append(row)
        return observations.astype(np.float32), rewards.astype(np.float32), dones, rows

    def close(self) -> None:
        self.vector.close()

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        """Env ``i``'s ``attr_name`` (the vector env's ``get_attr``), or the batch's own
        attribute where no env has one of its own (``spec``, ``backend``)."""
        vector = self.vector.unwrapped
        try:
            values = vector.get_attr(attr_name)
        except AttributeError:
            return [getattr(vector, attr_name) for _ in self._indices(indices)]
        return [values[i] for i in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        """Set ``attr_name`` of the envs ``indices`` to ``value`` (the vector env's
        ``set_attr``: ``goal`` and ``np_random``); the other envs keep theirs."""
        vector = self.vector.unwrapped
        values = list(vector.get_attr(attr_name))
        for i in self._indices(indices):
            values[i] = value
        vector.set_attr(attr_name, values)

    def env_method(self, method_name: str, *args, indices: Any = None, **kwargs) -> list[Any]:
        raise AttributeError(f"env_method({method_name!r}): call the vector env (.vector) instead")

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False for _ in self._indices(indices)]

    def _indices(self, indices: Any) -> Sequence[int]:
        if indices is None:
            return range(self.num_envs)
        return [indices] if isinstance(indices, int) else list(indices)
