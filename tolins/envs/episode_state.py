"""One running episode of the insertion task: what every API of the task holds and calls.

An :class:`EpisodeState` owns the episode's workpiece, goal, score and last observation.
``InsertionEnv``, every slot of the vector env (:mod:`tolins.envs.vector`) and the
dm_control task (:class:`tolins.dmc.Insert`) each hold one and call the same methods in the
same order with their own random generator, so an episode is the same bit for bit whichever
runs it. The simulator is not in it: the caller steps its own (one backend, a batch, a
dm_control physics) and hands over the resulting :class:`~tolins.physics.protocol.BackendState`.

* :meth:`EpisodeState.plan`: validate the reset and draw, in this order, the workpiece,
  the physics and the initial pose (:class:`~tolins.envs.task_settings.TaskSettings`);
  nothing changes yet, and a failed plan leaves the episode as it was, marked broken, so
  that stepping raises ``gymnasium.error.ResetNeeded`` until a reset succeeds.
* :meth:`EpisodeState.start` (or :meth:`EpisodeState.begin`, with gymnasium's reset info):
  the planned episode from the simulator's first state, and its first observation.
* :meth:`EpisodeState.record` (or :meth:`EpisodeState.advance`, gymnasium's step tuple):
  score a control step (:class:`~tolins.envs.scoring.EpisodeScore`) and observe its state.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from tolins.envs.scoring import NO_SCORE, EpisodeScore, StepScore
from tolins.envs.task_settings import TaskSettings
from tolins.geometry.delicate import bent_beyond
from tolins.geometry.specs import SocketSpec, workpiece_dict
from tolins.geometry.workspace import check_goal, check_pose
from tolins.physics.protocol import BackendState
from tolins.physics.randomization import PhysicsDraw

#: The keys ``reset(options=...)`` accepts; each applies to that reset's episode only.
RESET_OPTIONS = ("pose", "goal", "keep_part")


@dataclass(frozen=True)
class ResetPlan:
    """A validated reset: the episode's workpiece, initial pose and goal."""

    socket: SocketSpec
    pose: np.ndarray
    goal: np.ndarray
    physics: PhysicsDraw | None = None
    grasp: np.ndarray | None = None
    keep_part: bool = False

    def apply_physics(self, set_physics: Callable[[PhysicsDraw], object]) -> None:
        """Hand the episode's randomised physics to a simulator's ``set_physics`` (before
        its reset). Without ``randomization`` nothing is drawn and the simulator keeps its
        model as compiled."""
        if self.physics is not None:
            set_physics(self.physics)

    def apply_grasp(self, set_grasp: Callable[[np.ndarray], object]) -> None:
        """Hand the episode's grasp error to a robot's ``set_grasp`` (before its reset);
        without ``grasp_error`` nothing is drawn and the robot keeps its grasp."""
        if self.grasp is not None:
            set_grasp(self.grasp)


def check_options(options: dict[str, Any] | None) -> dict[str, Any]:
    """``options`` as a dict with known keys only (``ValueError`` otherwise)."""
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise ValueError(f"reset options={options!r}; allowed: a dict or None")
    unknown = set(options) - set(RESET_OPTIONS)
    if unknown:
        raise ValueError(
            f"reset options {sorted(map(str, unknown))} are unknown; allowed: "
            f"{', '.join(map(repr, RESET_OPTIONS))}"
        )
    return options


def check_keep_part(settings: TaskSettings, options: dict[str, Any]) -> bool:
    """``options["keep_part"]`` (default ``False``); ``ValueError`` unless it is a bool, and
    ``True`` only with elastic-plastic pins (a rigid part has nothing to keep)."""
    keep = options.get("keep_part", False)
    if not isinstance(keep, (bool, np.bool_)):
        raise ValueError(f"options['keep_part']={keep!r}; allowed: True or False")
    if keep and settings.elastic is None:
        raise ValueError(
            "options['keep_part']=True keeps the bends of elastic-plastic pins; allowed: "
            "pins='elastic-plastic', or keep_part=False"
        )
    return bool(keep)


