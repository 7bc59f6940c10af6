"""Reward modes of the insertion task, named as in ManiSkill3: sparse, dense, normalized_dense.

Pure functions of the true pose ``[x, y, theta, z]``, the episode's socket and the task's
settings. ``sparse`` is the paper's reward. ``dense`` adds four shaping terms to it, each
≤ 0 and near 0 only once every pin is ``success_depth`` deep in its hole, centred, so that
no term pays for hovering, for pushing on the board or for leaving the board, and ending
the episode by success is always worth more than any way of staying in it:

* ``reward_approach`` = ``-w_a · min(d / 5 mm, 1)``, ``d`` the mean horizontal distance of
  the workpiece's key points to their targets (circles: each pin centre to its hole's;
  polygons: each peg vertex to its place in the hole, theta modulo the symmetry).
* ``reward_height`` = ``-w_h · clip(z, 0, 20 mm) / 20 mm``: the pin tips' height over the
  board; nothing more is paid below the board's top.
* ``reward_alignment`` = ``-w_l · u / (1 + u)``, ``u`` the use of the clearance
  (:func:`clearance_use`: 0 centred, ``u ≤ 1`` exactly when every pin is over its own
  hole, :func:`tolins.geometry.tolerance.contains`; ``-w_l / 2`` on the boundary). It
  does not saturate, so a rotation far outside the tolerance still has a gradient.
* ``reward_depth`` = ``-w_d · (1 - aligned · clip(-z, 0, success_depth) / success_depth)``:
  insertion depth, counted only while aligned.

``normalized_dense`` maps the dense step reward affinely onto [0, 1]:
``(r - lo) / (hi - lo)`` with ``lo = -(w_a + w_h + w_l + w_d) + COLLISION_REWARD`` and
``hi = SUCCESS_REWARD``; every term is scaled by ``1 / (hi - lo)`` and ``reward_offset``
``= -lo / (hi - lo)`` carries the shift (so the terms still sum to the reward).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from tolins.envs.initial_pose import InitialPoseDistribution
from tolins.geometry.specs import CircularSocket, SocketSpec, inradius, polygon_vertices
from tolins.geometry.tolerance import contains, pin_gaps
from tolins.paper import A_MAX, COLLISION_REWARD, CONTROL_DT, HORIZON, SUCCESS_REWARD

REWARD_MODES = ("sparse", "dense", "normalized_dense")
#: Distance (mm) and height (mm) at which the approach and height terms saturate.
APPROACH_SCALE = 5.0
HEIGHT_SCALE = 20.0


@dataclass(frozen=True)
class DenseWeights:
    """Weights of the dense shaping terms (the largest penalty of each, per step)."""

    approach: float = 1.0
    height: float = 1.0
    alignment: float = 1.0
    depth: float = 0.5

    @property
    def total(self) -> float:
        return self.approach + self.height + self.alignment + self.depth


DENSE_WEIGHTS = DenseWeights()


@dataclass(frozen=True)
class RewardTerms:
    """One step's reward, term by term (each term is also an ``info`` key ``reward_*``)."""

    success: float = 0.0
    collision: float = 0.0
    approach: float = 0.0
    height: float = 0.0
    alignment: float = 0.0
    depth: float = 0.0
    offset: float = 0.0

    @property
    def total(self) -> float:
        """The step reward: the sum of the terms (``sparse``: exactly success + collision)."""
        return (
            self.success
            + self.collision
            + (self.approach + self.height + self.alignment + self.depth + self.offset)
        )

    def to_info(self) -> dict[str, float]:
        return {key: float(getattr(self, name)) for key, name in _INFO_KEYS}


#: ``(info key, field)`` of every term, in field order.
_INFO_KEYS = tuple((f"reward_{f.name}", f.name) for f in fields(RewardTerms))


def check_reward_mode(mode: object) -> str:
    """``mode`` if it is one of :data:`REWARD_MODES`, else ``ValueError``."""
    if mode not in REWARD_MODES:
        raise ValueError(f"reward_mode={mode!r}; allowed: {', '.join(REWARD_MODES)}")
    return str(mode)


def approach_distance(socket: SocketSpec, pose: np.ndarray) -> float:
    """Mean horizontal distance (mm) of the workpiece's key points to their targets."""
    pose = np.asarray(pose, dtype=float)
    if isinstance(socket, CircularSocket):
        gaps = pin_gaps(socket, socket.offsets, pose[:3])
        return float(np.mean(np.hypot(gaps[:, 0], gaps[:, 1])))
    period = 2 * np.pi / socket.sides
    theta = (pose[2] + period / 2) % period - period / 2
    vertices = polygon_vertices(socket.sides, socket.pin_circumradius)
    c, s = np.cos(theta), np.sin(theta)
    moved = vertices @ np.array([[c, s], [-s, c]]) + pose[:2]
    return float(np.mean(np.hypot(*(moved - vertices).T)))


