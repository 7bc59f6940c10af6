"""The physics versions: what the ``-v1`` and ``-v2`` env ids simulate with MuJoCo.

========  ==============================================================================
version   the MuJoCo model and its control step
========  ==============================================================================
1         the board's pieces in a static body; every physics step the contact step
2         the board's pieces in the world body (MuJoCo's broadphase no longer recomputes
          the board's bounding box in every step); a longer physics step in free flight,
          where nothing can touch (:mod:`tolins.physics.free_flight`)
========  ==============================================================================

Version 2 keeps version 1's outcomes in 7,988 of 8,000 measured episodes (both experts, a
random policy and π_n on every preset kind, ``benchmarks/v2_equivalence.py``); the other 12
part in contact from a femtometre apart, fewer than moving version 1's start by 1e-12 mm
changes (89). The paper's kinematic simulator is the same in both.
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Integral


@dataclass(frozen=True)
class PhysicsVersion:
    """One physics version.

    Attributes:
        number: 1 or 2, as in the env ids' ``-v1`` and ``-v2``.
        board_in_world: The board's pieces in the world body (``make_mjcf(board_body=False)``).
        free_flight: The longer physics step where nothing can touch.
    """

    number: int
    board_in_world: bool
    free_flight: bool


#: Every version by number.
VERSIONS: dict[int, PhysicsVersion] = {
    1: PhysicsVersion(1, board_in_world=False, free_flight=False),
    2: PhysicsVersion(2, board_in_world=True, free_flight=True),
}
#: The newest version (the default of the generic constructors stays 1: ``-v1`` bit for bit).
LATEST = max(VERSIONS)


def physics_version(value: object) -> PhysicsVersion:
    """The version numbered ``value``; ``ValueError`` naming the allowed numbers otherwise."""
    allowed = ", ".join(map(str, VERSIONS))
    if isinstance(value, bool) or not isinstance(value, Integral) or int(value) not in VERSIONS:
        raise ValueError(f"physics_version={value!r}; allowed: {allowed}")
    return VERSIONS[int(value)]
