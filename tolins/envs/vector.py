"""The batched insertion env: ``num_envs`` episodes stepped together, each the single env's.

``gymnasium.make_vec("tolins/Circle2x2-v1", num_envs=N, vectorization_mode=
"vector_entry_point")`` and :func:`tolins.make_vec` build an :class:`InsertionVectorEnv`:
one batched simulator (:mod:`tolins.envs.mujoco_batch` on ``mujoco.batch``'s thread pool,
:mod:`tolins.envs.kinematic_batch` as numpy) under one
:class:`~tolins.envs.episode_state.EpisodeState` per env, which does what ``InsertionEnv``
does with its own random generator (noise, reward, success, defect draws). Env ``i`` reset
with seed ``s`` runs the episodes of ``gymnasium.make(id)`` reset with seed ``s``, bit for
bit (tested), at any thread count.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from tolins.envs.batch import BatchPhysics
from tolins.envs.episode import TaskSettings, check_action
from tolins.envs.episode_state import EpisodeState
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import check_int
from tolins.paper import A_MAX

#: Batched simulators by name (``warp`` needs ``pip install 'tolins[warp]'``).
BATCH_BACKENDS = ("mujoco", "kinematic", "warp")
_AUTORESET = {mode.value: mode for mode in AutoresetMode}


def make_batch_physics(
    backend: str,
    socket: SocketSpec,
    num_envs: int,
    control_dt: float,
    num_threads: int | None = None,
    device: str | None = None,
) -> BatchPhysics:
    """The batched simulator ``backend`` of ``num_envs`` copies of ``socket``."""
    if backend not in BATCH_BACKENDS:
        raise ValueError(f"backend={backend!r}; allowed: {', '.join(map(repr, BATCH_BACKENDS))}")
    if device is not None and backend != "warp":
        raise ValueError(f"device={device!r} is for backend='warp' only; got backend={backend!r}")
    if backend == "mujoco":
        from tolins.envs.mujoco_batch import MujocoBatch

        return MujocoBatch(socket, num_envs, control_dt, num_threads)
    if backend == "kinematic":
        from tolins.envs.kinematic_batch import KinematicBatch

        return KinematicBatch(socket, num_envs, control_dt)
    from tolins.envs.warp_batch import WarpBatch  # raises a clear ImportError without warp

    return WarpBatch(socket, num_envs, control_dt, device=device or "cpu")


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
        if key == "final_obs" or not (
            isinstance(first, (dict, np.ndarray, np.number)) or type(first) in (int, float, bool)
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
    """Gymnasium's rule: an int seeds env ``i`` with ``seed + i``; a list gives each its own."""
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
        return [int(seed) + i for i in range(n)]
    if isinstance(seed, (list, tuple)) and len(seed) == n:
        return list(seed)
    raise ValueError(f"seed={seed!r}; allowed: None, an int, or a list of {n} ints or None")


class InsertionVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` insertion envs (``InsertionEnv``'s task, spaces and info) in one batch.

    Args:
        num_envs: Number of envs.
        socket: The socket, as ``InsertionEnv``'s (the ids' presets pass theirs).
        backend: ``"mujoco"`` (``mujoco.batch``), ``"kinematic"`` or ``"warp"``.
        num_threads: Threads of the MuJoCo batch; default: every core of the machine.
        device: Warp's device (``"cpu"``, ``"cuda:0"``), for ``backend="warp"`` only.
        autoreset_mode: ``"NextStep"`` (gymnasium's default: an env that ended is reset by
            the next ``step``, which returns its first observation, reward 0 and the reset's
            info) or ``"SameStep"`` (reset within the step that ends it; that step's last
            observation and info are in ``info["final_obs"]`` / ``info["final_info"]``) or
            ``"Disabled"`` (no autoreset: an env whose episode has ended, or that was never
            reset, is not stepped — its row repeats its last observation with reward 0 and
            no ``info`` — until ``reset(options={"reset_mask": mask})`` resets it).
        goal: The goal of every env, as ``InsertionEnv``'s.
        **task: Every other keyword of ``InsertionEnv`` (``measurement_noise``,
            ``force_noise``, ``horizon``, ``control_dt``, ``success_depth``,
            ``collision_force``, ``defect_sigma``, ``initial_pose``, ``reward_mode``,
            ``randomization``, ``defects``).

    ``info`` holds every key of the single env's, batched, with gymnasium's ``_key``
    masks. ``reset(seed=s)`` seeds env ``i`` with ``s + i``; ``reset(seed=[s0, s1, ...])``
    each with its own; options (``pose``, ``goal``) apply to every env reset by that call,
    ``options["reset_mask"]`` (a bool per env, gymnasium's) resets only those envs. A
    reset or step that raises changes nothing; after a failed reset every step raises
    ``gymnasium.error.ResetNeeded`` until a reset succeeds.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "autoreset_mode": AutoresetMode.NEXT_STEP,
        "render_modes": [],
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
        **task: Any,
    ) -> None:
        if socket is None:
            raise ValueError("socket is required; allowed: a CircularSocket or PolygonSocket")
        if render_mode is not None:
            raise ValueError(f"render_mode={render_mode!r}; allowed: None (render one env)")
        mode = getattr(autoreset_mode, "value", autoreset_mode)
        if mode not in _AUTORESET:
            raise ValueError(f"autoreset_mode={autoreset_mode!r}; allowed: {sorted(_AUTORESET)}")
        self.num_envs = check_int("num_envs", num_envs, minimum=1)
        self.settings = TaskSettings(socket, **task)
        self.backend_name = backend
        self.metadata = {**self.metadata, "autoreset_mode": _AUTORESET[mode]}
        self.render_mode = None
        self.physics = make_batch_physics(
            backend, socket, self.num_envs, self.settings.control_dt, num_threads, device
        )
        if self.settings.randomization is not None and not hasattr(self.physics, "set_physics"):
            raise ValueError(f"randomization is not supported on backend={backend!r}")
        kind = None if self.settings.defects is None else self.settings.defects[0]
        # Warp's worlds carry only bent pins; a plug changes the MuJoCo batch's layout.
        if (kind is not None and backend == "warp") or (kind == "blocked" and backend == "mujoco"):
            raise ValueError(
                f"defects={self.settings.defects!r} is not supported on backend={backend!r}; "
                "allowed: the single env, or backend='kinematic' (and 'mujoco' but for blocked)"
            )
        self.single_action_space = gym.spaces.Box(-A_MAX, A_MAX, dtype=np.float64)
        self.single_observation_space = gym.spaces.Box(-np.inf, np.inf, (8,), np.float64)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.episodes = [EpisodeState(self.settings, goal) for _ in range(self.num_envs)]
        self._rngs: list[np.random.Generator | None] = [None] * self.num_envs
        self._autoreset = np.zeros(self.num_envs, dtype=bool)

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
        seeds = _per_env_seeds(seed, self.num_envs)
        options = dict(options or {})
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
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i] = seeding.np_random(seeds[i])[0]
        try:
            plans = [self.episodes[i].plan(self._rngs[i], options) for i in ids]
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
        shape = np.shape(actions)
        if shape != (self.num_envs, 4):
            raise ValueError(
                f"actions have shape {shape}; allowed: ({self.num_envs}, 4), one "
                "[ux, uy, utheta, uz] per env"
            )
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
                    state.row(k), self._rngs[i]
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
            plans = [self.episodes[i].plan(self._rngs[i], None) for i in ids]
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
        for i, plan in zip(ids, plans, strict=True):
            self.physics.set_socket(int(i), plan.socket)
            if self.settings.randomization is not None:
                self.physics.set_physics(int(i), plan.physics)
        state = self.physics.reset(ids, np.array([plan.pose for plan in plans]))
        observations, infos = np.zeros((self.num_envs, 8)), []
        for k, (i, plan) in enumerate(zip(ids, plans, strict=True)):
            observations[i], info = self.episodes[i].begin(plan, state.row(k), self._rngs[i])
            infos.append(info)
        return observations, infos

    def close_extras(self, **kwargs: Any) -> None:
        self.physics.close()
