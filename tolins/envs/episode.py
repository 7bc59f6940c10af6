"""The paper's task whatever the API: settings, actions, observations and scoring.

``InsertionEnv`` (gymnasium) and ``tolins.dmc.Insert`` (dm_control) both delegate here,
so the two APIs cannot drift apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tolins.envs.backend import BackendState
from tolins.envs.initial_pose import InitialPoseDistribution
from tolins.geometry.defects import sample_defects
from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec
from tolins.geometry.validation import check_int, check_positive, finite_vector
from tolins.paper import A_MAX, COLLISION_REWARD, HORIZON, POSE_NOISE_STD, SUCCESS_REWARD

_A_MIN = -A_MAX


@dataclass(frozen=True, eq=False)
class TaskSettings:
    """Validated settings of one insertion task (see ``InsertionEnv`` for their meaning).

    Attributes:
        socket: The nominal socket.
        measurement_noise: Pose noise std ``[x, y, theta, z]`` (mm, rad); a scalar broadcasts.
        force_noise: Wrench noise std ``[Fx, Fy, q_theta, Fz]`` (N, N·mm).
        horizon: Steps before truncation (k_max).
        success_depth: Depth of the pin tips below the board that counts as success (mm).
        collision_force: Summed normal contact force above which a step collides (N).
        defect_sigma: Bent-pin std (mm) re-drawn every episode, or ``None``.
        initial_pose: Distribution of the initial pose around the goal.
    """

    socket: SocketSpec
    measurement_noise: Any = field(default_factory=POSE_NOISE_STD.copy)
    force_noise: Any = 0.0
    horizon: int = HORIZON
    success_depth: float = 1.0
    collision_force: float = 0.5
    defect_sigma: float | None = None
    initial_pose: InitialPoseDistribution | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if not isinstance(self.socket, (CircularSocket, PolygonSocket)):
            raise ValueError(f"socket={self.socket!r}; allowed: a CircularSocket or PolygonSocket")
        if self.defect_sigma is not None:
            if not isinstance(self.socket, CircularSocket):
                raise ValueError("defect_sigma is set but only a CircularSocket has bent pins")
            set_(self, "defect_sigma", check_positive("defect_sigma", self.defect_sigma))
        for name, what in (
            ("measurement_noise", "[x, y, theta, z]"),
            ("force_noise", "[Fx, Fy, q_theta, Fz]"),
        ):
            std = finite_vector(name, getattr(self, name), 4, f"std ≥ 0 for {what}")
            if np.any(std < 0):
                raise ValueError(f"{name}={std.tolist()!r} is negative; allowed: std ≥ 0")
            set_(self, name, std)
        set_(self, "horizon", check_int("horizon", self.horizon, minimum=1))
        set_(self, "success_depth", check_positive("success_depth", self.success_depth))
        set_(self, "collision_force", check_positive("collision_force", self.collision_force, "N"))
        set_(self, "initial_pose", self.initial_pose or InitialPoseDistribution())
        set_(self, "_noise_std", np.concatenate([self.measurement_noise, self.force_noise]))

    def draw_socket(self, rng: np.random.Generator) -> SocketSpec:
        """The episode's workpiece: a fresh bent-pin copy with ``defect_sigma``, else nominal."""
        if self.defect_sigma is None:
            return self.socket
        return sample_defects(self.socket, self.defect_sigma, rng)

    def is_success(self, state: BackendState) -> bool:
        return bool(state.pose[3] <= -self.success_depth)

    def observe(
        self, state: BackendState, goal: np.ndarray, rng: np.random.Generator
    ) -> np.ndarray:
        """``[x̂−x*, ŷ−y*, θ̂−θ*, ẑ, F̂x, F̂y, q̂θ, F̂z]`` with the measurement noise."""
        exact = np.concatenate([state.pose[:3] - goal, state.pose[3:], state.wrench])
        return exact + rng.normal(0.0, 1.0, 8) * self._noise_std


def check_action(action: Any) -> np.ndarray:
    """``action`` ``[ux, uy, utheta, uz]`` as floats clipped to ±a_max; NaN, inf or a wrong
    shape raise ``ValueError``."""
    try:
        action = np.asarray(action, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f"action={action!r} is not numeric; allowed: 4 floats") from error
    if action.shape != (4,):
        raise ValueError(f"action has shape {action.shape}; allowed: (4,) = [ux, uy, utheta, uz]")
    if not np.isfinite(action).all():
        raise ValueError(f"action={action.tolist()!r} contains NaN or inf; allowed: finite values")
    return np.minimum(np.maximum(action, _A_MIN), A_MAX)


@dataclass(frozen=True)
class StepScore:
    """How one control step scored."""

    success: bool
    collision: bool
    reward_success: float
    reward_collision: float
    truncated: bool

    @property
    def reward(self) -> float:
        return self.reward_success + self.reward_collision


#: The score before any step (after a reset).
NO_SCORE = StepScore(False, False, 0.0, 0.0, truncated=False)


@dataclass
class EpisodeScore:
    """Counts an episode's steps and collisions and scores each step with the paper's reward:
    ``c (1 - k / k_max)`` on the step ``k`` that succeeds, -1 on every step with a collision."""

    settings: TaskSettings
    steps: int = 0
    collisions: int = 0

    def reset(self) -> None:
        self.steps = 0
        self.collisions = 0

    def score(self, state: BackendState) -> StepScore:
        """Score the step that produced ``state`` (a valid state, not a fault)."""
        self.steps += 1
        collision = state.peak_force > self.settings.collision_force
        self.collisions += int(collision)
        success = self.settings.is_success(state)
        return StepScore(
            success=success,
            collision=collision,
            reward_success=SUCCESS_REWARD * (1 - self.steps / self.settings.horizon)
            if success
            else 0.0,
            reward_collision=COLLISION_REWARD if collision else 0.0,
            truncated=not success and self.steps >= self.settings.horizon,
        )

    def fault(self) -> StepScore:
        """Count a step that ended in a simulator fault: no reward, the episode is over."""
        self.steps += 1
        return StepScore(False, False, 0.0, 0.0, truncated=True)
