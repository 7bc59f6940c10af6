"""``Insert``: the paper's insertion task as a dm_control ``Task``."""

from __future__ import annotations

import collections
from typing import Any

import numpy as np
from dm_control.rl import control
from dm_env import specs

from tolins.dmc.physics import InsertionPhysics
from tolins.envs.backend import BackendState
from tolins.envs.initial_pose import InitialPoseDistribution
from tolins.envs.insertion_env import _finite_vector
from tolins.geometry.defects import sample_defects
from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec
from tolins.geometry.validation import check_int, check_positive
from tolins.paper import A_MAX, COLLISION_REWARD, HORIZON, POSE_NOISE_STD, SUCCESS_REWARD

#: Observation names and sizes, in the order of the gym env's 8-vector.
OBSERVATIONS = (("pose_error", 3), ("height", 1), ("wrench", 4))
ACTION_NAMES = ("ux", "uy", "utheta", "uz")
Observation = collections.OrderedDict[str, np.ndarray]
ObservationSpec = collections.OrderedDict[str, specs.Array]


def _generator(random: Any) -> np.random.Generator:
    """A ``Generator`` from a seed, ``None``, a ``Generator`` or a legacy ``RandomState``."""
    if isinstance(random, np.random.RandomState):
        return np.random.default_rng(random.randint(0, 2**31, size=4))
    try:
        return np.random.default_rng(random)
    except (TypeError, ValueError) as error:
        raise ValueError(
            f"random={random!r}; allowed: an int seed, None, a numpy Generator or RandomState"
        ) from error


