"""The benchmark cannot be scored without inserting: blind actions, bad poses and settings,
steps after the end."""

from __future__ import annotations

import copy
import itertools
import pickle
from concurrent.futures import ThreadPoolExecutor

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import tolins
from tolins import dmc
from tolins.envs import InsertionEnv
from tolins.envs.tasks import TASKS
from tolins.geometry.workspace import PIN_LENGTH, in_holes, pin_axes, reach
from tolins.mjcf import make_mjcf
from tolins.paper import A_MAX, CONTROL_DT
from tolins.physics.mujoco import MujocoBackend

BACKENDS = ["mujoco", "kinematic"]
#: A handful is enough: held for a whole episode, each corner of the action box drives the
#: workpiece to the same corner of the servo range from any start, 7 mm from the holes.
SEEDS = range(10000, 10005)
#: Every corner of the action box.
CORNERS = [np.array(c) * A_MAX for c in itertools.product((-1.0, 1.0), repeat=4)]
DIVE = np.array([2.5, 0.0, 0.0, -2.5])


def _gym_returns(env_id: str, backend: str, action: np.ndarray, seeds=SEEDS) -> list:
    env = gym.make(env_id, backend=backend)
    out = []
    for seed in seeds:
        env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            _, reward, terminated, truncated, info = env.step(action)
            total += reward
            done = terminated or truncated
        out.append((total, info["success"]))
    return out


def _dmc_returns(domain: str, action: np.ndarray, seeds=SEEDS) -> list:
    out = []
    for seed in seeds:
        env = dmc.load(domain, "insert", task_kwargs={"random": seed})
        timestep, total = env.reset(), 0.0
        while not timestep.last():
            timestep = env.step(action)
            total += timestep.reward
        out.append((total, env.task.last_score.success))
    return out


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("task", TASKS, ids=lambda t: t.name)
def test_the_off_board_dive_scores_nothing(task, backend: str) -> None:
    """The reported hack: full speed sideways and down flew off the board and 'succeeded'."""
    results = _gym_returns(task.gym_id, backend, DIVE)
    assert not any(success for _, success in results)
    assert max(total for total, _ in results) <= 0.0


def test_the_off_board_dive_scores_nothing_in_dm_control() -> None:
    for domain in ("circle2x2", "square", "circle2x1_defective"):
        results = _dmc_returns(domain, DIVE)
        assert not any(success for _, success in results)
        assert max(total for total, _ in results) <= 0.0


@pytest.mark.slow
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("env_id", ["tolins/Circle2x2-v2", "tolins/Square-v2"])
def test_no_blind_open_loop_action_scores(env_id: str, backend: str) -> None:
    """Every corner of the action box held for a whole episode, 5 seeds: no success, reward ≤ 0.
    (The scoring is the task rules', the same for every physics version.)"""
    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda a: _gym_returns(env_id, backend, a), CORNERS))
    for corner, episodes in zip(CORNERS, results, strict=True):
        assert not any(s for _, s in episodes), corner
        assert max(total for total, _ in episodes) <= 0.0, corner


@pytest.mark.slow
def test_no_blind_open_loop_action_scores_in_dm_control() -> None:
    """The corners in dm_control's task (the gym env's rules, tests/test_dmc.py replays its
    episodes): five seeds each."""
    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda a: _dmc_returns("circle2x2", a), CORNERS))
    for corner, episodes in zip(CORNERS, results, strict=True):
        assert not any(s for _, s in episodes), corner
        assert max(total for total, _ in episodes) <= 0.0, corner


# --- the workspace --------------------------------------------------------------------------


@pytest.mark.parametrize(
    "socket",
    [
        *(t.socket for t in TASKS),
        tolins.CircularSocket(2, 20),
        tolins.CircularSocket(2, 1, pin_offsets=[[2.0, -2.0], [-2.0, 2.0]]),
        tolins.PolygonSocket(3, 2.0, 2.2),
    ],
    ids=repr,
)
def test_the_board_covers_every_pin_anywhere_in_the_servo_range(socket) -> None:
    """Corners of the joint ranges, pins at their farthest: every pin over a board piece."""
    model = mujoco.MjModel.from_xml_string(make_mjcf(socket))
    boxes = [g for g in range(model.ngeom) if model.geom(g).name.startswith("board_box")]
    lo = np.min([model.geom_pos[g][:2] - model.geom_size[g][:2] for g in boxes], axis=0)
    hi = np.max([model.geom_pos[g][:2] + model.geom_size[g][:2] for g in boxes], axis=0)
    assert np.all(hi >= reach(socket)) and np.all(-lo >= reach(socket))
    ranges = model.jnt_range[[model.joint(j).id for j in ("x", "y", "theta")]]
    corners = np.array(list(itertools.product(*ranges)))
    axes = pin_axes(socket, corners)
    assert np.all(np.abs(axes) + socket.pin_reach <= reach(socket) + 1e-9)


