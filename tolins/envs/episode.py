"""The paper's task whatever the API: settings, actions, observations and scoring.

``InsertionEnv`` (gymnasium) and ``tolins.dmc.Insert`` (dm_control) both delegate here,
so the two APIs cannot drift apart.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, fields
from typing import Any

import gymnasium as gym
import numpy as np

from tolins.envs.backend import BackendState
from tolins.envs.initial_pose import InitialPoseDistribution, spread_pose
from tolins.envs.randomization import PhysicsDraw, PhysicsRandomization
from tolins.envs.reward import RewardTerms, check_reward_mode, reward_terms
from tolins.geometry.defects import check_defect_sigma, check_defects, sample_defects
from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec
from tolins.geometry.validation import (
    check_int,
    check_positive,
    check_real,
    finite_vector,
    real_array,
)
from tolins.geometry.workspace import (
    GOAL_RANGE,
    PIN_LENGTH,
    THETA_RANGE,
    XY_RANGE,
    Z_MAX,
    in_holes,
)
from tolins.mjcf.model import TIMESTEP
from tolins.paper import (
    A_MAX,
    COLLISION_REWARD,
    CONTROL_DT,
    HORIZON,
    POSE_NOISE_STD,
    SUCCESS_REWARD,
)

_A_MIN = -A_MAX
#: Longest control period (s): four times the paper's.
MAX_CONTROL_DT = 1.0
#: Shortest control period (s): two physics steps. The servos are re-anchored at the start
#: of every control step and push only from the second physics step on, so in one step the
#: workpiece cannot move. Of the commanded motion they cover 10 % at 2 ms, 55 % at 10 ms
#: and 98 % at 0.25 s (about ``1 - 4.7 ms / control_dt`` from 10 ms on;
#: benchmarks/servo_tracking.py).
MIN_PHYSICS_STEPS = 2
MIN_CONTROL_DT = MIN_PHYSICS_STEPS * TIMESTEP
#: Largest noise std of any measured quantity (mm, rad, N, N·mm): far beyond any sensor,
#: it keeps every observation finite.
MAX_NOISE_STD = 1e3


def check_control_dt(control_dt: object) -> float:
    """``control_dt`` (s) if finite, in ``[MIN_CONTROL_DT, MAX_CONTROL_DT]`` and a whole number
    of MuJoCo physics steps (:data:`~tolins.mjcf.model.TIMESTEP`); the same rule on every
    backend."""
    allowed = (
        f"a multiple of the {TIMESTEP} s physics step in [{MIN_CONTROL_DT}, {MAX_CONTROL_DT}] s "
        f"(the paper's: {CONTROL_DT}; in one physics step the servos cannot move)"
    )
    value = check_real("control_dt", control_dt, allowed)
    steps = round(value / TIMESTEP)
    if (
        not MIN_PHYSICS_STEPS <= steps <= MAX_CONTROL_DT / TIMESTEP
        or abs(steps * TIMESTEP - value) > 1e-9
    ):
        raise ValueError(f"control_dt={control_dt!r} is not allowed; allowed: {allowed}")
    return value


def _check_initial_pose(distribution: object) -> InitialPoseDistribution:
    """``distribution`` (``None``: the default one) if it is an
    :class:`InitialPoseDistribution` whose every pose around any allowed goal is in the
    servo range."""
    if distribution is None:
        return InitialPoseDistribution()
    if not isinstance(distribution, InitialPoseDistribution):
        raise ValueError(
            f"initial_pose={distribution!r} is not an InitialPoseDistribution; allowed: None "
            "or InitialPoseDistribution(radius_min=..., ...)"
        )
    limits = (
        ("radius_max", distribution.radius_max, XY_RANGE - GOAL_RANGE[0]),
        ("theta_max", distribution.theta_max, THETA_RANGE - GOAL_RANGE[2]),
        ("z_max", distribution.z_max, Z_MAX),
    )
    for name, value, limit in limits:
        if value > limit:
            raise ValueError(
                f"initial_pose.{name}={value!r} reaches beyond the servo range; allowed: "
                f"{name} ≤ {limit:.4g}"
            )
    return distribution


@dataclass(frozen=True, eq=False)
class TaskSettings:
    """Validated settings of one insertion task (see ``InsertionEnv`` for their meaning).

    Attributes:
        socket: The nominal socket.
        measurement_noise: Pose noise std ``[x, y, theta, z]`` (mm, rad); a scalar broadcasts.
        force_noise: Wrench noise std ``[Fx, Fy, q_theta, Fz]`` (N, N·mm). Each std in
            ``[0, MAX_NOISE_STD]``.
        horizon: Steps before truncation (k_max).
        success_depth: Depth of the pin tips below the board that counts as success (mm),
            less than the pins' length (the carrier stops the tips at ``z = -4``).
        collision_force: Summed normal contact force above which a step collides (N).
        defect_sigma: Bent-pin std (mm) re-drawn every episode, or ``None``; at most the
            socket's :func:`~tolins.geometry.defects.max_defect_sigma` (a workpiece with a
            pin out of its cell is re-drawn, :func:`~tolins.geometry.defects.sample_defects`).
        initial_pose: Distribution of the initial pose around the goal.
        control_dt: Control period (s), see :func:`check_control_dt`.
        reward_mode: ``sparse`` (the paper's), ``dense`` or ``normalized_dense``
            (:mod:`tolins.envs.reward`).
        randomization: Physics drawn per episode (:mod:`tolins.envs.randomization`), or
            ``None`` (the paper's fixed setting).
        defects: Another kind of defect drawn every episode, ``(kind, sigma)`` as
            :func:`~tolins.geometry.defects.sample_defects` takes them (e.g. ``("burr",
            0.05)``, ``("blocked", None)``), after any bent pins of ``defect_sigma``; or
            ``None``.
    """

    socket: SocketSpec
    measurement_noise: Any = field(default_factory=POSE_NOISE_STD.copy)
    force_noise: Any = 0.0
    horizon: int = HORIZON
    success_depth: float = 1.0
    collision_force: float = 0.5
    defect_sigma: float | None = None
    initial_pose: InitialPoseDistribution | None = None
    control_dt: float = CONTROL_DT
    reward_mode: str = "sparse"
    randomization: Any = None
    defects: Any = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if not isinstance(self.socket, (CircularSocket, PolygonSocket)):
            raise ValueError(f"socket={self.socket!r}; allowed: a CircularSocket or PolygonSocket")
        if self.defect_sigma is not None:
            if not isinstance(self.socket, CircularSocket):
                raise ValueError("defect_sigma is set but only a CircularSocket has bent pins")
            sigma = check_defect_sigma(self.socket, self.defect_sigma, "defect_sigma")
            set_(self, "defect_sigma", sigma)
        if self.defects is not None:
            set_(self, "defects", check_defects(self.socket, self.defects))
        for name, what in (
            ("measurement_noise", "[x, y, theta, z]"),
            ("force_noise", "[Fx, Fy, q_theta, Fz]"),
        ):
            allowed = f"0 ≤ std ≤ {MAX_NOISE_STD:g} for {what}"
            std = finite_vector(name, getattr(self, name), 4, allowed)
            if np.any(std < 0) or np.any(std > MAX_NOISE_STD):
                raise ValueError(f"{name}={std.tolist()!r} is out of range; allowed: {allowed}")
            set_(self, name, std)
        set_(self, "horizon", check_int("horizon", self.horizon, minimum=1))
        set_(self, "success_depth", check_positive("success_depth", self.success_depth))
        if self.success_depth >= PIN_LENGTH:
            raise ValueError(
                f"success_depth={self.success_depth!r} cannot be reached: the carrier stops the "
                f"pin tips at z = -{PIN_LENGTH:g} mm; allowed: 0 < success_depth < {PIN_LENGTH:g}"
            )
        set_(self, "collision_force", check_positive("collision_force", self.collision_force, "N"))
        set_(self, "initial_pose", _check_initial_pose(self.initial_pose))
        set_(self, "control_dt", check_control_dt(self.control_dt))
        set_(self, "reward_mode", check_reward_mode(self.reward_mode))
        set_(self, "randomization", PhysicsRandomization.of(self.randomization))
        if self.randomization is not None and self.randomization.pose_spread is not None:
            widest = spread_pose(self.initial_pose, self.randomization.pose_spread[1])
            try:
                _check_initial_pose(widest)
            except ValueError as error:
                raise ValueError(f"randomization.pose_spread: {error}") from None
        set_(self, "_noise_std", np.concatenate([self.measurement_noise, self.force_noise]))

    def draw_physics(self, rng: np.random.Generator) -> PhysicsDraw | None:
        """The episode's randomised physics (``None`` without ``randomization``)."""
        return None if self.randomization is None else self.randomization.sample(rng)

    def draw_socket(self, rng: np.random.Generator) -> SocketSpec:
        """The episode's workpiece: a fresh bent-pin copy with ``defect_sigma``, then a draw of
        ``defects``' kind, else nominal."""
        socket = self.socket
        if self.defect_sigma is not None:
            socket = sample_defects(socket, self.defect_sigma, rng)
        if self.defects is not None:
            socket = sample_defects(socket, self.defects[1], rng, kind=self.defects[0])
        return socket

    def is_success(self, state: BackendState, socket: SocketSpec | None = None) -> bool:
        """Every pin of ``socket`` (the episode's workpiece, default the nominal one) inside
        its own hole, ``success_depth`` deep (:func:`~tolins.geometry.workspace.in_holes`)."""
        return bool(in_holes(socket or self.socket, state.pose, self.success_depth))

    def observe(
        self, state: BackendState, goal: np.ndarray, rng: np.random.Generator
    ) -> np.ndarray:
        """``[x̂−x*, ŷ−y*, θ̂−θ*, ẑ, F̂x, F̂y, q̂θ, F̂z]`` with the measurement noise."""
        exact = np.concatenate([state.pose[:3] - goal, state.pose[3:], state.wrench])
        return exact + rng.normal(0.0, 1.0, 8) * self._noise_std


#: The keywords of :class:`TaskSettings` an env takes besides its socket.
TASK_KEYWORDS = tuple(f.name for f in fields(TaskSettings) if f.init and f.name != "socket")


def check_keywords(owner: str, given: dict[str, Any], allowed: Iterable[str]) -> None:
    """``ValueError`` naming the keywords of ``given`` that ``owner`` does not take, with the
    ones it takes (not their values: a socket or a distribution prints long)."""
    allowed = sorted(allowed)
    unknown = sorted(set(given) - set(allowed))
    if unknown:
        names = ", ".join(map(repr, unknown))
        plural = "s" if len(unknown) > 1 else ""
        raise ValueError(
            f"{owner} got unknown keyword{plural} {names}; allowed: {', '.join(allowed)}"
        )


def check_action(action: Any) -> np.ndarray:
    """``action`` ``[ux, uy, utheta, uz]`` as floats clipped to ±a_max; NaN, inf, a wrong
    shape or anything but real numbers (ints and floats; a bool, string or complex number is
    not a velocity) raise ``ValueError``."""
    action = real_array("action", action, "4 real numbers [ux, uy, utheta, uz]")
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
    #: The dense modes' terms (:mod:`tolins.envs.reward`); ``None`` in the sparse mode.
    terms: RewardTerms | None = None

    @property
    def reward(self) -> float:
        if self.terms is not None:
            return self.terms.total
        return self.reward_success + self.reward_collision

    def reward_info(self) -> dict[str, float]:
        """Every term of the reward as ``info`` keys ``reward_*`` (they sum to ``reward``)."""
        if self.terms is not None:
            return self.terms.to_info()
        return RewardTerms(self.reward_success, self.reward_collision).to_info()


#: The score before any step (after a reset).
NO_SCORE = StepScore(False, False, 0.0, 0.0, truncated=False)


@dataclass
class EpisodeScore:
    """Counts an episode's steps and collisions and scores each step with the paper's reward:
    ``c (1 - k / k_max)`` on the step ``k`` that succeeds, -1 on every step with a collision.

    ``over`` turns true with the step that succeeds, reaches the horizon or faults, and
    stays true until :meth:`reset`: an ended episode scores nothing more.
    """

    settings: TaskSettings
    steps: int = 0
    collisions: int = 0
    over: bool = False

    def reset(self) -> None:
        self.steps = 0
        self.collisions = 0
        self.over = False

    def check_running(self) -> None:
        """``gymnasium.error.ResetNeeded`` if the episode has ended."""
        if self.over:
            raise gym.error.ResetNeeded(
                "the episode has ended (success, horizon or simulator fault); call reset() "
                "before stepping again"
            )

    def score(self, state: BackendState, socket: SocketSpec | None = None) -> StepScore:
        """Score the step that produced ``state`` (a valid state, not a fault); ``socket``:
        the episode's workpiece (default the nominal one)."""
        self.check_running()
        self.steps += 1
        collision = state.peak_force > self.settings.collision_force
        self.collisions += int(collision)
        success = self.settings.is_success(state, socket)
        reward_success = (
            SUCCESS_REWARD * (1 - self.steps / self.settings.horizon) if success else 0.0
        )
        reward_collision = COLLISION_REWARD if collision else 0.0
        terms = None
        if self.settings.reward_mode != "sparse":
            terms = reward_terms(
                self.settings.reward_mode,
                reward_success,
                reward_collision,
                socket or self.settings.socket,
                state.pose,
                self.settings.success_depth,
            )
        truncated = not success and self.steps >= self.settings.horizon
        self.over = success or truncated
        return StepScore(
            success=success,
            collision=collision,
            reward_success=reward_success,
            reward_collision=reward_collision,
            truncated=truncated,
            terms=terms,
        )

    def fault(self) -> StepScore:
        """Count a step that ended in a simulator fault: no reward, the episode is over."""
        self.check_running()
        self.steps += 1
        self.over = True
        return StepScore(False, False, 0.0, 0.0, truncated=True)
