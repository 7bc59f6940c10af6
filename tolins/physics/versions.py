"""The physics versions: what the ``-v1``, ``-v2`` and ``-v3`` env ids simulate with MuJoCo.

========  ==============================================================================
version   the MuJoCo model and its control step
========  ==============================================================================
1         the board's pieces in a static body; every physics step the contact step
2         the board's pieces in the world body (MuJoCo's broadphase no longer recomputes
          the board's bounding box in every step); a longer physics step in free flight,
          where nothing can touch (:mod:`tolins.physics.free_flight`)
3         the Panda's only (the free body's newest is 2): version 2 with a firm grip (the
          pads' contacts on the handle stiffer, :data:`~tolins.mjcf.panda.FIRM_GRIP_IMPEDANCE`)
          and the law eight times as stiff along x and y
          (:data:`~tolins.physics.arm.SIDEWAYS_STIFFNESS`)
========  ==============================================================================

Version 2 keeps version 1's outcomes in 7,988 of 8,000 measured episodes (both experts, a
random policy and π_n on every preset kind, ``benchmarks/v2_equivalence.py``); the other 12
part in contact from a femtometre apart, fewer than moving version 1's start by 1e-12 mm
changes (89). The paper's kinematic simulator is the same in both.

Version 3 brings the Panda's success at 50 µm to within 0.05 of the free body's with both
experts on the 2*2, the 2*8 and the square (``benchmarks/panda_fit50.py``, 100 episodes;
version 2: 0.07–0.17 below). On version 2 the part crept 60–90 µm in the hand while its
pins dragged on the board, and under the arm's press (7–9 N, the servos' 5 N) its
sideways spring stalled: a commanded 0.1 mm move made half of it, and the rest, still in
the law's target, added to the expert's next command. Version 2 stays the compliant arm;
version 3's is far stiffer sideways than a Franka's Cartesian impedance is run in practice.
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Integral


@dataclass(frozen=True)
class PhysicsVersion:
    """One physics version.

    Attributes:
        number: 1, 2 or 3, as in the env ids' ``-v1``, ``-v2`` and ``-v3``.
        board_in_world: The board's pieces in the world body (``make_mjcf(board_body=False)``).
        free_flight: The longer physics step where nothing can touch.
        robots: What may hold the workpiece in it (the envs' ``robot``).
        firm_grip: The Panda's pads hold the handle through stiffer contacts.
        stiff_sideways: The Panda's law eight times as stiff along x and y.
    """

    number: int
    board_in_world: bool
    free_flight: bool
    robots: tuple[str, ...] = ("free", "panda")
    firm_grip: bool = False
    stiff_sideways: bool = False


#: Every version by number.
VERSIONS: dict[int, PhysicsVersion] = {
    1: PhysicsVersion(1, board_in_world=False, free_flight=False),
    2: PhysicsVersion(2, board_in_world=True, free_flight=True),
    3: PhysicsVersion(
        3,
        board_in_world=True,
        free_flight=True,
        robots=("panda",),
        firm_grip=True,
        stiff_sideways=True,
    ),
}
#: The newest version (the default of the generic constructors stays 1: ``-v1`` bit for bit).
LATEST = max(VERSIONS)


def versions_of(robot: str) -> tuple[int, ...]:
    """The numbers of the versions that ``robot`` can hold the workpiece in."""
    return tuple(number for number, version in VERSIONS.items() if robot in version.robots)


def check_version_robot(version: PhysicsVersion, robot: str) -> None:
    """``ValueError`` unless ``robot`` can hold the workpiece in ``version``."""
    if robot not in version.robots:
        allowed = ", ".join(map(str, versions_of(robot)))
        raise ValueError(
            f"physics_version={version.number} is robot={' or '.join(map(repr, version.robots))}"
            f"'s only; allowed with robot={robot!r}: physics_version {allowed}"
        )


def physics_version(value: object) -> PhysicsVersion:
    """The version numbered ``value``, or ``value`` itself if it is a :class:`PhysicsVersion`
    already (resolved once, by the task's settings, and handed down as is); ``ValueError``
    naming the allowed numbers otherwise."""
    if isinstance(value, PhysicsVersion):
        return value
    allowed = ", ".join(map(str, VERSIONS))
    if isinstance(value, bool) or not isinstance(value, Integral) or int(value) not in VERSIONS:
        raise ValueError(f"physics_version={value!r}; allowed: {allowed}")
    return VERSIONS[int(value)]
