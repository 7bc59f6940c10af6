"""Each env of the batched insertion env seen as a single env, for gymnasium's vector API.

``SyncVectorEnv.call(name)``, ``get_attr(name)`` and ``set_attr(name, values)`` act on its
sub-envs one by one. :class:`~tolins.envs.vector.InsertionVectorEnv` has no sub-env
objects, so it answers them through an :class:`EnvView` per env: the attributes of
``InsertionEnv`` that mean something per env, read from (and written to) that env's slot
of the batch. What each means:

==================  ====  ===========================================================
attribute           set   env ``i``'s
==================  ====  ===========================================================
``socket``                workpiece of its current episode (``sockets[i]``)
``goal``            yes   goal; setting it moves the running episode's and later ones'
``np_random``       yes   random generator (noise, workpiece and pose draws)
``np_random_seed``        seed of that generator (``-1`` after ``np_random`` was set)
``render``                method: its ``rgb_array`` frame (``None`` without render mode)
``nominal_socket``,       the task's settings and simulator, the same for every env
``settings``, …           (``settings``: all of them; ``backend_name``; see ``InsertionEnv``)
``action_space``,         the single env's spaces (the vector env's ``single_*``)
``observation_space``
``render_mode``,          the single env's (``InsertionEnv.metadata``)
``metadata``
==================  ====  ===========================================================

The single env's ``backend`` (its own simulator) has no per-env counterpart: the batch
(``physics``) simulates every env. Names outside this table raise ``AttributeError``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding

from tolins.envs.insertion_env import InsertionEnv
from tolins.envs.task_settings import SettingsAttributes, TaskSettings
from tolins.geometry.specs import SocketSpec
from tolins.geometry.workspace import check_goal

if TYPE_CHECKING:
    from tolins.envs.vector import InsertionVectorEnv


class EnvView(SettingsAttributes):
    """Env ``index`` of ``vector`` through the single env's attributes (module docstring)."""

    def __init__(self, vector: InsertionVectorEnv, index: int) -> None:
        self._vector = vector
        self._index = index

    @property
    def settings(self) -> TaskSettings:
        """The task's validated settings."""
        return self._vector.settings

    @property
    def backend_name(self) -> str:
        """The simulator's name (``"mujoco"``, ``"kinematic"`` or ``"warp"``)."""
        return self._vector.backend_name

    @property
    def socket(self) -> SocketSpec:
        """The workpiece of this env's current episode."""
        return self._vector.episodes[self._index].socket

    @property
    def goal(self) -> np.ndarray:
        """This env's goal ``[x*, y*, theta*]`` (mm, rad)."""
        return self._vector.episodes[self._index].goal

    @goal.setter
    def goal(self, value: Any) -> None:
        self._vector.episodes[self._index].goal = value

    @property
    def np_random(self) -> np.random.Generator:
        """This env's random generator; made from a fresh seed if it has none yet, as
        ``gymnasium.Env.np_random``."""
        vector, i = self._vector, self._index
        if vector.env_rngs[i] is None:
            vector.env_rngs[i], vector.env_seeds[i] = seeding.np_random()
        return vector.env_rngs[i]

    @np_random.setter
    def np_random(self, value: np.random.Generator) -> None:
        self._vector.env_rngs[self._index] = check_value("np_random", value)
        self._vector.env_seeds[self._index] = -1  # gymnasium's: not a seed to make it from

    @property
    def np_random_seed(self) -> int:
        """The seed of this env's generator (``-1`` after ``np_random`` was set)."""
        self.np_random  # noqa: B018 - made on first use, as gymnasium's
        return self._vector.env_seeds[self._index]

    @property
    def action_space(self) -> gym.spaces.Box:
        """The single env's action space (``single_action_space``)."""
        return self._vector.single_action_space

    @property
    def observation_space(self) -> gym.spaces.Box:
        """The single env's observation space (``single_observation_space``)."""
        return self._vector.single_observation_space

    @property
    def render_mode(self) -> str | None:
        """The vector env's render mode, which every env draws with."""
        return self._vector.render_mode

    @property
    def metadata(self) -> dict[str, Any]:
        """The single env's metadata (its render modes and frame rate)."""
        return InsertionEnv.metadata

    def render(self) -> np.ndarray | None:
        """This env's ``rgb_array`` frame, or ``None`` without ``render_mode="rgb_array"``."""
        return self._vector.render_env(self._index)


#: Every name :class:`EnvView` answers.
VIEW_ATTRIBUTES = tuple(sorted(name for name in dir(EnvView) if not name.startswith("_")))
#: The names ``set_attr`` may set.
SETTABLE = tuple(
    name
    for name in VIEW_ATTRIBUTES
    if isinstance(getattr(EnvView, name), property) and getattr(EnvView, name).fset
)


def check_name(name: object, settable: bool = False) -> str:
    """``name`` if an :class:`EnvView` answers it (and, with ``settable``, may set it);
    ``AttributeError`` naming it and the allowed ones otherwise."""
    allowed = SETTABLE if settable else VIEW_ATTRIBUTES
    if name not in allowed:
        what = "settable" if settable else "per-env"
        raise AttributeError(
            f"{name!r} is not a {what} attribute of InsertionVectorEnv's envs; allowed: "
            f"{', '.join(allowed)}"
        )
    return name


def check_value(name: str, value: Any) -> Any:
    """``value`` checked for the settable attribute ``name`` (``ValueError`` naming it), so
    that ``set_attr`` can check every env's value before it sets any."""
    if name == "goal":
        return check_goal(value)
    if not isinstance(value, np.random.Generator):
        raise ValueError(f"np_random={value!r}; allowed: a numpy.random.Generator")
    return value