def clearance_use(socket: SocketSpec, pose: np.ndarray) -> float:
    """How much of the clearance ``[x, y, theta]`` uses: 0 centred, ≤ 1 inside the tolerance.

    Circles: the largest pin-to-hole distance over the clearance. Polygons: how far the
    peg's support reaches past its centred position toward the nearest hole face, over
    the face-to-face clearance.
    """
    pose = np.asarray(pose, dtype=float)
    if isinstance(socket, CircularSocket):
        gaps = pin_gaps(socket, socket.offsets, pose[:3])
        return float(np.max(np.hypot(gaps[:, 0], gaps[:, 1])) / socket.clearance)
    angles = np.arange(socket.sides) * (2 * np.pi / socket.sides)
    gauge = np.max(pose[0] * np.cos(angles) + pose[1] * np.sin(angles))
    period = 2 * np.pi / socket.sides
    support = socket.pin_circumradius * np.cos(np.mod(pose[2], period) - period / 2)
    reach = gauge + support - inradius(socket.sides, socket.pin_circumradius)
    return float(max(reach, 0.0) / socket.clearance)


def is_aligned(socket: SocketSpec, pose: np.ndarray) -> bool:
    """Whether ``[x, y, theta]`` puts every pin over its own hole (inside the tolerance)."""
    return bool(contains(socket, np.asarray(pose, dtype=float)[:3]))


def shaping_terms(
    socket: SocketSpec,
    pose: np.ndarray,
    success_depth: float,
    weights: DenseWeights = DENSE_WEIGHTS,
) -> dict[str, float]:
    """The dense shaping terms (``approach``, ``height``, ``alignment``, ``depth``) of ``pose``."""
    z = float(pose[3])
    aligned = is_aligned(socket, pose)
    use = clearance_use(socket, pose)
    depth = min(max(-z, 0.0), success_depth) / success_depth if aligned else 0.0
    return {
        "approach": -weights.approach * min(approach_distance(socket, pose) / APPROACH_SCALE, 1.0),
        "height": -weights.height * min(max(z, 0.0), HEIGHT_SCALE) / HEIGHT_SCALE,
        "alignment": -weights.alignment * use / (1.0 + use),
        "depth": -weights.depth * (1.0 - depth),
    }


def reward_terms(
    mode: str,
    reward_success: float,
    reward_collision: float,
    socket: SocketSpec,
    pose: np.ndarray,
    success_depth: float,
    weights: DenseWeights = DENSE_WEIGHTS,
) -> RewardTerms:
    """The step's terms in ``mode`` from the paper's two terms and the true ``pose``."""
    if mode == "sparse":
        return RewardTerms(reward_success, reward_collision)
    terms = RewardTerms(
        reward_success, reward_collision, **shaping_terms(socket, pose, success_depth, weights)
    )
    if mode == "dense":
        return terms
    low = -weights.total + COLLISION_REWARD
    span = SUCCESS_REWARD - low
    scaled = {f.name: getattr(terms, f.name) / span for f in fields(terms)}
    scaled["offset"] = -low / span
    return RewardTerms(**scaled)


def sparse_return_ceiling(
    initial_pose: InitialPoseDistribution | None = None,
    success_depth: float = 1.0,
    horizon: int = HORIZON,
) -> float:
    """The most sparse return a policy can expect from ``initial_pose``'s starts: success
    in the fewest control steps a full-speed descent takes, ``ceil((z0 + success_depth) /
    (a_max,z · dt))``, and no collision; the mean over the start height ``z0`` (uniform in
    ``[z_min, z_max]``), exact. The horizontal and theta offsets are covered while
    descending (at the default distribution's largest, 3 mm and 0.1 rad, in 5 and 4 steps
    of the 28 or more the descent takes)."""
    distribution = initial_pose or InitialPoseDistribution()
    per_step = float(A_MAX[3]) * CONTROL_DT
    low, high = distribution.z_min + success_depth, distribution.z_max + success_depth
    first, last = int(np.ceil(low / per_step)), int(np.ceil(high / per_step))
    if high == low:
        weights = {first: 1.0}
    else:  # k steps for the heights in ((k - 1) · per_step, k · per_step]
        weights = {
            k: (min(k * per_step, high) - max((k - 1) * per_step, low)) / (high - low)
            for k in range(first, last + 1)
        }
    return float(sum(w * SUCCESS_REWARD * max(1 - k / horizon, 0.0) for k, w in weights.items()))
