"""The batched insertion env: ``num_envs`` episodes stepped together, each the single env's.

``gymnasium.make_vec("tolins/Circle2x2-v1", num_envs=N, vectorization_mode=
"vector_entry_point")`` and :func:`tolins.make_vec` build an :class:`InsertionVectorEnv`:
one batched simulator (:mod:`tolins.physics`: MuJoCo on ``mujoco.batch``'s thread pool,
the kinematic model as numpy, MuJoCo Warp) under one
:class:`~tolins.envs.episode_state.EpisodeState` per env, which does what ``InsertionEnv``
does with its own random generator (noise, reward, success, defect draws). Env ``i`` reset
with seed ``s`` runs the episodes of ``gymnasium.make(id)`` reset with seed ``s``, bit for
bit (tested), at any thread count. It answers gymnasium's vector API as ``SyncVectorEnv``
of single envs does (``call``, ``get_attr``, ``set_attr``, ``render``; per-env attributes
in :mod:`tolins.envs.vector_views`).
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from tolins.envs.actions import check_action
from tolins.envs.episode_state import RESET_OPTIONS, EpisodeState
from tolins.envs.rendering import FRAME_SIZE, close_renderer, draw_frame, open_renderer
from tolins.envs.task_settings import TaskSettings, check_capabilities, keywords_of
from tolins.envs.vector_views import EnvView, check_name, check_value
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int, is_seed
from tolins.paper import A_MAX
from tolins.physics import BatchPhysics, make_batch
from tolins.physics.registry import with_capability

_AUTORESET = {mode.value: mode for mode in AutoresetMode}
#: The backends whose simulations can be drawn (``render_mode="rgb_array"``).
DRAWABLE_BACKENDS = with_capability("supports_render")


def batch_infos(infos: list[dict[str, Any] | None], n: int) -> dict[str, Any]:
    """gymnasium's batched info of the per-env ``infos`` (``None``: no info), as
    ``VectorEnv._add_info`` builds it env by env (the same keys, arrays, dtypes and ``_key``
    masks), one array per key."""
    present = [i for i, info in enumerate(infos) if info is not None]
    keys: dict[str, None] = {}
    for i in present:
        keys.update(dict.fromkeys(infos[i]))
    out: dict[str, Any] = {}
    for key in keys:
        rows = [i for i in present if key in infos[i]]
        values = [infos[i][key] for i in rows]
        where: Any = slice(None) if len(rows) == n else rows
        first = values[0]
        array: Any
        if (
            key == "final_obs"
            or not (
                isinstance(first, (dict, np.ndarray, np.number))
                or type(first) in (int, float, bool)
            )
            or any(value is None for value in values)  # info["damaged_at"]: a step or None
        ):  # gymnasium keeps these (and every final_obs) as objects
            array = np.full(n, None, dtype=object)
            for i, value in zip(rows, values, strict=True):
                array[i] = value
        elif isinstance(first, dict):
            per_env: list[dict[str, Any] | None] = [None] * n
            for i, value in zip(rows, values, strict=True):
                per_env[i] = value
            array = batch_infos(per_env, n)
        elif isinstance(first, np.ndarray):
            array = np.zeros((n, *first.shape), dtype=first.dtype)
            array[where] = np.array(values)
        else:
            array = np.zeros(n, dtype=type(first))
            array[where] = values
        mask = np.zeros(n, dtype=bool)
        mask[where] = True
        out[key], out[f"_{key}"] = array, mask
    return out


def _per_env_seeds(seed: int | list[int | None] | None, n: int) -> list[int | None]:
    """Gymnasium's rule: an int seeds env ``i`` with ``seed + i``; a list gives each its own.
    Seeds are integers ≥ 0 (numpy's as well, returned as Python ints)."""
    allowed = f"None, an int ≥ 0, or a list of {n} ints ≥ 0 or None"
    if seed is None:
        return [None] * n
    if is_seed(seed):
        return [int(seed) + i for i in range(n)]
    if not isinstance(seed, (list, tuple)) or len(seed) != n:
        raise ValueError(f"seed={seed!r}; allowed: {allowed}")
    for i, value in enumerate(seed):
        if value is not None and not is_seed(value):
            raise ValueError(f"seed[{i}]={value!r} is not a seed; allowed: {allowed}")
    return [None if value is None else int(value) for value in seed]


def _check_options(options: object) -> dict[str, Any]:
    """A copy of ``options`` if it is ``None`` or a dict (its keys are checked later)."""
    if options is None:
        return {}
    if not isinstance(options, dict):
        keys = ", ".join(map(repr, (*RESET_OPTIONS, "reset_mask")))
        raise ValueError(f"options={options!r}; allowed: None or a dict with keys {keys}")
    return dict(options)


def check_actions_shape(actions: Any, num_envs: int, allowed: str) -> None:
    """``ValueError`` naming ``actions``' shape unless it is ``(num_envs, 4)`` (a ragged list
    included); ``allowed`` says what a row is."""
    try:
        shape: Any = np.shape(actions)
    except ValueError:  # rows of different lengths
        shape = "ragged (rows of different lengths)"
    if shape != (num_envs, 4):
        raise ValueError(f"actions have shape {shape}; allowed: ({num_envs}, 4), {allowed}")


class InsertionVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` insertion envs (``InsertionEnv``'s task, spaces and info) in one batch.

    Args:
        num_envs: Number of envs.
        socket: The socket, as ``InsertionEnv``'s (the ids' presets pass theirs).
        backend: ``"mujoco"`` (``mujoco.batch``), ``"kinematic"`` or ``"warp"``.
        num_threads: Threads of the MuJoCo batch, at most the machine's cores; default: the
            cores this process may run on.
        device: Warp's device (``"cpu"``, ``"cuda:0"``), for ``backend="warp"`` only.
        autoreset_mode: ``"NextStep"`` (gymnasium's default: an env that ended is reset by
            the next ``step``, which returns its first observation, reward 0 and the reset's
            info) or ``"SameStep"`` (reset within the step that ends it; that step's last
            observation and info are in ``info["final_obs"]`` / ``info["final_info"]``) or
            ``"Disabled"`` (no autoreset: an env whose episode has ended, or that a masked
            reset has not reset yet, is not stepped — its row repeats its last observation
            with reward 0 and no ``info`` — until ``reset(options={"reset_mask": mask})``
            resets it).
        goal: The goal of every env, as ``InsertionEnv``'s.
        render_mode: ``None`` or ``"rgb_array"`` (``render()``: one frame per env, each the
            single env's frame of the same state; not on ``backend="warp"``).
        **settings: The task's settings, as ``InsertionEnv`` takes them: every attribute
            of :class:`~tolins.envs.task_settings.TaskSettings` (its docstring gives their
            meaning and defaults: ``measurement_noise``, ``horizon``, ``reward_mode``,
            ``physics_version``, …), validated there once; any other keyword raises
            ``ValueError`` naming it and the allowed ones (:data:`VECTOR_KEYWORDS`).

    ``info`` holds every key of the single env's, batched, with gymnasium's ``_key``
    masks. ``reset(seed=s)`` seeds env ``i`` with ``s + i``; ``reset(seed=[s0, s1, ...])``
    each with its own (Python or numpy integers); options (``pose``, ``goal``) apply to
    every env reset by that call, ``options["reset_mask"]`` (a bool per env, gymnasium's)
    resets only those envs. A reset or step that raises changes nothing; after a failed
    reset every step raises ``gymnasium.error.ResetNeeded`` until a reset succeeds.
    ``step`` before the first ``reset`` raises ``ResetNeeded`` in every autoreset mode, as
    the single env does. ``close()`` releases the batch and the renderers; a later
    ``reset``, ``step`` or ``render`` raises ``gymnasium.error.ClosedEnvironmentError``.

    **Vector API** (``SyncVectorEnv``'s semantics, as if each env were an ``InsertionEnv``):
    ``call(name, *args, **kwargs)`` gives a tuple with env ``i``'s attribute ``name``, called
    with the arguments if it is a method; ``get_attr(name)`` is ``call(name)``;
    ``set_attr(name, values)`` sets env ``i``'s attribute to ``values[i]`` (a list or tuple
    of ``num_envs``) or every env's to ``values`` (anything else: a goal for every env is
    an array, since a list is per env); ``render()`` is ``call("render")``. The per-env
    attributes: ``socket`` (env ``i``'s workpiece), ``goal`` and ``np_random`` (settable),
    ``np_random_seed``, ``render``, the task's settings (``nominal_socket``, ``horizon``,
    …, the same for every env), the single env's spaces, ``render_mode`` and ``metadata``
    (table in :mod:`tolins.envs.vector_views`). Any other name raises ``AttributeError``.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "autoreset_mode": AutoresetMode.NEXT_STEP,
        "render_modes": ["rgb_array"],
        "render_fps": 4,
    }

    def __init__(
        self,
        num_envs: int = 1,
        socket: SocketSpec | None = None,
        *,
        backend: str = "mujoco",
        num_threads: int | None = None,
        device: str | None = None,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        goal: Any = (0.0, 0.0, 0.0),
        render_mode: str | None = None,
        **settings: Any,
    ) -> None:
        if socket is None:
            raise ValueError("socket is required; allowed: a CircularSocket or PolygonSocket")
        self.settings = TaskSettings.build(InsertionVectorEnv, socket, settings)
        _check_render_mode(render_mode, backend)
        mode = getattr(autoreset_mode, "value", autoreset_mode)
        if mode not in _AUTORESET:
            raise ValueError(f"autoreset_mode={autoreset_mode!r}; allowed: {sorted(_AUTORESET)}")
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        self.backend_name = backend
        self.metadata = {**self.metadata, "autoreset_mode": _AUTORESET[mode]}
        self.render_mode = render_mode
        check_capabilities(self.settings, backend)
        self.physics: BatchPhysics | None = make_batch(
            backend,
            socket,
            self.num_envs,
            self.settings.control_dt,
            physics_version=self.settings.version,
            num_threads=num_threads,
            device=device,
            persistent=render_mode is not None,
            robot=self.settings.robot,
            pins=self.settings.elastic,
        )
        self.single_action_space = gym.spaces.Box(-A_MAX, A_MAX, dtype=np.float64)
        self.single_observation_space = gym.spaces.Box(-np.inf, np.inf, (8,), np.float64)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.episodes = [EpisodeState(self.settings, goal) for _ in range(self.num_envs)]
        #: Each env's random generator and the seed it was made from (``None``: not yet).
        self.env_rngs: list[np.random.Generator | None] = [None] * self.num_envs
        self.env_seeds: list[int | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        #: Whether any env has had a state (set in ``_begin``): ``step`` needs a reset first.
        self._started = False
        self._views = [EnvView(self, i) for i in range(self.num_envs)]
        # Renderers by identity of the model they draw, the least recently drawn first.
        self._renderers: dict[int, tuple[mujoco.MjModel, mujoco.Renderer]] = {}

    @property
    def sockets(self) -> list[SocketSpec]:
        """Each env's workpiece of its current episode."""
        return [episode.socket for episode in self.episodes]

    def reset(
        self,
        *,
        seed: int | list[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        self._check_open()
        seeds = _per_env_seeds(seed, self.num_envs)
        options = _check_options(options)
        mask = np.ones(self.num_envs, dtype=bool)
        if "reset_mask" in options:
            mask = np.asarray(options.pop("reset_mask"))
            if mask.shape != (self.num_envs,) or mask.dtype != bool or not mask.any():
                raise ValueError(
                    f"options['reset_mask']={mask!r}; allowed: {self.num_envs} bools, at "
                    "least one True"
                )
        if seed is not None and isinstance(seeds[0], int):
            self._np_random, self._np_random_seed = seeding.np_random(seeds[0])
        ids = np.flatnonzero(mask)
        for i in ids:
            if seeds[i] is not None or self.env_rngs[i] is None:
                self.env_rngs[i], self.env_seeds[i] = seeding.np_random(seeds[i])
        try:
            plans = [self.episodes[i].plan(self.env_rngs[i], options) for i in ids]
        except Exception:
            for i in ids:
                self.episodes[i].broken = True
            raise
        observations, reset_infos = self._begin(ids, plans)
        if not mask.all():
            observations[~mask] = [self.episodes[i].observation for i in np.flatnonzero(~mask)]
        env_infos: list[dict[str, Any] | None] = [None] * self.num_envs
        for i, info in zip(ids.tolist(), reset_infos, strict=True):
            env_infos[i] = info
        infos = batch_infos(env_infos, self.num_envs)
        self._autoreset[ids] = False
        return observations, infos

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        self._check_open()
        if not self._started:
            raise gym.error.ResetNeeded("step() called before reset()")
        check_actions_shape(actions, self.num_envs, "one [ux, uy, utheta, uz] per env")
        mode = self.metadata["autoreset_mode"]
        same_step = mode == AutoresetMode.SAME_STEP
        if mode == AutoresetMode.DISABLED:
            running = np.array([i for i, e in enumerate(self.episodes) if e.running], np.intp)
        else:
            running = np.flatnonzero(~self._autoreset)
        for i in running:
            self.episodes[i].check_running()
        velocities = np.array([check_action(actions[i]) for i in running]).reshape(-1, 4)

        observations = np.array([episode.observation for episode in self.episodes])
        rewards = np.zeros(self.num_envs)
        terminations = np.zeros(self.num_envs, dtype=bool)
        truncations = np.zeros(self.num_envs, dtype=bool)
        env_infos: list[dict[str, Any] | None] = [None] * self.num_envs
        if running.size:
            state = self.physics.step(running, velocities)
            for k, i in enumerate(running.tolist()):
                obs, reward, terminated, truncated, info = self.episodes[i].advance(
                    state.row(k), self.env_rngs[i]
                )
                observations[i], rewards[i] = obs, reward
                terminations[i], truncations[i] = terminated, truncated
                env_infos[i] = info
        ended = terminations | truncations
        resetting = ended if same_step else self._autoreset
        if mode == AutoresetMode.DISABLED:
            resetting = np.zeros(self.num_envs, bool)
        if resetting.any():
            ids = np.flatnonzero(resetting)
            plans = [self.episodes[i].plan(self.env_rngs[i], None) for i in ids]
            reset_observations, reset_infos = self._begin(ids, plans)
            for i, info in zip(ids.tolist(), reset_infos, strict=True):
                if same_step:  # gymnasium's: the step's last observation and info aside
                    info = {"final_obs": observations[i].copy(), "final_info": env_infos[i], **info}
                env_infos[i] = info
            observations[ids] = reset_observations[ids]
        infos = batch_infos(env_infos, self.num_envs)
        self._autoreset = np.zeros(self.num_envs, bool) if same_step else ended
        return observations, rewards, terminations, truncations, infos

    def _begin(self, ids: np.ndarray, plans: list) -> tuple[np.ndarray, list[dict[str, Any]]]:
        """Start the planned episodes of envs ``ids``: observations ``(num_envs, 8)`` (rows
        ``ids`` set) and each one's info."""
        for i, plan in zip(ids.tolist(), plans, strict=True):
            self.physics.set_socket(i, plan.socket)
            plan.apply_physics(lambda draw, i=i: self.physics.set_physics(i, draw))
            plan.apply_grasp(lambda grasp, i=i: self.physics.set_grasp(i, grasp))
        poses = np.array([plan.pose for plan in plans])
        keep = np.array([plan.keep_part for plan in plans], dtype=bool)
        state = self.physics.reset(ids, poses, keep_part=keep)
        observations, infos = np.zeros((self.num_envs, 8)), []
        for k, (i, plan) in enumerate(zip(ids, plans, strict=True)):
            row = state.row(k)
            self._started = True  # begin sets the episode's state before anything can fail
            observations[i], info = self.episodes[i].begin(plan, row, self.env_rngs[i])
            infos.append(info)
        return observations, infos

    def render(self) -> tuple[np.ndarray | None, ...]:
        """Each env's frame (``render_env``), as ``SyncVectorEnv.render`` gives its envs'."""
        return self.call("render")

    def render_env(self, index: int) -> np.ndarray | None:
        """Env ``index``'s ``rgb_array`` frame ``(480, 640, 3)``, the single env's of the same
        state; ``None`` without ``render_mode="rgb_array"``. ``ResetNeeded`` before the env's
        first reset, as gymnasium's ``OrderEnforcing``."""
        self._check_open()
        if self.episodes[index].state is None:
            raise gym.error.ResetNeeded(f"render() of env {index} called before its reset()")
        if self.render_mode is None:
            return None
        model, data = self.physics.drawing(index)
        return draw_frame(self._renderer(model), data)

    def _renderer(self, model: mujoco.MjModel) -> mujoco.Renderer:
        """A renderer of ``model``, kept while its model is among the ``num_envs`` drawn last
        (the cache holds the model, so its id is not reused meanwhile)."""
        entry = self._renderers.pop(id(model), None)
        if entry is None:
            if len(self._renderers) >= self.num_envs:
                close_renderer(self._renderers.pop(next(iter(self._renderers)))[1])
            entry = (model, open_renderer(model, *FRAME_SIZE))
        self._renderers[id(model)] = entry  # the last drawn at the end
        return entry[1]

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """Env ``i``'s attribute ``name`` for each ``i``, called with ``args`` and ``kwargs``
        if it is callable (``SyncVectorEnv.call``)."""
        check_name(name)
        results = []
        for view in self._views:
            value = getattr(view, name)
            results.append(value(*args, **kwargs) if callable(value) else value)
        return tuple(results)

    def get_attr(self, name: str) -> tuple[Any, ...]:
        """Env ``i``'s attribute ``name`` for each ``i`` (``call(name)``, as gymnasium's)."""
        return self.call(name)

    def set_attr(self, name: str, values: list[Any] | tuple[Any, ...] | Any) -> None:
        """Set env ``i``'s attribute ``name`` to ``values[i]`` (a list or tuple of
        ``num_envs`` values) or every env's to ``values``; every value is checked before
        any is set."""
        check_name(name, settable=True)
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        if len(values) != self.num_envs:
            raise ValueError(
                f"set_attr({name!r}) got {len(values)} values; allowed: a list or tuple of "
                f"{self.num_envs} (one per env) or one value for every env"
            )
        checked = [check_value(name, value) for value in values]
        for view, value in zip(self._views, checked, strict=True):
            setattr(view, name, value)

    def _check_open(self) -> None:
        """``gymnasium.error.ClosedEnvironmentError`` once the env is closed."""
        if self.closed:
            raise gym.error.ClosedEnvironmentError(
                "this InsertionVectorEnv is closed: close() released its batch; make a new one"
            )

    def close_extras(self, **kwargs: Any) -> None:
        """Release the renderers and the batch (its simulations, models and threads)."""
        for _, renderer in self._renderers.values():
            close_renderer(renderer)
        self._renderers = {}
        physics, self.physics = self.physics, None
        physics.close()


#: Every keyword ``InsertionVectorEnv`` takes: its own, then the settings'.
VECTOR_KEYWORDS = keywords_of(InsertionVectorEnv)


def _check_render_mode(render_mode: object, backend: str) -> None:
    """``ValueError`` unless ``render_mode`` is one the vector env draws on ``backend``."""
    if render_mode is None:
        return
    if not (isinstance(render_mode, str) and render_mode == "rgb_array"):
        raise ValueError(f"render_mode={render_mode!r}; allowed: None, 'rgb_array'")
    if backend not in DRAWABLE_BACKENDS:
        raise ValueError(
            f"render_mode='rgb_array' is not supported on backend={backend!r}; allowed: "
            f"backend {', '.join(map(repr, DRAWABLE_BACKENDS))}, or render_mode=None"
        )
