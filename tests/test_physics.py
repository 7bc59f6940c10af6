"""Contact physics: pins inside the clearance go in, pins outside it are blocked, nothing tunnels.

Every case starts 0.05 mm above the board with noise off and pushes straight down at
full speed. Clearances: 2*2 circle 0.2 mm radial, theta ≈ 0.0498 rad (pins 4.02 mm
from the centre); square 0.106 mm per face, theta ≈ 0.106 rad; hexagon 0.052 mm per
face, theta ≈ 0.094 rad; triangle 0.075 mm per face.
"""

from __future__ import annotations

import numpy as np
import pytest
from rollouts import push_down

import tolins
from tolins.envs import InsertionEnv
from tolins.paper import A_MAX, HORIZON

DOWN = np.array([0.0, 0.0, 0.0, -A_MAX[3]])
CIRCLE = tolins.CircularSocket(2, 2)
SQUARE = tolins.PolygonSocket(4, 1.5, 1.65)
HEXAGON = tolins.PolygonSocket(6, 1.2, 1.26)
TRIANGLE = tolins.PolygonSocket(3, 1.5, 1.65)
BENT = tolins.CircularSocket(2, 1, pin_offsets=[[0.3, 0.0], [0.3, 0.0]])

# (socket, axis of the pose [x, y, theta], offset inside, offset outside the clearance)
CASES = [
    (CIRCLE, 0, 0.15, 0.25),
    (CIRCLE, 1, -0.15, -0.25),
    (CIRCLE, 2, 0.035, 0.065),
    (SQUARE, 0, 0.07, 0.15),
    (SQUARE, 1, 0.07, 0.15),
    (SQUARE, 2, -0.07, -0.15),
    (HEXAGON, 0, 0.03, 0.08),
    (HEXAGON, 1, 0.03, 0.08),
    (HEXAGON, 2, 0.05, 0.14),
    (TRIANGLE, 0, 0.05, 0.12),
    (TRIANGLE, 1, 0.05, 0.12),
]
IDS = [f"{type(s).__name__}{getattr(s, 'sides', '')}-{'xyt'[axis]}" for s, axis, *_ in CASES]


def _pose(axis: int, offset: float) -> list[float]:
    pose = [0.0, 0.0, 0.0, 0.05]
    pose[axis] = offset
    return pose


@pytest.mark.parametrize(("socket", "axis", "inside", "outside"), CASES, ids=IDS)
def test_offset_inside_the_clearance_reaches_full_depth(socket, axis, inside, outside) -> None:
    infos = push_down(socket, _pose(axis, inside))
    assert infos[-1]["success"]
    assert infos[-1]["pose"][3] <= -1.0
    assert infos[-1]["n_collisions"] == 0


@pytest.mark.parametrize(("socket", "axis", "inside", "outside"), CASES, ids=IDS)
def test_offset_outside_the_clearance_is_blocked_at_the_surface(
    socket, axis, inside, outside
) -> None:
    infos = push_down(socket, _pose(axis, outside), steps=4)
    last = infos[-1]
    assert not last["success"]
    assert abs(last["pose"][3]) < 1e-3
    assert last["wrench"][3] > 0.0
    assert last["collision"] and last["n_collisions"] >= 3
    assert last["pose"][axis] == pytest.approx(outside, abs=1e-3)


@pytest.mark.parametrize("socket", [CIRCLE, SQUARE, HEXAGON, TRIANGLE], ids=lambda s: repr(s)[:20])
def test_full_speed_push_for_the_whole_horizon_never_tunnels(socket) -> None:
    blocked = [0.5, 0.0, 0.0, 0.05] if socket is CIRCLE else [0.3, 0.0, 0.0, 0.05]
    infos = push_down(socket, blocked)
    assert len(infos) == HORIZON and not infos[-1]["success"]
    penetration = -min(info["pose"][3] for info in infos)
    assert penetration < 1e-3  # below 1 µm
    assert infos[-1]["n_collisions"] == HORIZON
    assert 4.0 < infos[-1]["wrench"][3] <= 5.0 + 1e-6  # the servo's bounded push


def test_bent_pins_insert_where_the_defect_allows_and_not_at_the_nominal_goal() -> None:
    assert not push_down(BENT, [0.0, 0.0, 0.0, 0.05], steps=4)[-1]["success"]
    assert push_down(BENT, [-0.3, 0.0, 0.0, 0.05])[-1]["success"]


def test_force_and_torque_point_against_the_push() -> None:
    """A pin pressed sideways against a hole wall feels the wall push back."""
    env = InsertionEnv(CIRCLE, measurement_noise=0, success_depth=2.0)
    env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, -1.5]})
    _, _, _, _, info = env.step([A_MAX[0], 0.0, 0.0, 0.0])
    assert info["collision"]
    assert info["wrench"][0] < -1.0
    assert info["pose"][0] == pytest.approx(0.2, abs=2e-3)
    env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, -1.5]})
    for _ in range(3):  # 0.025 rad per step against a ≈ 0.05 rad clearance
        _, _, _, _, info = env.step([0.0, 0.0, A_MAX[2], 0.0])
    assert info["collision"]
    assert info["wrench"][2] < 0.0
    assert info["pose"][2] == pytest.approx(0.0498, abs=1e-3)


# Just beyond the clearance: (socket, axis, geometric limit, how far the pin moves per unit)
BEYOND = [
    (CIRCLE, 0, 0.2, 1.0),
    (CIRCLE, 2, 0.0499, 4.016),  # theta: pins 4.016 mm from the centre
    (SQUARE, 0, 0.10607, 1.0),
    (HEXAGON, 0, 0.05196, 1.0),
]


@pytest.mark.parametrize("speed", [A_MAX[3], 0.5])
@pytest.mark.parametrize(("socket", "axis", "limit", "lever"), BEYOND, ids=lambda v: str(v)[:12])
def test_pins_5_to_60_um_beyond_the_clearance_are_not_pulled_in(
    socket, axis, limit, lever, speed
) -> None:
    """Contacts resolved sideways at the hole's edge must not ratchet pins into the hole."""
    for beyond_um in (5, 10, 20, 35, 60):
        pose = _pose(axis, limit + beyond_um * 1e-3 / lever)
        last = push_down(socket, pose, steps=6, speed=speed)[-1]
        assert not last["success"] and last["pose"][3] > -1e-3, (beyond_um, last["pose"])
