"""A Panda law's state and gains as flat vectors, and its target's motion: what the numpy law
(:mod:`tolins.physics.arm`) and the compiled one (:mod:`tolins.physics.compiled_law`) share.
"""

from __future__ import annotations

import numpy as np

#: Layout of a simulation's law state vector: the target position (3, mm), yaw (rad), the
#: commanded twist (6: mm/s, then rad/s) and the posture (one angle per arm joint).
STATE = {"target": slice(0, 3), "yaw": 3, "twist": slice(4, 10), "posture": slice(10, None)}
#: Its length for the Panda's seven joints.
STATE_SIZE = 17


def pack_gains(
    stiffness: np.ndarray,
    damping: np.ndarray,
    force_limit: np.ndarray,
    null: float,
    held: np.ndarray,
) -> np.ndarray:
    """The gains vector the compiled law reads: stiffness (6), damping (6), force limit
    (3), the posture's rate, then the held weight (3, model units)."""
    return np.concatenate([stiffness, damping, force_limit, [null], held]).astype(float)


def advance_target(state: np.ndarray, advance: float, bounds: np.ndarray) -> np.ndarray:
    """Move a law state's target ``advance`` s along its twist within ``bounds`` (the rows
    low and high of ``[x, y, z, yaw]``): a target beyond is put back on the edge, and the
    twist this update tracks (returned) has that axis dropped. Nothing moves at 0."""
    twist = state[4:10].copy()
    if advance > 0.0:
        for r in range(4):
            at = 3 if r == 3 else r  # the yaw's slot; its twist is the last
            turn = 5 if r == 3 else r
            state[at] += state[4 + turn] * advance
            if state[at] < bounds[0, r] or state[at] > bounds[1, r]:
                state[at] = min(max(state[at], bounds[0, r]), bounds[1, r])
                twist[turn] = 0.0
    return twist
