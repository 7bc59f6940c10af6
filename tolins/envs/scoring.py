"""Scoring of the insertion task: each control step's success, collision, reward and end.

:class:`EpisodeScore` counts an episode's steps and collisions and scores each step with
the paper's reward (or a dense mode's, :mod:`tolins.envs.reward`); :class:`StepScore` is
one step's outcome, which every API turns into its own reward and episode end.
"""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym

from tolins.envs.reward import RewardTerms, reward_terms
from tolins.envs.task_settings import TaskSettings
from tolins.geometry.specs import SocketSpec
from tolins.paper import COLLISION_REWARD, SUCCESS_REWARD
from tolins.physics.protocol import BackendState


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
    #: The ``delicate`` reward's term (``-damage_penalty`` on the step a pin became
    #: damaged, else 0), or ``None`` without a ``damage_penalty``.
    reward_damage: float | None = None

    @property
    def damage_ended(self) -> bool:
        """Whether the step ended the episode because a pin became damaged."""
        return bool(self.reward_damage)

    @property
    def terminated(self) -> bool:
        """The episode reached a terminal state: success, or a damaged part."""
        return self.success or self.damage_ended

    @property
    def reward(self) -> float:
        reward = self.reward_success + self.reward_collision
        if self.terms is not None:
            reward = self.terms.total
        if self.reward_damage is not None:
            reward += self.reward_damage
        return reward

    def reward_info(self) -> dict[str, float]:
        """Every term of the reward as ``info`` keys ``reward_*`` (they sum to ``reward``)."""
        if self.terms is not None:
            info = self.terms.to_info()
        else:
            info = RewardTerms(self.reward_success, self.reward_collision).to_info()
        if self.reward_damage is not None:
            info["reward_damage"] = self.reward_damage
        return info


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

    def score(
        self, state: BackendState, socket: SocketSpec | None = None, damaged: bool = False
    ) -> StepScore:
        """Score the step that produced ``state`` (a valid state, not a fault); ``socket``:
        the episode's workpiece (default the nominal one); ``damaged``: a pin became damaged
        in it (the ``delicate`` reward's penalty, with a ``damage_penalty``)."""
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
        penalty = self.settings.damage_penalty
        reward_damage = None if penalty is None else (-penalty if damaged else 0.0)
        ended = success or bool(reward_damage)
        truncated = not ended and self.steps >= self.settings.horizon
        self.over = ended or truncated
        return StepScore(
            success=success,
            collision=collision,
            reward_success=reward_success,
            reward_collision=reward_collision,
            truncated=truncated,
            terms=terms,
            reward_damage=reward_damage,
        )

    def fault(self) -> StepScore:
        """Count a step that ended in a simulator fault: no reward, the episode is over."""
        self.check_running()
        self.steps += 1
        self.over = True
        return StepScore(False, False, 0.0, 0.0, truncated=True)