class Insert(control.Task):
    """Insert a workpiece's pins into a socket's holes: the gym env's task for dm_control.

    **Observation** (ordered dict of float64 arrays, the gym env's 8-vector split up):
    ``pose_error`` ``[x̂−x*, ŷ−y*, θ̂−θ*]`` (mm, rad), ``height`` ``[ẑ]`` (mm, pin tips
    over the board), ``wrench`` ``[F̂x, F̂y, q̂θ, F̂z]`` (N, N·mm) of the board on the
    workpiece. Pose noise std ``measurement_noise`` (``[x, y, theta, z]``, default the
    paper's ``[0.1, 0.1, 0, 0.1]``), wrench noise ``force_noise`` (default 0).

    **Action** ``[ux, uy, utheta, uz]`` in mm/s and rad/s within ``±a_max``
    ``[2.5, 2.5, 0.1, 2.5]``; larger values are clipped, NaN or inf raises ``ValueError``.

    **Reward** ``c (1 - k / k_max)`` (c = 100, k_max = ``horizon``) on the step ``k``
    that succeeds (pin tips ``success_depth`` below the surface), plus -1 on every step
    whose peak summed normal contact force exceeded ``collision_force``.

    **Episode end**: success (discount 0); ``horizon`` steps (discount 1; the task ends
    the episode itself, so a success on the last step still has discount 0); a
    simulator fault (discount 1, the previous observation, ``error`` set).

    **Randomisation** (``random``: seed, ``Generator`` or ``RandomState``; an int seed
    draws what ``InsertionEnv.reset(seed=...)`` draws): the initial pose from
    ``initial_pose`` around the goal, or the fixed ``pose`` ``[x, y, theta, z]``; with
    ``defect_sigma``, a new bent-pin workpiece every episode, for which the physics is
    rebuilt from its MJCF (``InsertionPhysics.reload_from_spec``, about 5 ms).
    """

    def __init__(
        self,
        socket: SocketSpec,
        *,
        defect_sigma: float | None = None,
        measurement_noise: Any = POSE_NOISE_STD,
        force_noise: Any = 0.0,
        goal: Any = (0.0, 0.0, 0.0),
        pose: Any = None,
        initial_pose: InitialPoseDistribution | None = None,
        horizon: int = HORIZON,
        success_depth: float = 1.0,
        collision_force: float = 0.5,
        random: Any = None,
    ) -> None:
        if not isinstance(socket, (CircularSocket, PolygonSocket)):
            raise ValueError(f"socket={socket!r}; allowed: a CircularSocket or PolygonSocket")
        if defect_sigma is not None:
            if not isinstance(socket, CircularSocket):
                raise ValueError("defect_sigma is set but only a CircularSocket has bent pins")
            defect_sigma = check_positive("defect_sigma", defect_sigma)
        noise = {
            "measurement_noise": _finite_vector(
                "measurement_noise", measurement_noise, 4, "std ≥ 0 for [x, y, theta, z]"
            ),
            "force_noise": _finite_vector(
                "force_noise", force_noise, 4, "std ≥ 0 for [Fx, Fy, q_theta, Fz]"
            ),
        }
        for name, std in noise.items():
            if np.any(std < 0):
                raise ValueError(f"{name}={std.tolist()!r} is negative; allowed: std ≥ 0")
        self.nominal_socket = self.socket = socket
        self.defect_sigma = defect_sigma
        self.noise_std = np.concatenate(list(noise.values()))
        self.goal = _finite_vector("goal", goal, 3, "[x*, y*, theta*] in mm and rad")
        self.pose = None if pose is None else _finite_vector("pose", pose, 4, "[x, y, θ, z]")
        self.initial_pose = initial_pose or InitialPoseDistribution()
        self.horizon = check_int("horizon", horizon, minimum=1)
        self.success_depth = check_positive("success_depth", success_depth)
        self.collision_force = check_positive("collision_force", collision_force, unit="N")
        self.random = _generator(random)
        self._observation = np.zeros(8)
        self._begin_episode()

    def _begin_episode(self) -> None:
        self.step_count = 0
        self.n_collisions = 0
        self.collision = False
        self.success = False
        self.error: str | None = None
        self.reward_terms = (0.0, 0.0)

    def initialize_episode(self, physics: InsertionPhysics) -> None:
        """Draw the workpiece (defective domain) and the initial pose; place the workpiece."""
        if self.defect_sigma is not None:
            self.socket = sample_defects(self.nominal_socket, self.defect_sigma, self.random)
            physics.reload_from_spec(self.socket)
        if self.pose is not None:
            pose = self.pose
        else:
            pose = self.initial_pose.sample(self.random, self.goal)
        self._begin_episode()
        self._observation = self._observe(physics.set_pose(pose))

    def before_step(self, action: Any, physics: InsertionPhysics) -> None:
        """Check and clip ``action`` and command it."""
        try:
            action = np.asarray(action, dtype=float)
        except (TypeError, ValueError) as error:
            raise ValueError(f"action={action!r} is not numeric; allowed: 4 floats") from error
        if action.shape != (4,) or not np.isfinite(action).all():
            raise ValueError(
                f"action={action.tolist()!r}; allowed: 4 finite floats [ux, uy, utheta, uz]"
            )
        physics.command(np.minimum(np.maximum(action, -A_MAX), A_MAX))

    def after_step(self, physics: InsertionPhysics) -> None:
        """Score the control step that ``physics.step`` just ran."""
        state: BackendState = physics.last_state
        self.step_count += 1
        if state.error is not None:
            self.error = state.error
            self.collision = self.success = False
            self.reward_terms = (0.0, 0.0)
            return
        self.collision = state.peak_force > self.collision_force
        self.n_collisions += int(self.collision)
        self.success = bool(state.pose[3] <= -self.success_depth)
        k = self.step_count
        self.reward_terms = (
            SUCCESS_REWARD * (1 - k / self.horizon) if self.success else 0.0,
            COLLISION_REWARD if self.collision else 0.0,
        )
        self._observation = self._observe(state)

    def _observe(self, state: BackendState) -> np.ndarray:
        exact = np.concatenate([state.pose[:3] - self.goal, state.pose[3:], state.wrench])
        return exact + self.random.normal(0.0, 1.0, 8) * self.noise_std

    def get_observation(self, physics: InsertionPhysics) -> Observation:
        """The last observation, split into ``pose_error``, ``height`` and ``wrench``."""
        parts = np.split(self._observation, np.cumsum([n for _, n in OBSERVATIONS])[:-1])
        return collections.OrderedDict(
            (name, part.copy()) for (name, _), part in zip(OBSERVATIONS, parts, strict=True)
        )

    def get_reward(self, physics: InsertionPhysics) -> float:
        return self.reward_terms[0] + self.reward_terms[1]

    def get_termination(self, physics: InsertionPhysics) -> float | None:
        if self.success:
            return 0.0
        if self.error is not None or self.step_count >= self.horizon:
            return 1.0
        return None

    def action_spec(self, physics: InsertionPhysics) -> specs.BoundedArray:
        return specs.BoundedArray((4,), np.float64, -A_MAX, A_MAX, name="\t".join(ACTION_NAMES))

    def observation_spec(self, physics: InsertionPhysics) -> ObservationSpec:
        return collections.OrderedDict(
            (name, specs.Array((size,), np.float64, name=name)) for name, size in OBSERVATIONS
        )