def test_pushing_on_after_insertion_stops_at_the_carrier() -> None:
    """The carrier plate collides with the board: the workpiece cannot sink through it."""
    backend = MujocoBackend(tolins.CircularSocket(2, 2), CONTROL_DT)
    backend.reset(np.array([0.0, 0.0, 0.0, -1.0]))
    for _ in range(20):
        state = backend.step(np.array([0.0, 0.0, 0.0, -A_MAX[3]]))
    assert -PIN_LENGTH - 0.01 <= state.pose[3] <= -PIN_LENGTH + 0.01
    assert state.error is None


def test_sliding_past_the_servo_range_stops_at_its_edge_on_both_backends() -> None:
    for backend in BACKENDS:
        env = InsertionEnv(tolins.CircularSocket(2, 2), backend=backend, measurement_noise=0)
        env.reset(seed=0, options={"pose": [4.0, 0.0, 0.0, 10.0]})
        for _ in range(4):
            *_, info = env.step([A_MAX[0], 0.0, 0.0, 0.0])
        assert info["pose"][0] == pytest.approx(5.0, abs=1e-3), backend


def test_success_needs_every_pin_in_its_own_hole() -> None:
    socket = tolins.CircularSocket(2, 2)
    assert in_holes(socket, [0.1, 0.0, 0.0, -1.0], 1.0)
    assert not in_holes(socket, [0.1, 0.0, 0.0, -0.9], 1.0)  # not deep enough
    assert not in_holes(socket, [socket.col_pitch, 0.0, 0.0, -1.0], 1.0)  # next holes over
    assert not in_holes(socket, [4.9, 0.0, 0.0, -2.0], 1.0)  # below z, beside the holes
    bent = tolins.CircularSocket(2, 1, pin_offsets=[[0.6, 0.0], [0.0, 0.0]])
    assert not in_holes(bent, [0.0, 0.0, 0.0, -1.0], 1.0)  # the bent pin's axis is beside
    assert in_holes(bent, [-0.3, 0.0, 0.0, -1.0], 1.0)


# --- reset and settings validation -----------------------------------------------------------


def _make_both(**kwargs):
    return [InsertionEnv(tolins.CircularSocket(2, 2), backend=b, **kwargs) for b in BACKENDS]


@pytest.mark.parametrize(
    ("pose", "match"),
    [
        ([0.7, 0.0, 0.0, -2.0], "inside the board"),
        ([2000.0, 0.0, 0.0, 5.0], "beyond the servo range"),
        ([0.0, -5.5, 0.0, 5.0], "beyond the servo range"),
        ([0.0, 0.0, 0.5, 5.0], "beyond the servo range"),
        ([0.0, 0.0, 0.0, 50.0], "beyond the servo range"),
        ([0.0, 0.0, 0.0, -5.0], "beyond the servo range"),
        ([0.0, 0.0, np.nan, 1.0], "NaN"),
        ([0.0, 0.0, 1.0], "shape"),
    ],
)
def test_bad_reset_poses_raise_the_same_error_on_both_backends_and_dm_control(
    pose, match: str
) -> None:
    messages = set()
    for env in _make_both():
        with pytest.raises(ValueError, match=match) as error:
            env.reset(seed=0, options={"pose": pose})
        messages.add(str(error.value))
    assert len(messages) == 1 and "options['pose']" in messages.pop()
    with pytest.raises(ValueError, match=match):
        dmc.load("circle2x2", "insert", task_kwargs={"pose": pose}).reset()


@pytest.mark.parametrize("goal", [[2.5, 0.0, 0.0], [0.0, 0.0, 0.2], [np.inf, 0.0, 0.0]])
def test_goals_beyond_the_allowed_range_raise(goal) -> None:
    for env in _make_both():
        with pytest.raises(ValueError, match="goal"):
            env.reset(seed=0, options={"goal": goal})
    with pytest.raises(ValueError, match="goal"):
        dmc.load("circle2x2", "insert", task_kwargs={"goal": goal})


def test_a_partly_inserted_pose_is_allowed() -> None:
    for env in _make_both():
        _, info = env.reset(seed=0, options={"pose": [0.1, 0.0, 0.0, -0.5]})
        assert info["pose"][3] == pytest.approx(-0.5, abs=1e-6)


@pytest.mark.parametrize("control_dt", [np.nan, np.inf, 0.0, -0.25, 1e6, 0.2505, "fast"])
def test_control_dt_is_validated_alike_on_both_backends_and_dm_control(control_dt) -> None:
    messages = set()
    for backend in BACKENDS:
        with pytest.raises(ValueError, match="control_dt") as error:
            InsertionEnv(tolins.CircularSocket(2, 2), backend=backend, control_dt=control_dt)
        messages.add(str(error.value))
    assert len(messages) == 1
    with pytest.raises(ValueError, match="control_dt"):
        dmc.load("circle2x2", "insert", environment_kwargs={"control_timestep": control_dt})


