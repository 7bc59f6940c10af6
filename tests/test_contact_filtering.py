"""Lazy sensors and explicit contact pairs change nothing, bit for bit.

The eager-sensor control step (pins colliding through MuJoCo's bounding-volume
trees, sensors computed in every physics step) is stepped side by side with today's
(sensors only before each read, ``ServoStepper.lazy_sensors``) and with the opt-in
``make_mjcf(spec, contact_pairs=True)`` (explicit pin-piece ``<pair>``s) through the
same episodes; after every control step their states, sensor readings and contacts
must be equal exactly. The opt-in ``board_body=False`` (the board in the world body) is
not bit-identical; its deviation is bounded here too.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from tolins import CircularSocket, PolygonSocket, make_mjcf, sample_defects
from tolins.geometry.workspace import POSE_HIGH, POSE_LOW, pin_axes
from tolins.mjcf.contacts import pin_reach_boxes
from tolins.paper import A_MAX
from tolins.physics.servo import ServoStepper
from tolins.policies.experts import EfficientExpert, SafeExpert

SUBSTEPS = 250
DOWN = np.array([0.0, 0.0, 0.0, -A_MAX[3]])


def _stepper(
    spec, contact_pairs: bool, lazy_sensors: bool, board_body: bool = True
) -> ServoStepper:
    xml = make_mjcf(spec, contact_pairs=contact_pairs, board_body=board_body)
    model = mujoco.MjModel.from_xml_string(xml)
    stepper = ServoStepper(model, mujoco.MjData(model))
    stepper.lazy_sensors = lazy_sensors
    return stepper


def _snapshot(stepper: ServoStepper) -> dict[str, np.ndarray]:
    d = stepper.data
    contacts = d.contact
    return {
        "qpos": d.qpos.copy(),
        "qvel": d.qvel.copy(),
        "act": d.act.copy(),
        "sensordata": d.sensordata.copy(),
        "geom": contacts.geom.copy(),
        "pos": contacts.pos.copy(),
        "frame": contacts.frame.copy(),
        "dist": contacts.dist.copy(),
        "efc_force": d.efc_force.copy(),
    }


def _assert_same(old: ServoStepper, new: ServoStepper, where: str) -> None:
    a, b = _snapshot(old), _snapshot(new)
    for key in a:
        assert a[key].shape == b[key].shape, f"{where}: {key} shapes differ"
        assert np.array_equal(a[key], b[key]), f"{where}: {key} differs"


def _episode(spec, pose, policy, steps: int) -> tuple[int, float]:
    """Step the old control step, lazy sensors, and lazy sensors with contact pairs side
    by side; the most contacts seen at the end of a control step, the lowest tip (mm)."""
    old = _stepper(spec, contact_pairs=False, lazy_sensors=False)
    news = [_stepper(spec, pairs, lazy_sensors=True) for pairs in (False, True)]
    pose = np.asarray(pose, dtype=float)
    for stepper in (old, *news):
        stepper.reset(pose)
    for new in news:
        _assert_same(old, new, "reset")
    most, lowest = 0, np.inf
    for k in range(steps):
        action = policy(old.state(0.0).pose)
        a = old.step(action, SUBSTEPS)
        for new in news:
            b = new.step(action, SUBSTEPS)
            assert np.array_equal(a.pose, b.pose) and np.array_equal(a.wrench, b.wrench)
            assert a.peak_force == b.peak_force and a.error == b.error
            _assert_same(old, new, f"control step {k}")
        most, lowest = max(most, old.data.ncon), min(lowest, a.pose[3])
    return most, lowest


def _random_policy(seed: int):
    rng = np.random.default_rng(seed)
    return lambda pose: rng.uniform(-A_MAX, A_MAX)


SOCKETS = [
    pytest.param(CircularSocket(2, 2), id="2x2"),
    pytest.param(CircularSocket(2, 8), id="2x8"),
    pytest.param(sample_defects(CircularSocket(2, 4), 0.1, rng=2020), id="bent-2x4"),
    pytest.param(
        CircularSocket(
            2, 4, pin_pitch_scale=(1.01, 1.0), pin_burrs=(0.05,) + (0.0,) * 7, blocked_holes=(5,)
        ),
        id="pitch-burr-plug-2x4",
    ),
    pytest.param(PolygonSocket(4, 1.5, 1.65), id="square"),
    pytest.param(PolygonSocket(6, 1.2, 1.26), id="hexagon"),
    pytest.param(PolygonSocket(3, 1.5, 1.65), id="triangle"),
]


@pytest.mark.parametrize("spec", SOCKETS)
def test_random_actions_near_the_board_give_the_same_trajectory(spec) -> None:
    # Random actions from just above the board, off the holes: free flight, blocks,
    # slides and (for the polygons' wide clearance) insertions.
    assert _episode(spec, [0.15, -0.1, 0.02, 0.3], _random_policy(7), 10)[0] > 0


@pytest.mark.parametrize("spec", SOCKETS)
@pytest.mark.parametrize("expert", [SafeExpert(), EfficientExpert()], ids=["safe", "efficient"])
def test_expert_episodes_give_the_same_trajectory(spec, expert) -> None:
    # From the air 1.5 mm off the goal: free flight, the board (efficient expert), the
    # holes' walls and the insertion (the bent pins stay on the board at this goal).
    most, lowest = _episode(spec, [1.2, -0.9, 0.05, 2.0], expert, 14)
    assert lowest < -1.0 or (most > 0 and spec.is_defective)


def test_pins_a_pitch_away_and_pins_pressed_on_the_walls_give_the_same_trajectory() -> None:
    # Shifted by one column pitch, seven pins land on their neighbours' holes and the last
    # on the board.
    spec = CircularSocket(2, 8)
    assert _episode(spec, [spec.col_pitch, 0.0, 0.0, 0.05], lambda pose: DOWN, 6)[0] > 0
    # Pressed sideways against the walls while going in to the servo's lower end.
    press = np.array([A_MAX[0], 0.0, 0.0, -A_MAX[3]])
    most, lowest = _episode(CircularSocket(2, 2), [0.1, 0.0, 0.0, 0.05], lambda pose: press, 9)
    assert most > 0 and lowest == pytest.approx(-4.0, abs=0.01)


def test_a_large_socket_at_the_edge_of_the_servo_range_gives_the_same_trajectory() -> None:
    # 2*20: the pairs leave out the pieces a pin cannot reach; turned and shifted to the
    # servo range's corner, pressed onto the board and slid.
    spec = CircularSocket(2, 20)
    slide = np.array([-A_MAX[0], A_MAX[1], -A_MAX[2], -A_MAX[3]])
    assert _episode(spec, [4.9, 4.9, 0.29, 0.05], lambda pose: slide, 3)[0] > 0


@pytest.mark.parametrize(
    "spec",
    [
        CircularSocket(2, 20),
        CircularSocket(3, 5, row_pitch=2.0),
        sample_defects(CircularSocket(2, 8), 0.1, rng=3),
        CircularSocket(2, 1, pin_pitch_scale=(1.0, 1.02), pin_burrs=(0.05, 0.0)),
        PolygonSocket(5, 1.5, 1.65),
    ],
    ids=["2x20", "3x5", "bent-2x8", "pitch-burr-2x1", "pentagon"],
)
def test_reach_boxes_hold_every_pin_over_the_servo_range(spec) -> None:
    rng = np.random.default_rng(0)
    corners = np.array(np.meshgrid(*zip(POSE_LOW[:3], POSE_HIGH[:3], strict=True), indexing="ij"))
    poses = np.concatenate(
        [corners.reshape(3, -1).T, rng.uniform(POSE_LOW[:3], POSE_HIGH[:3], (2000, 3))]
    )
    axes = pin_axes(spec, poses)  # (poses, pins, 2)
    circle = isinstance(spec, CircularSocket)
    radii = np.asarray(spec.pin_radii if circle else [spec.pin_reach])[:, None]
    boxes = pin_reach_boxes(spec)
    assert np.all(axes - radii >= boxes[:, 0]) and np.all(axes + radii <= boxes[:, 1])


def test_the_pairs_of_a_family_do_not_depend_on_bent_pins() -> None:
    # One layout for every workpiece of a family (the vector env's per-env models).
    nominal = CircularSocket(2, 8)
    bent = sample_defects(nominal, 0.1, rng=5)
    assert bent.is_defective

    def pairs(spec) -> list[tuple[int, int]]:
        model = mujoco.MjModel.from_xml_string(make_mjcf(spec, contact_pairs=True))
        return list(zip(model.pair_geom1.tolist(), model.pair_geom2.tolist(), strict=True))

    assert pairs(bent) == pairs(nominal)


def test_large_sockets_pair_each_pin_with_only_the_pieces_it_can_reach() -> None:
    model = mujoco.MjModel.from_xml_string(make_mjcf(CircularSocket(2, 20), contact_pairs=True))
    pieces = int(np.sum(model.geom_bodyid == model.body("board").id))
    assert 0 < model.npair < 0.5 * pieces * 40
    # No pin collides automatically; the carrier still does.
    pins = [model.geom(f"pin{i}").id for i in range(40)]
    assert not np.any(model.geom_contype[pins]) and not np.any(model.geom_conaffinity[pins])
    assert model.geom_contype[model.geom("carrier").id]


def test_lazy_sensors_leave_the_model_flags_as_they_were() -> None:
    stepper = _stepper(CircularSocket(2, 2), contact_pairs=False, lazy_sensors=True)
    flags = stepper.model.opt.disableflags
    stepper.reset(np.array([0.5, 0.0, 0.0, 0.05]))
    state = stepper.step(DOWN, SUBSTEPS)
    assert stepper.model.opt.disableflags == flags
    assert state.peak_force > 0 and state.wrench[3] > 0  # the sensors were read


@pytest.mark.parametrize("spec", [CircularSocket(2, 4), PolygonSocket(6, 1.2, 1.26)])
def test_contact_pairs_and_the_world_board_are_opt_in_and_deterministic(spec) -> None:
    assert make_mjcf(spec) == make_mjcf(spec, contact_pairs=False, board_body=True)
    assert "<pair " not in make_mjcf(spec) and '<body name="board">' in make_mjcf(spec)
    for options in ({"contact_pairs": True}, {"board_body": False}):
        assert make_mjcf(spec, **options) == make_mjcf(spec, **options)
    assert '<body name="board">' not in make_mjcf(spec, board_body=False)


@pytest.mark.parametrize("spec", [CircularSocket(2, 8), PolygonSocket(4, 1.5, 1.65)])
def test_the_world_board_moves_expert_episodes_by_rounding_only(spec) -> None:
    # Down to the servo's lower end, where the carrier rests on the board at zero distance.
    old = _stepper(spec, contact_pairs=False, lazy_sensors=True)
    new = _stepper(spec, contact_pairs=False, lazy_sensors=True, board_body=False)
    pose = np.array([1.2, -0.9, 0.05, 2.0])
    old.reset(pose), new.reset(pose)
    expert = SafeExpert()
    for _ in range(14):
        action = expert(old.state(0.0).pose)
        a, b = old.step(action, SUBSTEPS), new.step(action, SUBSTEPS)
        np.testing.assert_allclose(b.pose, a.pose, rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.wrench, a.wrench, rtol=0, atol=1e-9)
    assert a.pose[3] == pytest.approx(-4.0, abs=0.01)