def is_damaged(settings: TaskSettings, bend: np.ndarray) -> bool:
    """Whether a pin's permanent tip offset ``bend`` ``(n_pins, 2)`` (mm) reaches the
    settings' ``damage_threshold``."""
    return bent_beyond(bend, settings.damage_threshold)


def check_fixed_pose(settings: TaskSettings, pose: object) -> np.ndarray | None:
    """``pose`` ``[x, y, theta, z]`` as the initial pose of every episode (``None``: drawn),
    valid for the nominal socket; one below the board's top (pins in their holes) is refused
    when the episodes draw defective workpieces, which may not fit there."""
    if pose is None:
        return None
    pose = check_pose(settings.socket, pose)
    if pose[3] < 0:
        for name in ("defect_sigma", "defects"):
            if getattr(settings, name) is not None:
                raise ValueError(
                    f"pose={pose.tolist()!r} has the pins in the holes, which a defective "
                    f"workpiece ({name}) may not fit; allowed with {name}: z ≥ 0"
                )
    return pose


class EpisodeState:
    """The episode of one env (see the module docstring).

    Args:
        settings: The task's validated settings.
        goal: The goal ``[x*, y*, theta*]`` of every episode whose reset names none.
    """

    def __init__(self, settings: TaskSettings, goal: Any) -> None:
        self.settings = settings
        self.goal = goal
        self.socket = settings.socket
        self.score = EpisodeScore(settings)
        self.state: BackendState | None = None
        self.physics: PhysicsDraw | None = None
        self.observation = np.zeros(8)
        self.broken = False
        self.damaged_at: int | None = None

    @property
    def goal(self) -> np.ndarray:
        """The goal ``[x*, y*, theta*]`` (mm, rad) the observation is measured from now."""
        return self.episode_goal.copy()

    @goal.setter
    def goal(self, value: Any) -> None:
        """Move the goal of the running episode and of every later one whose reset names
        none (a goal in ``reset(options=...)`` is for that episode only)."""
        self._goal = check_goal(value)
        self.episode_goal = self._goal

    def plan(
        self,
        rng: np.random.Generator,
        options: dict[str, Any] | None = None,
        *,
        pose: Any = None,
    ) -> ResetPlan:
        """Validate ``options`` and draw the next episode's workpiece, physics and initial
        pose (in that order, from ``rng``); the pose is ``options["pose"]``, else ``pose``
        (a fixed one, :func:`check_fixed_pose`), else drawn around the goal. ``ValueError``
        leaves the episode as it was, broken."""
        try:
            options = check_options(options)
            goal = check_goal(options["goal"], "options['goal']") if "goal" in options else None
            goal = self._goal if goal is None else goal
            keep_part = check_keep_part(self.settings, options)
            socket = self.settings.draw_socket(rng)
            if keep_part:  # drawn all the same, so the random stream does not change
                socket = self.socket
            physics = self.settings.draw_physics(rng)
            grasp = self.settings.draw_grasp(rng)
            if "pose" in options:
                pose = check_pose(socket, options["pose"], "options['pose']")
            elif pose is not None:
                pose = check_pose(socket, pose)
            else:
                distribution = self.settings.pose_distribution(physics)
                pose = check_pose(socket, distribution.sample(rng, goal))
        except BaseException:
            self.broken = True
            raise
        return ResetPlan(socket, pose, goal, physics, grasp, keep_part)

    def start(self, plan: ResetPlan, state: BackendState, rng: np.random.Generator) -> np.ndarray:
        """Start the planned episode from the simulator's first ``state``: its first
        observation (a copy)."""
        self.socket, self.episode_goal, self.physics = plan.socket, plan.goal, plan.physics
        self.state, self.broken = state, False
        self.score.reset()
        self.damaged_at = None
        if state.pin_bend is not None and is_damaged(self.settings, state.pin_bend):
            self.damaged_at = 0
        self.observation = self._observe(state, rng)
        return self.observation.copy()

    def begin(
        self, plan: ResetPlan, state: BackendState, rng: np.random.Generator
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """:meth:`start` with gymnasium's reset info (with ``info["workpiece"]``, the
        episode's socket as :func:`~tolins.geometry.specs.workpiece_dict`: its defects'
        ground truth, and ``info["physics"]`` with a physics draw)."""
        observation = self.start(plan, state, rng)
        info = {**self.info(NO_SCORE), "workpiece": workpiece_dict(plan.socket)}
        if self.physics is not None:
            info["physics"] = self.physics.to_info()
        if plan.grasp is not None:
            info["grasp_error"] = plan.grasp.copy()
        return observation, info

    def _observe(self, state: BackendState, rng: np.random.Generator) -> np.ndarray:
        """The observation of ``state``, with the episode's drawn sensor bias and noise."""
        observation = self.settings.observe(state, self.episode_goal, rng)
        if self.physics is not None:
            observation = self.physics.observe(observation, rng)
        return observation

    def check_running(self) -> None:
        """``gymnasium.error.ResetNeeded`` unless an episode is running."""
        if self.state is None:
            raise gym.error.ResetNeeded("step() called before reset()")
        if self.broken:
            raise gym.error.ResetNeeded(
                "the last reset() failed; fix what it raised and call reset() before stepping"
            )
        self.score.check_running()

    @property
    def running(self) -> bool:
        """Whether an episode has been started and has not ended (a broken one counts)."""
        return self.state is not None and not self.score.over

    def record(self, state: BackendState, rng: np.random.Generator) -> StepScore:
        """Score the control step that produced ``state`` and observe it; a simulator fault
        (``state.error``) ends the episode without reward and keeps the last state and
        observation."""
        if state.error is not None:
            return self.score.fault()
        self.state = state
        bend = state.pin_bend
        damaged = self.damaged_at is None and bend is not None and is_damaged(self.settings, bend)
        score = self.score.score(state, self.socket, damaged)
        if damaged:
            self.damaged_at = self.score.steps
        self.observation = self._observe(state, rng)
        return score

    def advance(
        self, state: BackendState, rng: np.random.Generator
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """:meth:`record` as gymnasium's step tuple (``info["error"]`` after a fault)."""
        score = self.record(state, rng)
        if state.error is not None:
            info = self.info(score)
            info["error"] = state.error
        else:
            info = self.info(score, score.success)  # the score's success is the state's
        return self.observation.copy(), score.reward, score.terminated, score.truncated, info

    def info(self, score: StepScore, success: bool | None = None) -> dict[str, Any]:
        """The ``info`` dict after a reset (``NO_SCORE``) or a step scored ``score``
        (``success``: the state's, when the caller knows it)."""
        state = self.state
        if success is None:
            success = self.settings.is_success(state, self.socket)
        info = {
            "success": success,
            "is_success": success,
            "collision": score.collision,
            "n_collisions": self.score.collisions,
            "pose": state.pose.copy(),
            "wrench": state.wrench.copy(),
            "peak_force": state.peak_force,
            "step": self.score.steps,
            "goal": self.episode_goal.copy(),
            **score.reward_info(),
        }
        if state.sensed_pose is not None:
            info["sensed_pose"] = state.sensed_pose.copy()
        if state.sensed_wrench is not None:
            info["sensed_wrench"] = state.sensed_wrench.copy()
        if state.pin_bend is not None:
            info["pin_bend"] = state.pin_bend.copy()
            info["pin_deflection"] = state.pin_deflection.copy()
            info["damaged"] = self.damaged_at is not None
            info["damaged_at"] = self.damaged_at
        return info
