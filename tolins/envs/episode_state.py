"""One env's running episode: what ``InsertionEnv`` and every slot of the vector env hold.

An :class:`EpisodeState` owns the episode's workpiece, goal, score and last observation,
and turns the backend's :class:`~tolins.envs.backend.BackendState` into the gymnasium
``(observation, reward, terminated, truncated, info)``. The simulator is not in it: the
single env steps one backend, the vector env a batch (:mod:`tolins.envs.vector`), and
both call the same methods in the same order with the env's own random generator, so an
episode is the same bit for bit whichever runs it.

A reset is planned (:meth:`EpisodeState.plan`: every option validated, the workpiece and
the pose drawn) before anything changes; a failed plan leaves the state as it was, marked
broken, and stepping raises ``gymnasium.error.ResetNeeded`` until a reset succeeds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from tolins.envs.backend import BackendState
from tolins.envs.episode import NO_SCORE, EpisodeScore, StepScore, TaskSettings
from tolins.envs.initial_pose import spread_pose
from tolins.envs.randomization import PhysicsDraw
from tolins.geometry.specs import SocketSpec, workpiece_dict
from tolins.geometry.workspace import check_goal, check_pose

#: The keys ``reset(options=...)`` accepts; each applies to that reset's episode only.
RESET_OPTIONS = ("pose", "goal")


@dataclass(frozen=True)
class ResetPlan:
    """A validated reset: the episode's workpiece, initial pose and goal."""

    socket: SocketSpec
    pose: np.ndarray
    goal: np.ndarray
    physics: PhysicsDraw | None = None


def check_options(options: dict[str, Any] | None) -> dict[str, Any]:
    """``options`` as a dict with known keys only (``ValueError`` otherwise)."""
    if options is None:
        return {}
    if not isinstance(options, dict):
        raise ValueError(f"reset options={options!r}; allowed: a dict or None")
    unknown = set(options) - set(RESET_OPTIONS)
    if unknown:
        raise ValueError(
            f"reset options {sorted(map(str, unknown))} are unknown; allowed: 'pose', 'goal'"
        )
    return options


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

    def plan(self, rng: np.random.Generator, options: dict[str, Any] | None) -> ResetPlan:
        """Validate ``options`` and draw the next episode's workpiece and initial pose (in
        that order, from ``rng``); ``ValueError`` leaves the episode as it was, broken."""
        try:
            options = check_options(options)
            goal = check_goal(options["goal"], "options['goal']") if "goal" in options else None
            goal = self._goal if goal is None else goal
            socket = self.settings.draw_socket(rng)
            physics = self.settings.draw_physics(rng)
            if "pose" in options:
                pose = check_pose(socket, options["pose"], "options['pose']")
            else:
                distribution = self.settings.initial_pose
                if physics is not None and physics.pose_spread is not None:
                    distribution = spread_pose(distribution, physics.pose_spread)
                pose = check_pose(socket, distribution.sample(rng, goal))
        except Exception:
            self.broken = True
            raise
        return ResetPlan(socket, pose, goal, physics)

    def begin(
        self, plan: ResetPlan, state: BackendState, rng: np.random.Generator
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start the planned episode from the backend's ``state``: the first observation
        and info (with ``info["workpiece"]``, the episode's socket as
        :func:`~tolins.geometry.specs.workpiece_dict`: its defects' ground truth)."""
        self.socket, self.episode_goal, self.physics = plan.socket, plan.goal, plan.physics
        self.state, self.broken = state, False
        self.score.reset()
        self.observation = self._observe(state, rng)
        info = {**self.info(NO_SCORE), "workpiece": workpiece_dict(plan.socket)}
        if self.physics is not None:
            info["physics"] = self.physics.to_info()
        return self.observation.copy(), info

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
                "the last reset() failed; call reset() with valid options before stepping"
            )
        self.score.check_running()

    @property
    def running(self) -> bool:
        """Whether an episode has been started and has not ended (a broken one counts)."""
        return self.state is not None and not self.score.over

    def advance(
        self, state: BackendState, rng: np.random.Generator
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Score the control step that produced ``state``: gymnasium's step tuple."""
        if state.error is not None:
            info = self.info(self.score.fault())
            info["error"] = state.error
            return self.observation.copy(), 0.0, False, True, info
        self.state = state
        score = self.score.score(state, self.socket)
        self.observation = self._observe(state, rng)
        info = self.info(score, score.success)  # the score's success is the state's
        return self.observation.copy(), score.reward, score.success, score.truncated, info

    def info(self, score: StepScore, success: bool | None = None) -> dict[str, Any]:
        """The ``info`` dict after a reset (``NO_SCORE``) or a step scored ``score``
        (``success``: the state's, when the caller knows it)."""
        state = self.state
        if success is None:
            success = self.settings.is_success(state, self.socket)
        return {
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
