"""What an episode keeps, step by step: the collectors an episode loop feeds.

A collector is a small object with three methods. The loop calls :meth:`Collector.on_reset`
once with the reset's observation and ``info``, :meth:`Collector.on_step` after every
``env.step`` with the action the env applied and what the step returned, and at the end
:meth:`Collector.result` for the fields of the episode's record
(:class:`~tolins.rollouts.episodes.Episode`) that it fills. Every loop of
:mod:`tolins.rollouts` feeds the same collectors in the same way, whether the episode runs
in a single env or in one slot of a vector env (there ``info`` is the slot's view of the
batched infos, :class:`~tolins.rollouts.infos.InfoRow`).

:class:`Outcome` and :class:`Forces` are kept for every episode (Table 1's figures and the
force-aware scores); :class:`Pairs` (a demonstration's (observation, action) pairs) and
:class:`Poses` (the true poses, for recordings and plots) when asked for.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from tolins.rollouts.forces import ForceTracker

Info = Mapping[str, Any]


class Collector(Protocol):
    """Records one episode from the calls of an episode loop."""

    def on_reset(self, observation: np.ndarray, info: Info) -> None:
        """The episode begins: the reset's ``observation`` and ``info``."""

    def on_step(
        self,
        observation: np.ndarray,
        action: np.ndarray,
        reward: float,
        terminated: bool,
        truncated: bool,
        info: Info,
    ) -> None:
        """One step: the ``action`` the env applied, then what ``env.step`` returned."""

    def result(self) -> dict[str, Any]:
        """The fields of the episode's record this collector fills (none for one whose
        owner reads it directly)."""


class Outcome:
    """Table 1's figures of an episode: its return, and at its end whether it succeeded,
    its steps, its collision steps and the simulator fault that ended it, if any."""

    def on_reset(self, observation: np.ndarray, info: Info) -> None:
        self._total, self._last = 0.0, info

    def on_step(self, observation, action, reward, terminated, truncated, info) -> None:
        self._total += reward
        self._last = info

    def result(self) -> dict[str, Any]:
        info = self._last
        error = info.get("error")
        result = {
            "reward": float(self._total),
            "success": bool(info["success"]),
            "steps": int(info["step"]),
            "collisions": int(info["n_collisions"]),
            "error": None if error is None else str(error),
        }
        if "damaged" in info:  # pins that bend (docs/delicate.md)
            result["damaged"] = bool(info["damaged"])
        return result


class Forces:
    """The force-aware scores and the per-step ``(depth, peak force)`` profile
    (:class:`~tolins.rollouts.forces.ForceTracker`) of an env with ``settings``
    (``TaskSettings``: its control step and collision threshold)."""

    def __init__(self, settings: Any) -> None:
        self.settings = settings

    def on_reset(self, observation: np.ndarray, info: Info) -> None:
        self._tracker = ForceTracker.of(self.settings, info)

    def on_step(self, observation, action, reward, terminated, truncated, info) -> None:
        self._tracker.step(info["peak_force"], info["pose"][3])

    def result(self) -> dict[str, Any]:
        return {"forces": self._tracker.scores(), "profile": self._tracker.profile()}


class Pairs:
    """A demonstration's pairs: each observation the policy acted on ``(T, 8)`` and the
    action the env applied to it ``(T, 4)`` (checked and clipped to ±a_max)."""

    def on_reset(self, observation: np.ndarray, info: Info) -> None:
        self._seen = np.array(observation)
        self._observations: list[np.ndarray] = []
        self._actions: list[np.ndarray] = []

    def on_step(self, observation, action, reward, terminated, truncated, info) -> None:
        self._observations.append(self._seen)
        self._actions.append(np.array(action))
        self._seen = np.array(observation)

    def result(self) -> dict[str, Any]:
        return {"observations": np.array(self._observations), "actions": np.array(self._actions)}


class Poses:
    """The true workpiece pose ``[x, y, theta, z]`` after the reset and after every step,
    ``(steps + 1, 4)``: the trajectory a recording or a plot draws."""

    def on_reset(self, observation: np.ndarray, info: Info) -> None:
        self._poses = [np.array(info["pose"])]

    def on_step(self, observation, action, reward, terminated, truncated, info) -> None:
        self._poses.append(np.array(info["pose"]))

    def result(self) -> dict[str, Any]:
        return {"poses": np.array(self._poses)}


class Transitions:
    """Every step as the env gave it, for a dataset: ``observations`` and ``infos`` after
    the reset and after each step (``T + 1``), and per step the applied ``actions``, the
    ``rewards``, ``terminations`` and ``truncations`` (``T``). Its owner reads them; the
    record gets none."""

    def on_reset(self, observation: np.ndarray, info: Info) -> None:
        self.observations, self.infos = [np.array(observation)], [info]
        self.actions: list[np.ndarray] = []
        self.rewards: list[float] = []
        self.terminations: list[bool] = []
        self.truncations: list[bool] = []

    def on_step(self, observation, action, reward, terminated, truncated, info) -> None:
        self.observations.append(np.array(observation))
        self.infos.append(info)
        self.actions.append(np.array(action))
        self.rewards.append(reward)
        self.terminations.append(terminated)
        self.truncations.append(truncated)

    def result(self) -> dict[str, Any]:
        return {}
