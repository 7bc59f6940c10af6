"""The settings of one insertion task, validated once, and the per-episode draws they define.

:class:`TaskSettings` holds what every API of the task shares (noise, horizon, success and
collision thresholds, control period, reward mode, defect and physics randomisation, the
physics version and the robot) and draws an episode's workpiece and physics, judges success
and measures an observation. It is the one place a setting is written: its field (default
and docstring) and its check in ``__post_init__``. The gym env, the vector env and the
dm_control task take every setting as a keyword they hand on to :meth:`TaskSettings.build`
unread, and give the settings to their :class:`~tolins.envs.episode_state.EpisodeState`;
their simulators get the :class:`~tolins.physics.versions.PhysicsVersion` resolved here.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from tolins.envs.initial_pose import InitialPoseDistribution, check_initial_pose, spread_pose
from tolins.envs.reward import check_reward_mode
from tolins.geometry.defects import check_defect_sigma, check_defects, sample_defects
from tolins.geometry.delicate import ElasticPins, check_pins
from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec
from tolins.geometry.validation import check_int, check_positive, checked_array, finite_vector
from tolins.geometry.workspace import PIN_LENGTH, in_holes
from tolins.paper import CONTROL_DT, HORIZON, POSE_NOISE_STD
from tolins.physics.panda import check_gain_range
from tolins.physics.protocol import BackendState
from tolins.physics.randomization import PhysicsDraw, PhysicsRandomization
from tolins.physics.registry import (
    check_elastic_pins,
    check_robot,
    simulator,
    simulator_place,
    taking_defect,
)
from tolins.physics.schedule import check_control_dt
from tolins.physics.versions import PhysicsVersion, check_version_robot, physics_version

#: Largest std of the grasp error ``[x, y, yaw]`` (mm, mm, rad): beyond it the part could
#: leave the fingers' pads.
MAX_GRASP_ERROR_STD = np.array([1.0, 1.0, 0.1])
#: Largest noise std of any measured quantity (mm, rad, N, N·mm): far beyond any sensor,
#: it keeps every observation finite.
MAX_NOISE_STD = 1e3


@dataclass(frozen=True, eq=False)
class TaskSettings:
    """Validated settings of one insertion task: every keyword of the gym env, the vector env
    and the dm_control task besides the env's own (``backend``, ``goal``, ``render_mode``, …).

    Build one from an env's keywords with :meth:`build`. A new setting is a field here, with
    its default and a line below, and its check in ``__post_init__``; every API takes it.

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
        control_dt: Control period (s), see :func:`~tolins.physics.schedule.check_control_dt`.
        reward_mode: ``sparse`` (the paper's), ``dense`` or ``normalized_dense``
            (:mod:`tolins.envs.reward`).
        randomization: Physics drawn per episode (:mod:`tolins.physics.randomization`), or
            ``None`` (the paper's fixed setting).
        defects: Another kind of defect drawn every episode, ``(kind, sigma)`` as
            :func:`~tolins.geometry.defects.sample_defects` takes them (e.g. ``("burr",
            0.05)``, ``("blocked", None)``), after any bent pins of ``defect_sigma``; or
            ``None``.
        physics_version: The MuJoCo physics, 1 or 2, or 3 with ``robot="panda"``
            (:mod:`tolins.physics.versions`; the ``-v1``, ``-v2`` and ``-v3`` ids); a
            :class:`~tolins.physics.versions.PhysicsVersion` is taken too. Kept as its number.
        robot: What holds the workpiece (:data:`~tolins.physics.registry.ROBOTS`):
            ``"free"``, the paper's ideal servos on a free-floating body, or ``"panda"``, a
            Franka Panda (:mod:`tolins.physics.panda`).
        grasp_error: Std ``[x, y, yaw]`` (mm, mm, rad, the hand's frame: x along the
            finger pads, y across them) of where the part is put in the hand, drawn every
            episode from independent normals clipped at 3 std (after the physics, before
            the pose; the draw in the reset's ``info["grasp_error"]``), or ``None`` (the
            part where the robot believes it). The closing fingers centre the part across
            the pads and square it to them, pushing a part off across them along the
            pads (up to about 3.4 times the std across, docs/robot.md), so what stays is
            an offset along the pads that is not the draw's: the part's true offset is
            ``info["pose"] - info["sensed_pose"]``. A robot's only; three stds (a single
            number is refused), each at most :data:`MAX_GRASP_ERROR_STD`.
        pins: ``"rigid"`` (the default, the paper's) or ``"elastic-plastic"``: round pins
            that bend under load and stay bent beyond their yield moment (docs/delicate.md;
            MuJoCo's single env and dm_control; :mod:`tolins.physics.plasticity`).
        pin_material: With elastic-plastic pins, their material: a preset name
            (``"phosphor_bronze"``, the default, ``"brass"``, ``"alloy42"``) or a mapping
            ``{"youngs_modulus": GPa, "yield_strength": MPa[, "density": g/cm³]}``
            (:func:`~tolins.geometry.materials.pin_material`); kept resolved.
        damage_threshold: With elastic-plastic pins, the permanent tip offset (mm) from which
            a pin counts as damaged (``info["damaged"]``), in ``(0, clearance]``; default half
            the socket's radial clearance.
        damage_penalty: With elastic-plastic pins, the penalty of the ``delicate`` reward: the
            step on which a pin becomes damaged gets ``-damage_penalty`` (``info
            ["reward_damage"]``) and ends the episode (terminated); ``None`` (the default):
            damage is reported, not rewarded, and the episode goes on.
        version: Not a keyword: the :class:`~tolins.physics.versions.PhysicsVersion` of
            ``physics_version``, looked up once here; what the envs hand their simulators.
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
    physics_version: int = 1
    robot: str = "free"
    grasp_error: Any = None
    pins: str = "rigid"
    pin_material: Any = None
    damage_threshold: float | None = None
    damage_penalty: float | None = None
    version: PhysicsVersion = field(init=False, repr=False)
    elastic: ElasticPins | None = field(init=False, repr=False)

    @classmethod
    def build(
        cls, owner: Callable[..., Any], socket: SocketSpec, keywords: dict[str, Any]
    ) -> TaskSettings:
        """The settings of ``socket`` and ``keywords``, the keywords that ``owner`` (an env
        class) took besides its own parameters; ``ValueError`` naming any that is neither a
        setting nor ``owner``'s parameter, with the allowed ones (:func:`keywords_of`)."""
        check_keywords(owner.__name__, keywords, keywords_of(owner))
        return cls(socket, **keywords)

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
        set_(self, "initial_pose", check_initial_pose(self.initial_pose))
        set_(self, "control_dt", check_control_dt(self.control_dt))
        set_(self, "reward_mode", check_reward_mode(self.reward_mode))
        set_(self, "randomization", PhysicsRandomization.of(self.randomization))
        set_(self, "version", physics_version(self.physics_version))
        set_(self, "physics_version", self.version.number)
        set_(self, "robot", check_robot(self.robot))
        check_version_robot(self.version, self.robot)
        if self.robot == "panda" and self.randomization is not None:
            check_gain_range(self.version, self.randomization.servo_gain)
        set_(self, "grasp_error", check_grasp_error(self.grasp_error, self.robot))
        elastic = check_pins(
            self.socket, self.pins, self.pin_material, self.damage_threshold, self.damage_penalty
        )
        set_(self, "elastic", elastic)
        if elastic is not None:
            set_(self, "pin_material", elastic.material)
            set_(self, "damage_threshold", elastic.damage_threshold)
            set_(self, "damage_penalty", elastic.damage_penalty)
        if self.randomization is not None and self.randomization.pose_spread is not None:
            widest = spread_pose(self.initial_pose, self.randomization.pose_spread[1])
            try:
                check_initial_pose(widest)
            except ValueError as error:
                raise ValueError(f"randomization.pose_spread: {error}") from None
        set_(self, "_noise_std", np.concatenate([self.measurement_noise, self.force_noise]))

    def draw_socket(self, rng: np.random.Generator) -> SocketSpec:
        """The episode's workpiece: a fresh bent-pin copy with ``defect_sigma``, then a draw of
        ``defects``' kind, else nominal."""
        socket = self.socket
        if self.defect_sigma is not None:
            socket = sample_defects(socket, self.defect_sigma, rng)
        if self.defects is not None:
            socket = sample_defects(socket, self.defects[1], rng, kind=self.defects[0])
        return socket

    def draw_physics(self, rng: np.random.Generator) -> PhysicsDraw | None:
        """The episode's randomised physics (``None`` without ``randomization``)."""
        return None if self.randomization is None else self.randomization.sample(rng)

    def draw_grasp(self, rng: np.random.Generator) -> np.ndarray | None:
        """The episode's grasp error ``[dx, dy, dyaw]`` (``None`` without ``grasp_error``)."""
        if self.grasp_error is None:
            return None
        return np.clip(rng.normal(0.0, 1.0, 3), -3.0, 3.0) * self.grasp_error

    def pose_distribution(self, physics: PhysicsDraw | None) -> InitialPoseDistribution:
        """The initial-pose distribution of an episode whose physics draw is ``physics``
        (its pose spread widens or narrows :attr:`initial_pose`)."""
        if physics is None or physics.pose_spread is None:
            return self.initial_pose
        return spread_pose(self.initial_pose, physics.pose_spread)

    def is_success(self, state: BackendState, socket: SocketSpec | None = None) -> bool:
        """Every pin of ``socket`` (the episode's workpiece, default the nominal one) inside
        its own hole, ``success_depth`` deep (:func:`~tolins.geometry.workspace.in_holes`)."""
        return bool(in_holes(socket or self.socket, state.pose, self.success_depth))

    def observe(
        self, state: BackendState, goal: np.ndarray, rng: np.random.Generator
    ) -> np.ndarray:
        """``[x̂−x*, ŷ−y*, θ̂−θ*, ẑ, F̂x, F̂y, q̂θ, F̂z]`` with the measurement noise."""
        pose = state.observed_pose
        exact = np.concatenate([pose[:3] - goal, pose[3:], state.observed_wrench])
        return exact + rng.normal(0.0, 1.0, 8) * self._noise_std


def check_grasp_error(grasp_error: Any, robot: str) -> np.ndarray | None:
    """``grasp_error`` as a ``[x, y, yaw]`` std array, or ``None``; ``ValueError`` unless it
    is three stds (a scalar is refused: mm and rad do not share one number), each in
    ``[0, MAX_GRASP_ERROR_STD]``, and a robot holds the part."""
    if grasp_error is None:
        return None
    if robot == "free":
        raise ValueError("grasp_error needs a robot holding the part; allowed: robot='panda'")
    high = MAX_GRASP_ERROR_STD.tolist()
    allowed = f"three stds [x, y, yaw] (mm, mm, rad), each 0 ≤ std ≤ {high}"
    std = checked_array("grasp_error", grasp_error, (3,), allowed)
    if np.any(std < 0) or np.any(std > MAX_GRASP_ERROR_STD):
        raise ValueError(f"grasp_error={std.tolist()!r} is out of range; allowed: {allowed}")
    return std


def check_capabilities(settings: TaskSettings, backend: str, *, single: bool = False) -> None:
    """``ValueError`` if the simulator of ``backend`` (the single env's with ``single``, else
    the vector env's batch) with ``settings.robot`` cannot simulate ``settings``' randomised
    physics or defect kind."""
    chosen = simulator(backend, single=single, robot=settings.robot)
    cls = chosen.single if single else chosen.batch
    on = simulator_place(backend, settings.robot)
    if settings.elastic is not None:
        check_elastic_pins(cls, simulator_place(backend, settings.robot, vector=not single))
    if settings.randomization is not None and not cls.supports_randomization:
        raise ValueError(f"randomization is not supported on {on}")
    kind = None if settings.defects is None else settings.defects[0]
    if kind is not None and kind not in cls.defect_kinds:
        if settings.robot != "free":
            allowed = ", ".join(map(repr, sorted(cls.defect_kinds)))
            raise ValueError(
                f"defects={settings.defects!r} is not supported on {on}; allowed: {allowed}"
            )
        supported = taking_defect(kind)
        raise ValueError(
            f"defects={settings.defects!r} is not supported on {on}; allowed: "
            f"the single env, or backend {', '.join(map(repr, supported))}"
        )


#: The keywords of :class:`TaskSettings` an env takes besides its socket.
TASK_KEYWORDS = tuple(f.name for f in fields(TaskSettings) if f.init and f.name != "socket")


def keywords_of(owner: Callable[..., Any]) -> tuple[str, ...]:
    """Every keyword ``owner`` (an env class, or a function) takes: its named parameters
    (not ``self``, ``*args`` or ``**kwargs``), then the settings' :data:`TASK_KEYWORDS`
    (which its ``**kwargs`` hands to :meth:`TaskSettings.build`)."""
    variadic = (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    parameters = inspect.signature(owner).parameters.values()
    own = tuple(p.name for p in parameters if p.kind not in variadic and p.name != "self")
    return (*own, *(name for name in TASK_KEYWORDS if name not in own))


def setting(name: str) -> property:
    """A read-only attribute: ``TaskSettings.<name>`` of its owner's ``settings``."""
    return property(lambda self: getattr(self.settings, name), doc=f"See ``TaskSettings.{name}``.")


def _with_every_setting(cls: type) -> type:
    """``cls`` with a read-only attribute per keyword of :data:`TASK_KEYWORDS`."""
    for name in TASK_KEYWORDS:
        setattr(cls, name, setting(name))
    return cls


@_with_every_setting
class SettingsAttributes:
    """The task's settings as read-only attributes of an owner that has ``settings`` (a
    :class:`TaskSettings`): what the gym env and each env of the vector env answer alike,
    one per keyword of :data:`TASK_KEYWORDS` (``horizon``, ``physics_version``, …), each
    ``TaskSettings``' attribute of that name. ``nominal_socket`` is the settings' socket,
    before any episode's defects."""

    nominal_socket = setting("socket")


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
