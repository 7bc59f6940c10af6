"""The random initial pose of an episode: its distribution and the servo range it must keep."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from tolins.geometry.validation import check_real
from tolins.geometry.workspace import GOAL_RANGE, THETA_RANGE, XY_RANGE, Z_MAX


@dataclass(frozen=True)
class InitialPoseDistribution:
    """Initial pose ``[x, y, theta, z]`` relative to the goal, sampled independently per axis.

    The horizontal offset has a radius uniform in ``[radius_min, radius_max]`` (mm) in a
    uniformly random direction; theta is uniform in ``±theta_max`` (rad); the height of
    the pin tips above the board is uniform in ``[z_min, z_max]`` (mm). The defaults
    are chosen so that the safe expert needs about 35 control steps and the efficient
    one about 30, as in the paper (measured by ``tolins demo``). Every field must be a
    finite real number (``ValueError`` naming it otherwise).
    """

    radius_min: float = 1.0
    radius_max: float = 3.0
    theta_max: float = 0.1
    z_min: float = 16.0
    z_max: float = 18.0

    def __post_init__(self) -> None:
        for name in ("radius_min", "radius_max", "theta_max", "z_min", "z_max"):
            value = check_real(name, getattr(self, name), "a finite number (mm or rad)")
            object.__setattr__(self, name, value)
        if not 0 <= self.radius_min <= self.radius_max:
            raise ValueError(
                f"radius_min={self.radius_min!r}, radius_max={self.radius_max!r}; "
                "allowed: 0 ≤ radius_min ≤ radius_max"
            )
        if self.theta_max < 0:
            raise ValueError(f"theta_max={self.theta_max!r}; allowed: ≥ 0")
        if not 0 < self.z_min <= self.z_max:
            raise ValueError(
                f"z_min={self.z_min!r}, z_max={self.z_max!r}; allowed: 0 < z_min ≤ z_max"
            )

    def sample(self, rng: np.random.Generator, goal: np.ndarray) -> np.ndarray:
        """One pose ``[x, y, theta, z]`` around ``goal`` ``[x*, y*, theta*]``."""
        radius = rng.uniform(self.radius_min, self.radius_max)
        direction = rng.uniform(0.0, 2 * np.pi)
        theta = rng.uniform(-self.theta_max, self.theta_max)
        z = rng.uniform(self.z_min, self.z_max)
        offset = np.array([radius * np.cos(direction), radius * np.sin(direction), theta])
        return np.append(np.asarray(goal, dtype=float) + offset, z)


def spread_pose(distribution: InitialPoseDistribution, factor: float) -> InitialPoseDistribution:
    """``distribution`` with its horizontal offsets and theta range scaled by ``factor``
    (the randomised initial-pose spread, :mod:`tolins.physics.randomization`)."""
    return dataclasses.replace(
        distribution,
        radius_min=distribution.radius_min * factor,
        radius_max=distribution.radius_max * factor,
        theta_max=distribution.theta_max * factor,
    )


def check_initial_pose(distribution: object) -> InitialPoseDistribution:
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
