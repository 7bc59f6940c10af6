"""``Insert``: the paper's insertion task as a dm_control ``Task``."""

from __future__ import annotations

import collections
from typing import Any

import numpy as np
from dm_control.rl import control
from dm_env import specs

from tolins.dmc.physics import InsertionPhysics
from tolins.envs.actions import check_action
from tolins.envs.episode_state import EpisodeState, check_fixed_pose
from tolins.envs.scoring import NO_SCORE, EpisodeScore
from tolins.envs.task_settings import TaskSettings
from tolins.geometry.specs import SocketSpec
from tolins.paper import A_MAX
from tolins.physics.randomization import PhysicsDraw

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

    ``Insert(socket, *, goal=(0, 0, 0), pose=None, random=None, **settings)``: ``socket``
    and ``goal`` as the gym env's, ``pose`` a fixed initial pose ``[x, y, theta, z]`` (or
    ``None``: drawn each episode), ``random`` the episodes' randomness (below). Every other
    keyword is a setting of the task, an attribute of
    :class:`~tolins.envs.task_settings.TaskSettings` (its docstring gives each one's meaning
    and default), the same as the gym env's; any other keyword raises ``ValueError``
    naming it and the allowed ones.

    **Observation** (ordered dict of float64 arrays, the gym env's 8-vector split up):
    ``pose_error`` ``[x̂−x*, ŷ−y*, θ̂−θ*]`` (mm, rad), ``height`` ``[ẑ]`` (mm, pin tips
    over the board), ``wrench`` ``[F̂x, F̂y, q̂θ, F̂z]`` (N, N·mm) of the board on the
    workpiece. Pose noise std ``measurement_noise`` (``[x, y, theta, z]``, default the
    paper's ``[0.1, 0.1, 0, 0.1]``), wrench noise ``force_noise`` (default 0).

    **Action** ``[ux, uy, utheta, uz]`` in mm/s and rad/s within ``±a_max``
    ``[2.5, 2.5, 0.1, 2.5]``; larger values are clipped, NaN or inf raises ``ValueError``.

    **Reward** ``c (1 - k / k_max)`` (c = 100, k_max = ``horizon``) on the step ``k``
    that succeeds (every pin ``success_depth`` deep in its own hole, the gym env's success),
    plus -1 on every step
    whose peak summed normal contact force exceeded ``collision_force``. That is
    ``reward_mode="sparse"`` (the default); ``"dense"`` and ``"normalized_dense"`` are the
    gym env's (``InsertionEnv``, :mod:`tolins.envs.reward`); ``last_score.reward_info()``
    has the step's terms.

    **Episode end**: success (discount 0); ``horizon`` steps (discount 1; the task ends
    the episode itself, so a success on the last step still has discount 0); a
    simulator fault (discount 1, the previous observation, ``error`` set).

    **Randomisation** (``random``: seed, ``Generator`` or ``RandomState``; an int seed
    draws what ``InsertionEnv.reset(seed=...)`` draws): the initial pose from
    ``initial_pose`` around the goal, or the fixed ``pose`` ``[x, y, theta, z]``; with
    ``defect_sigma``, a new bent-pin workpiece every episode, for which the physics is
    rebuilt from its MJCF (``InsertionPhysics.reload_from_spec``, about 5 ms). A fixed
    ``pose`` below the board's top (pins in their holes) is for a nominal workpiece only:
    with ``defect_sigma`` it is refused, as a bent workpiece may not fit there.
    ``randomization`` draws the episode's physics as the gym env's does (after the
    workpiece, before the pose; :mod:`tolins.physics.randomization`), applied to the physics'
    model; the draw is :attr:`physics_draw`. ``defects=(kind, sigma)`` draws another kind
    of defect every episode, as the gym env's ``defects`` (after any bend;
    :func:`~tolins.geometry.defects.sample_defects`: ``pitch``, ``burr``, ``short``,
    ``blocked`` with sigma ``None``; a circular socket only), the physics rebuilt from the
    drawn workpiece; a fixed ``pose`` in the holes is refused with it as with ``defect_sigma``.

    **Failed reset**: a reset validates the episode (workpiece, pose) before it changes
    anything; if it raises (e.g. a ``pose`` set on the task since that is out of range),
    the task, its random state and the physics stay as they were, and every step raises
    ``gymnasium.error.ResetNeeded`` until a reset succeeds.

    **The rules are the gym env's**: :attr:`settings` is a
    :class:`~tolins.envs.task_settings.TaskSettings` and :attr:`episode` an
    :class:`~tolins.envs.episode_state.EpisodeState`, what ``InsertionEnv`` and every env
    of the vector env hold; the task plans, starts and scores its episodes through them
    and turns the outcome into dm_control's observation, reward and discount.
    ``control_dt`` is the environment's ``control_timestep`` (s), validated by the settings
    (:func:`tolins.dmc.make_environment` passes it). ``physics_version`` (1, the default,
    or 2: :mod:`tolins.physics.versions`) is the gym ids' ``-v1`` or ``-v2``; the suite
    builds its physics in that version. ``robot`` and ``grasp_error`` are the gym env's
    (``"panda"``: a Franka Panda holds the part,
    :class:`~tolins.dmc.physics.PandaInsertionPhysics`).
    """

    def __init__(
        self,
        socket: SocketSpec,
        *,
        goal: Any = (0.0, 0.0, 0.0),
        pose: Any = None,
        random: Any = None,
        **settings: Any,
    ) -> None:
        self.settings = TaskSettings.build(Insert, socket, settings)
        self.episode = EpisodeState(self.settings, goal)
        self.pose = check_fixed_pose(self.settings, pose)
        self.random = _generator(random)
        self.last_score = NO_SCORE
        self.error: str | None = None
        super().__init__()

    @property
    def socket(self) -> SocketSpec:
        """The workpiece of the current episode (a defective draw in a defective domain)."""
        return self.episode.socket

    @property
    def goal(self) -> np.ndarray:
        """The goal ``[x*, y*, theta*]`` (mm, rad) ``pose_error`` is measured from; setting it
        moves the running episode's goal and every later one's."""
        return self.episode.goal

    @goal.setter
    def goal(self, value: Any) -> None:
        self.episode.goal = value

    @property
    def score(self) -> EpisodeScore:
        """The running episode's step and collision counts."""
        return self.episode.score

    @property
    def physics_draw(self) -> PhysicsDraw | None:
        """The episode's randomised physics (``None`` without ``randomization``)."""
        return self.episode.physics

    def initialize_episode(self, physics: InsertionPhysics) -> None:
        """Plan the episode (draw the workpiece, the physics and the initial pose, and check
        them), then rebuild or adjust the physics and place the workpiece; a failed plan
        changes nothing, the random state included (see **Failed reset**)."""
        if physics.version.number != self.settings.physics_version:
            raise ValueError(
                f"the physics is version {physics.version.number} but the task's "
                f"physics_version={self.settings.physics_version}; allowed: "
                "InsertionPhysics.from_spec(socket, physics_version) of the task's version"
            )
        if physics.robot != self.settings.robot:
            raise ValueError(
                f"the physics' robot is {physics.robot!r} but the task's "
                f"robot={self.settings.robot!r}; allowed: InsertionPhysics.from_spec(socket, "
                "physics_version, robot) of the task's robot"
            )
        random_state = self.random.bit_generator.state
        try:
            plan = self.episode.plan(self.random, pose=self.pose)
        except BaseException:
            self.random.bit_generator.state = random_state
            raise
        if plan.socket is not self.socket:
            physics.reload_from_spec(plan.socket)
        plan.apply_physics(physics.set_physics)
        plan.apply_grasp(physics.set_grasp)
        self.last_score, self.error = NO_SCORE, None
        self.episode.start(plan, physics.set_pose(plan.pose), self.random)

    def before_step(self, action: Any, physics: InsertionPhysics) -> None:
        """Check and clip ``action`` and command it; ``gymnasium.error.ResetNeeded`` after a
        failed reset."""
        self.episode.check_running()
        physics.command(check_action(action))

    def after_step(self, physics: InsertionPhysics) -> None:
        """Score the control step that ``physics.step`` just ran."""
        state = physics.last_state
        self.last_score = self.episode.record(state, self.random)
        self.error = state.error

    def get_observation(self, physics: InsertionPhysics) -> Observation:
        """The last observation, split into ``pose_error``, ``height`` and ``wrench``."""
        parts = np.split(self.episode.observation, np.cumsum([n for _, n in OBSERVATIONS])[:-1])
        return collections.OrderedDict(
            (name, part.copy()) for (name, _), part in zip(OBSERVATIONS, parts, strict=True)
        )

    def get_reward(self, physics: InsertionPhysics) -> float:
        return self.last_score.reward

    def get_termination(self, physics: InsertionPhysics) -> float | None:
        if self.last_score.terminated:
            return 0.0
        if self.last_score.truncated:
            return 1.0
        return None

    def action_spec(self, physics: InsertionPhysics) -> specs.BoundedArray:
        return specs.BoundedArray((4,), np.float64, -A_MAX, A_MAX, name="\t".join(ACTION_NAMES))

    def observation_spec(self, physics: InsertionPhysics) -> ObservationSpec:
        return collections.OrderedDict(
            (name, specs.Array((size,), np.float64, name=name)) for name, size in OBSERVATIONS
        )
