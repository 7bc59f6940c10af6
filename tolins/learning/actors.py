"""Policies named on a command line, ready to act: ``observation (8,) -> action (4,)``."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.learning.policy import load_policy
from tolins.policies import EXPERTS


def make_actor(entry: str, socket: SocketSpec) -> Callable[[np.ndarray], np.ndarray]:
    """An expert by name (``safe``, ``efficient``) or ``NAME=PATH`` of a policy saved by
    ``tolins train``; a tolerance-guided policy gets the embedding of ``socket``."""
    if "=" not in entry:
        if entry not in EXPERTS:
            raise ValueError(
                f"policy {entry!r} is unknown; allowed: {sorted(EXPERTS)} or NAME=PATH"
            )
        return EXPERTS[entry]()
    policy, _ = load_policy(entry.split("=", 1)[1])
    if policy.architecture.kind != "tolerance_guided":
        return policy.bind()
    from tolins.embedding import encode  # the embedding imports learning: import on use

    return policy.bind(encode(socket))
