"""stable-baselines3's ``VecEnv`` over the batched insertion env (needs ``tolins[rl]``).

``Sb3VectorEnv(env_id, n_envs)`` is what ``PPO("MlpPolicy", env)`` takes: the agent's view
of :func:`tolins.envs.wrappers.agent_env` (actions in ``[-1, 1]``, float32 observations,
gymnasium's ``RescaleAction`` applied to each env's action) on one
:class:`~tolins.envs.vector.InsertionVectorEnv`, with SB3's conventions:
``TimeLimit.truncated`` in every info, ``terminal_observation`` in the ended envs', an ended
env reset within the step that ended it, seeds from :meth:`seed` used at the next reset. It
steps as SB3's ``DummyVecEnv`` of ``n_envs`` such single envs would, episode for episode
(tested).

Each env's running episode is kept as its generator's state before the episode was drawn
and the actions since (at most a horizon of them): :meth:`Sb3VectorEnv.episodes` gives
them, and :meth:`Sb3VectorEnv.replay` puts a new env into that state by running them
again (an env's episode depends on nothing else), so that a training resumes from a
checkpoint bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from tolins.envs.tasks import make_vec
from tolins.envs.vector import check_actions_shape
from tolins.rollouts.infos import info_dict


@dataclass(frozen=True)
class RunningEpisode:
    """How one env's running episode came about: its generator's ``bit_generator.state``
    before the episode was drawn, and the actions ``(steps, 4)`` it has taken since."""

    rng_state: dict[str, Any]
    actions: np.ndarray


class Sb3VectorEnv(VecEnv):
    """``n_envs`` envs of ``env_id`` in one batch, for stable-baselines3.

    Args:
        env_id: A tolins id.
        n_envs: Number of envs.
        **kwargs: Keywords of :func:`tolins.make_vec` (``backend``, ``num_threads``,
            ``reward_mode``, …).
    """

    def __init__(self, env_id: str, n_envs: int = 1, **kwargs: Any) -> None:
        # Autoreset off: this adapter resets an ended env itself, in the same step, so
        # that it can note the env's generator before the next episode is drawn.
        vector = make_vec(env_id, n_envs, autoreset_mode="Disabled", **kwargs)
        vector = gym.wrappers.vector.RescaleAction(vector, -1.0, 1.0)
        self.vector = vector
        action_space = gym.spaces.Box(-1.0, 1.0, (4,), dtype=np.float32)
        observation_space = gym.spaces.Box(-np.inf, np.inf, (8,), dtype=np.float32)
        super().__init__(n_envs, observation_space, action_space)
        self._actions: np.ndarray | None = None
        self._starts: list[dict[str, Any] | None] = [None] * n_envs
        self._taken: list[list[np.ndarray]] = [[] for _ in range(n_envs)]

    def reset(self) -> np.ndarray:
        seeds = list(self._seeds)
        for i, seed in enumerate(seeds):
            rng = _generator_from_seed(seed) if seed is not None else self._rng(i)
            self._note_start(i, rng)
        given = None if all(s is None for s in seeds) else seeds
        observations, infos = self.vector.reset(seed=given, options=self._options[0] or None)
        self.reset_infos = [info_dict(infos, i) for i in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return observations.astype(np.float32)

    def step_async(self, actions: np.ndarray) -> None:
        """Hold ``actions`` ``(n_envs, 4)`` (each in ``[-1, 1]``) for :meth:`step_wait`;
        ``ValueError`` for another shape, before anything steps."""
        check_actions_shape(actions, self.num_envs, "one action in [-1, 1]^4 per env")
        self._actions = np.array(actions)

    def step_wait(self):
        observations, rewards, terminated, truncated, infos = self.vector.step(self._actions)
        for i, taken in enumerate(self._taken):
            taken.append(self._actions[i])
        dones = terminated | truncated
        rows = [info_dict(infos, i) for i in range(self.num_envs)]
        for i in range(self.num_envs):
            rows[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        if dones.any():
            ended = np.flatnonzero(dones)
            for i in ended:
                rows[i]["terminal_observation"] = observations[i].astype(np.float32)
            observations[ended] = self._restart(dones)[ended]
        return observations.astype(np.float32), rewards.astype(np.float32), dones, rows

    def _restart(self, mask: np.ndarray) -> np.ndarray:
        """Reset the envs of ``mask`` (noting each one's generator first): the observations."""
        rngs = self.vector.unwrapped.get_attr("np_random")
        for i in np.flatnonzero(mask):
            self._note_start(i, rngs[i])
        observations, infos = self.vector.reset(options={"reset_mask": mask})
        for i in np.flatnonzero(mask):
            self.reset_infos[i] = info_dict(infos, i)
        return observations

    def _rng(self, index: int) -> np.random.Generator:
        """Env ``index``'s generator (made, unseeded, if it has none yet)."""
        return self.vector.unwrapped.get_attr("np_random")[index]

    def _note_start(self, index: int, rng: np.random.Generator) -> None:
        self._starts[index] = rng.bit_generator.state
        self._taken[index] = []

    def episodes(self) -> list[RunningEpisode]:
        """Each env's running episode, as :meth:`replay` takes it."""
        if any(start is None for start in self._starts):
            raise ValueError("episodes() called before reset(); allowed: after the first reset")
        return [
            RunningEpisode(start, np.array(taken) if taken else np.zeros((0, 4), np.float32))
            for start, taken in zip(self._starts, self._taken, strict=True)
        ]

    def replay(self, episodes: Sequence[RunningEpisode]) -> np.ndarray:
        """Put this new env (never reset) into the state of the env whose :meth:`episodes`
        gave ``episodes``: each episode is drawn again from its generator's state and takes
        its actions again, each env's last one in the same call. The observations now."""
        if len(episodes) != self.num_envs or any(s is not None for s in self._starts):
            raise ValueError(
                f"replay of {len(episodes)} episodes on {self.num_envs} envs; allowed: one "
                "episode per env, on an env that has not been reset"
            )
        lengths = [len(episode.actions) for episode in episodes]
        depth = max(lengths)
        dtype = np.result_type(*(episode.actions.dtype for episode in episodes))
        self._reset_seeds()
        observations = np.zeros((self.num_envs, 8))
        for j in range(depth + 1):
            starting = np.array([depth - length == j for length in lengths])
            if starting.any():
                rngs = list(self.vector.unwrapped.get_attr("np_random"))
                for i in np.flatnonzero(starting):
                    rngs[i] = _generator_from_state(episodes[i].rng_state)
                self.vector.unwrapped.set_attr("np_random", rngs)
                observations[starting] = self._restart(starting)[starting]
            if j < depth:
                moving = np.array([j >= depth - length for length in lengths])
                actions = np.zeros((self.num_envs, 4), dtype=dtype)
                for i in np.flatnonzero(moving):
                    actions[i] = episodes[i].actions[j - (depth - lengths[i])]
                stepped = self.vector.step(actions)[0]
                observations[moving] = stepped[moving]
                for i in np.flatnonzero(moving):
                    self._taken[i].append(actions[i])
        return observations.astype(np.float32)

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


def _generator_from_seed(seed: int) -> np.random.Generator:
    """The generator a gymnasium env makes from ``seed``."""
    return gym.utils.seeding.np_random(seed)[0]


def _generator_from_state(state: dict[str, Any]) -> np.random.Generator:
    """A generator in ``state`` (a ``bit_generator.state``)."""
    generator = np.random.Generator(getattr(np.random, state["bit_generator"])())
    generator.bit_generator.state = state
    return generator
