"""An episode: its record (:class:`Episode`), the step logic every loop shares
(:class:`EpisodeRun`) and the single-env loop (:func:`run_episode`).

What an episode keeps comes from its collectors (:mod:`tolins.rollouts.collectors`):
Table 1's figures and the force-aware scores always, a demonstration's (observation,
action) pairs or the true poses when asked for. Many episodes at once go through the
vector env (:mod:`tolins.rollouts.runner`), which drives the same :class:`EpisodeRun` per
slot and gives the same records bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

import gymnasium as gym
import numpy as np

import tolins.envs  # noqa: F401  (registers the env ids)
from tolins.envs.actions import check_action
from tolins.envs.tasks import check_env_id
from tolins.rollouts.collectors import Collector, Forces, Info, Outcome, Poses
from tolins.rollouts.forces import ForceScores
from tolins.stopping import raise_if_stopped

Policy = Callable[[np.ndarray], np.ndarray]

#: The fields an episode's JSON form holds: its figures and force-aware scores (the arrays
#: of pairs and poses stay in memory), and ``damaged`` where the pins can bend.
JSON_FIELDS = ("reward", "success", "steps", "collisions", "error", "forces", "profile")
#: The JSON fields written only when they are not ``None``.
OPTIONAL_JSON_FIELDS = ("damaged",)


@dataclass(frozen=True, eq=False)
class Episode:
    """What one episode came to.

    ``reward`` (the return), ``success``, ``steps``, ``collisions`` (collision steps) and
    ``error`` (the simulator fault that ended it) are Table 1's; ``forces`` are its
    force-aware scores and ``profile`` each step's ``(depth mm, peak normal force N)``
    (:mod:`tolins.rollouts.forces`; both ``None`` in a record written before the scores
    existed). ``observations`` ``(T, 8)`` and ``actions`` ``(T, 4)`` are its pairs
    (:class:`~tolins.rollouts.collectors.Pairs`), ``poses`` ``(T + 1, 4)`` its true poses
    (:class:`~tolins.rollouts.collectors.Poses`); ``None`` unless collected. ``damaged``:
    whether a pin was bent beyond the env's ``damage_threshold`` by the episode's end
    (``info["damaged"]``, docs/delicate.md), ``None`` where the pins are rigid. Two records
    are equal when every field is, arrays element for element.
    """

    reward: float
    success: bool
    steps: int
    collisions: int
    error: str | None = None
    forces: ForceScores | None = None
    profile: tuple[tuple[float, float], ...] | None = None
    observations: np.ndarray | None = None
    actions: np.ndarray | None = None
    poses: np.ndarray | None = None
    damaged: bool | None = None

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Episode):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return a is not None and b is not None and np.array_equal(a, b)
    return a == b


def episode_to_dict(episode: Episode) -> dict[str, Any]:
    """``episode``'s JSON form: the :data:`JSON_FIELDS`, the scores as a dict."""
    row = asdict(replace(episode, observations=None, actions=None, poses=None))
    optional = {name: row[name] for name in OPTIONAL_JSON_FIELDS if row[name] is not None}
    return {**{name: row[name] for name in JSON_FIELDS}, **optional}


def episode_from_dict(row: dict) -> Episode:
    """The :class:`Episode` of :func:`episode_to_dict` (or ``dataclasses.asdict``), as
    JSON gives it back."""
    forces, profile = row.get("forces"), row.get("profile")
    return Episode(
        **{
            **row,
            "forces": None if forces is None else ForceScores(**forces),
            "profile": None if profile is None else tuple(tuple(p) for p in profile),
        }
    )


class EpisodeRun:
    """One episode as it runs: its policy chooses each action, its collectors record.

    A loop makes one after the reset, then for every step calls :meth:`act` on the
    observation, steps the env with the action and hands the step's outcome to
    :meth:`observe`, until :attr:`done`; :meth:`episode` is the record. The single-env
    loop and each slot of the vector runner drive it alike, so both make the same
    policy calls and the same records.

    Args:
        policy: ``observation -> [ux, uy, utheta, uz]``.
        settings: The env's ``TaskSettings`` (for :class:`~tolins.rollouts.collectors.Forces`).
        observation: The reset's observation.
        info: The reset's ``info``.
        collectors: Fresh collectors beyond :class:`~tolins.rollouts.collectors.Outcome`
            and :class:`~tolins.rollouts.collectors.Forces`, which every episode keeps.
    """

    def __init__(
        self,
        policy: Policy,
        settings: Any,
        observation: np.ndarray,
        info: Info,
        collectors: Sequence[Collector] = (),
    ) -> None:
        self.policy = policy
        self.collectors: tuple[Collector, ...] = (Outcome(), Forces(settings), *collectors)
        self.done = False
        self._action = np.zeros(4)
        for collector in self.collectors:
            collector.on_reset(observation, info)

    def act(self, observation: np.ndarray) -> np.ndarray:
        """The policy's action on ``observation``, checked and clipped to ±a_max as the env
        applies it (``ValueError`` for NaN, inf or a wrong shape)."""
        self._action = check_action(self.policy(observation))
        return self._action

    def observe(
        self,
        observation: np.ndarray,
        reward: float,
        terminated: bool,
        truncated: bool,
        info: Info,
    ) -> None:
        """What the env's step with the last :meth:`act` returned."""
        for collector in self.collectors:
            collector.on_step(observation, self._action, reward, terminated, truncated, info)
        self.done = bool(terminated or truncated)

    def episode(self) -> Episode:
        """The record: every collector's fields."""
        record: dict[str, Any] = {}
        for collector in self.collectors:
            record.update(collector.result())
        return Episode(**record)


def run_episode(
    env: gym.Env,
    policy: Policy,
    seed: int | None = None,
    collectors: Sequence[Collector] = (),
) -> Episode:
    """Run ``policy`` in ``env`` from ``reset(seed=seed)`` until the episode ends; its
    record, with what the ``collectors`` (fresh ones) kept
    (:class:`~tolins.stopping.Stopped` before a step once a stop is requested)."""
    observation, info = env.reset(seed=seed)
    run = EpisodeRun(policy, env.unwrapped.settings, observation, info, collectors)
    while not run.done:
        raise_if_stopped()
        observation, reward, terminated, truncated, info = env.step(run.act(observation))
        run.observe(observation, reward, terminated, truncated, info)
    return run.episode()


def episode_poses(env: gym.Env, policy: Policy, seed: int | None = None) -> np.ndarray:
    """The true workpiece poses ``(steps + 1, 4)`` = ``[x, y, theta, z]`` of one episode of
    ``policy`` in ``env``, from the initial pose to the last."""
    return run_episode(env, policy, seed, (Poses(),)).poses


def make_env(env_id: str, backend: str) -> gym.Env:
    """The unwrapped env ``env_id`` on ``backend`` (no wrappers: rollouts end on their own)."""
    return gym.make(check_env_id(env_id), backend=backend).unwrapped