def test_a_longer_whole_control_dt_is_accepted_on_both_backends() -> None:
    for env in _make_both(control_dt=0.5):
        env.reset(seed=0)
        assert env.step(np.zeros(4))[4]["step"] == 1


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: tolins.CircularSocket(2, 1, pin_offsets=[[5, 0], [5, 0]]), "pin_offsets"),
        (lambda: tolins.CircularSocket(1, 2, pin_offsets=[[0, 2.5], [0, 0]]), "pin_offsets"),
        (lambda: tolins.CircularSocket(2, 10**6), "at most 400 pins"),
        (lambda: tolins.CircularSocket(21, 20), "at most 400 pins"),
        (lambda: tolins.PolygonSocket(10**6, 1.5, 1.65), "sides"),
        (lambda: tolins.PolygonSocket(65, 1.5, 1.65), "sides"),
        (lambda: tolins.PolygonSocket(4, 1e6, 1e6 + 0.1), "every hole within 100 mm"),
        (lambda: tolins.PolygonSocket(4, 100.0, 100.1), "every hole within 100 mm"),
        (lambda: tolins.CircularSocket(2, 1, row_pitch=1e6), "every hole within 100 mm"),
        (lambda: tolins.CircularSocket(1, 1, 150.0, 150.2), "every hole within 100 mm"),
        (lambda: tolins.CircularSocket(20, 20, 0.3, 0.5, 10.6, 10.0), "within 100 mm"),
        (
            lambda: gym.make(
                "tolins/Insert-v2", socket=tolins.PolygonSocket(4, 1e4, 1e4 + 0.1), robot="panda"
            ),
            "every hole within 100 mm",
        ),
    ],
)
def test_socket_sizes_and_bends_are_bounded(make, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        make()


def test_the_largest_sockets_in_use_stay_valid() -> None:
    # A 20*20 socket at 10 mm pitch (tests/test_specs.py) reaches 95.5 mm.
    assert tolins.CircularSocket(20, 20, row_pitch=10.0, col_pitch=10.0).n_pins == 400
    assert tolins.PolygonSocket(4, 99.0, 100.0).hole_circumradius == 100.0


def test_an_initial_pose_distribution_beyond_the_servo_range_raises() -> None:
    wide = tolins.envs.InitialPoseDistribution(radius_max=4.0)
    with pytest.raises(ValueError, match="radius_max"):
        InsertionEnv(tolins.CircularSocket(2, 2), initial_pose=wide)


# --- the end of an episode is final ----------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
def test_stepping_after_success_or_the_horizon_raises_reset_needed(backend: str) -> None:
    env = InsertionEnv(tolins.CircularSocket(2, 2), backend=backend, measurement_noise=0)
    env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, 0.5]})
    terminated = False
    while not terminated:
        _, reward, terminated, truncated, _ = env.step([0.0, 0.0, 0.0, -A_MAX[3]])
    assert reward > 0
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(4))
    env.reset(seed=0)
    truncated = False
    while not truncated:
        *_, truncated, _ = env.step(np.zeros(4))
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(4))
    env.reset(seed=0)
    assert env.step(np.zeros(4))[4]["step"] == 1  # a reset starts over


def test_a_faulted_episode_stays_faulted_until_reset(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo logs the warning to ./MUJOCO_LOG.TXT
    env = InsertionEnv(tolins.CircularSocket(2, 2))
    env.reset(seed=0)
    env.backend.data.qpos[0] = np.nan
    _, reward, terminated, truncated, info = env.step(np.zeros(4))
    assert truncated and not terminated and reward == 0.0 and "BADQPOS" in info["error"]
    with pytest.raises(gym.error.ResetNeeded):
        env.step([0.0, 0.0, 0.0, -A_MAX[3]])
    env.reset(seed=0)
    assert "error" not in env.step(np.zeros(4))[4]


# --- copies ----------------------------------------------------------------------------------


def test_pickle_and_deepcopy_work_after_render() -> None:
    env = InsertionEnv(tolins.CircularSocket(2, 2), render_mode="rgb_array")
    env.reset(seed=0)
    try:
        env.render()
    except Exception as error:  # no OpenGL (EGL) on this machine
        pytest.skip(f"headless OpenGL unavailable: {error}")
    assert env._renderer is not None
    for copied in (pickle.loads(pickle.dumps(env)), copy.deepcopy(env)):
        action = [0.5, 0.0, 0.0, -1.0]
        assert np.array_equal(copied.step(action)[0], copy.deepcopy(env).step(action)[0])
        assert copied.render().shape == (480, 640, 3)
        copied.close()
    env.close()
