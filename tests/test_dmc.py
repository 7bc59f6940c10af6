"""The dm_control suite: dm_env conformance, determinism, and the gym env's physics."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from absl.testing import absltest
from dm_env import StepType, test_utils

import tolins
from tolins import dmc
from tolins.envs import TASKS, InsertionEnv
from tolins.envs.tasks import (
    DELICATE_ROBOT_TASKS,
    DELICATE_TASKS,
    GRADE_TASKS,
    PRESETS,
    ROBOT_TASKS,
)
from tolins.paper import A_MAX, HORIZON, SUCCESS_REWARD
from tolins.physics.servo import ServoStepper

DOWN = np.array([0.0, 0.0, 0.0, -A_MAX[3]])
TASK_BY_DOMAIN = {task.domain: task for task in PRESETS}


def _flat(observation) -> np.ndarray:
    return np.concatenate(list(observation.values()))


def _conformance_case(domain: str, task: str) -> type:
    """An ``EnvironmentTestMixin`` test case of one suite task; 4-step episodes keep it fast."""

    class Case(test_utils.EnvironmentTestMixin, absltest.TestCase):
        def make_object_under_test(self):
            return dmc.load(domain, task, task_kwargs={"random": 0, "horizon": 4})

        def make_action_sequence(self):
            for k in range(10):  # crosses two episode ends
                yield DOWN if k % 2 else self.make_action()

    Case.__name__ = Case.__qualname__ = f"TestConformance_{domain}_{task}"
    return Case


#: The Panda's domains tested for conformance (each compiles the arm's world, ~0.5 s): one
#: circle, the defective one (its physics rebuilt per episode), a polygon, and one with
#: delicate pins.
PANDA_CONFORMANCE = (
    "circle2x2_panda",
    "circle2x1_defective_panda",
    "square_panda",
    "circle2x1_delicate_panda",
)
#: The delicate domains tested for conformance: one stands for them (same stepper).
DELICATE_CONFORMANCE = ("circle2x2_delicate",)
for _domain, _task in dmc.ALL_TASKS:
    if _domain.endswith("_panda") and _domain not in PANDA_CONFORMANCE:
        continue
    if _domain.endswith("_delicate") and _domain not in DELICATE_CONFORMANCE:
        continue
    _case = _conformance_case(_domain, _task)
    globals()[_case.__name__] = _case
del _case, _domain, _task


def test_suite_is_built_from_the_task_table() -> None:
    everything = PRESETS + ROBOT_TASKS + DELICATE_TASKS + DELICATE_ROBOT_TASKS
    assert tuple((task.domain, "insert") for task in everything) == dmc.ALL_TASKS
    robot = ROBOT_TASKS + DELICATE_ROBOT_TASKS
    assert tuple((task.domain, "insert") for task in robot) == dmc.ROBOT
    delicate = DELICATE_TASKS + DELICATE_ROBOT_TASKS
    assert tuple((task.domain, "insert") for task in delicate) == dmc.DELICATE
    assert set(PANDA_CONFORMANCE) <= {domain for domain, _ in dmc.ROBOT}
    assert [domain for domain, _ in dmc.PAPER] == [
        "circle2x1",
        "circle2x2",
        "circle2x4",
        "circle2x8",
        "circle2x1_defective",
        "square",
        "pentagon",
        "hexagon",
    ]
    assert tuple((task.domain, "insert") for task in TASKS) == dmc.PAPER
    assert tuple((task.domain, "insert") for task in GRADE_TASKS) == dmc.GRADE
    assert ("circle2x2_fit50", "insert") in dmc.GRADE
    assert dmc.DEFECTIVE == (
        ("circle2x1_defective", "insert"),
        ("circle2x1_defective_panda", "insert"),
    )
    assert {d for d, _ in dmc.CIRCLE} == {t.domain for t in everything if "circle" in t.tags}
    polygons = [(d, t) for d, t in dmc.POLYGON if (d, t) in dmc.PAPER]
    assert polygons == [("square", "insert"), ("pentagon", "insert"), ("hexagon", "insert")]
    assert dmc.SUITES["square"].tagged("polygon", "paper").keys() == {"insert"}


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (("circle2x3", "insert"), "domain_name='circle2x3' is unknown; allowed: .*'hexagon'"),
        (("square", "swingup"), "task_name='swingup' is unknown.*allowed: \\['insert'\\]"),
        (("square", "insert", {"seed": 0}), "task_kwargs \\['seed'\\] are unknown.*'random'"),
        (("square", "insert", {"horizon": 0}), "horizon"),
        (("square", "insert", {"defect_sigma": 0.1}), "defect_sigma"),
        (("square", "insert", {"random": "x"}), "random"),
        (("square", "insert", {"defects": ("burr", 0.05)}), "defects.*CircularSocket"),
        (("circle2x2", "insert", {"defects": ("cracked", 0.1)}), "unknown.*pitch, burr"),
        (("circle2x2", "insert", {"defects": ("blocked", 0.1)}), "None"),
    ],
)
def test_unknown_names_and_bad_kwargs_raise(args: tuple, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        dmc.load(*args)


def _episode_observations(domain: str, seed: int, steps: int) -> list[np.ndarray]:
    env = dmc.load(domain, "insert", task_kwargs={"random": seed})
    rng = np.random.default_rng(1)
    observations = []
    for _ in range(2):
        observations.append(_flat(env.reset().observation))
        for _ in range(steps):
            observations.append(_flat(env.step(rng.uniform(-A_MAX, A_MAX)).observation))
    return observations


@pytest.mark.parametrize("domain", ["circle2x2", "circle2x1_defective"])
def test_same_seed_gives_bit_identical_observations(domain: str) -> None:
    first = _episode_observations(domain, seed=7, steps=10)
    second = _episode_observations(domain, seed=7, steps=10)
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
    assert not np.array_equal(first[0], _episode_observations(domain, seed=8, steps=0)[0])


# The grades' 2*8 domains at 0.25 ms steps would take minutes; two grades stand for them.
REPLAYED = [*dmc.PAPER, ("circle2x2_fit20", "insert"), ("square_fit50", "insert")]


@pytest.mark.parametrize(("domain", "task"), REPLAYED)
def test_an_int_seed_replays_the_gym_envs_episodes(domain: str, task: str) -> None:
    """Same seed, same actions: the same observations, rewards and ends, noise included."""
    gym_env = InsertionEnv(**TASK_BY_DOMAIN[domain].env_kwargs)
    env = dmc.load(domain, task, task_kwargs={"random": 3})
    rng = np.random.default_rng(0)
    for episode in range(2):
        observation, _ = gym_env.reset(seed=3 if episode == 0 else None)
        assert np.array_equal(_flat(env.reset().observation), observation)
        info = _same_episode(gym_env, env, rng)
    assert info["n_collisions"] > 0  # the actions did reach the board


@pytest.mark.parametrize(
    ("socket", "domain"),
    [(tolins.CircularSocket(2, 2), "circle2x2"), (tolins.PolygonSocket(6, 1.2, 1.26), "hexagon")],
)
def test_same_pose_and_actions_give_the_gym_envs_physical_outcome(socket, domain: str) -> None:
    pose = [0.3, -0.1, 0.02, 0.6]  # outside the clearance: pushes, slides, collides
    gym_env = InsertionEnv(socket, measurement_noise=0)
    gym_env.reset(seed=0, options={"pose": pose})
    env = dmc.load(domain, "insert", task_kwargs={"measurement_noise": 0, "pose": pose})
    timestep = env.reset()
    assert np.array_equal(env.physics.pose(), pose)
    assert np.array_equal(timestep.observation["pose_error"], pose[:3])
    actions = [DOWN] * 4 + [[1.0, 0.5, -0.05, -1.0]] * 6 + [[-A_MAX[0], 0, 0, -1.0]] * 8
    for action in actions:
        _, reward, terminated, truncated, info = gym_env.step(action)
        timestep = env.step(action)
        assert timestep.last() == (terminated or truncated)
        assert np.array_equal(env.physics.pose(), info["pose"])
        assert np.array_equal(timestep.observation["wrench"], info["wrench"])
        assert env.task.last_score.collision == info["collision"]
        assert env.task.score.collisions == info["n_collisions"]
        assert timestep.reward == reward
        if timestep.last():
            break
    assert info["n_collisions"] >= 8


def test_success_ends_the_episode_with_the_papers_reward_and_discount_0() -> None:
    env = dmc.load("circle2x2", "insert", task_kwargs={"pose": [0, 0, 0, 1.0], "random": 0})
    env.reset()
    steps = [env.step(DOWN) for _ in range(4)]  # 1 mm above + 1 mm deep at 0.625 mm/step
    assert [s.step_type for s in steps] == [StepType.MID] * 3 + [StepType.LAST]
    assert steps[-1].discount == 0.0
    assert steps[-1].reward == pytest.approx(SUCCESS_REWARD * (1 - 4 / HORIZON))
    assert env.task.last_score.success and env.task.score.collisions == 0
    assert env.step(DOWN).first()


def test_horizon_ends_the_episode_with_discount_1() -> None:
    env = dmc.load("square", "insert", task_kwargs={"random": 0})
    assert env.control_timestep() == pytest.approx(0.25)
    env.reset()
    steps = [env.step(np.zeros(4)) for _ in range(HORIZON)]
    assert all(s.mid() and s.reward == 0.0 for s in steps[:-1])
    assert steps[-1].last() and steps[-1].discount == 1.0


@pytest.mark.parametrize("action", [[0.0, np.nan, 0.0, 0.0], [1.0, 2.0, 3.0]])
def test_bad_action_raises(action: list[float]) -> None:
    env = dmc.load("square", "insert")
    env.reset()
    with pytest.raises(ValueError, match="action"):
        env.step(action)


def test_out_of_range_actions_are_clipped() -> None:
    envs = [dmc.load("circle2x1", "insert", task_kwargs={"random": 1}) for _ in range(2)]
    for env in envs:
        env.reset()
    sign = np.array([1, -1, 1, -1])
    big, limit = envs[0].step(10 * A_MAX * sign), envs[1].step(A_MAX * sign)
    assert np.array_equal(_flat(big.observation), _flat(limit.observation))


@pytest.mark.parametrize(
    "defects", [("pitch", 0.005), ("burr", 0.05), ("short", 0.3), ("blocked", None)]
)
def test_defects_draw_the_gym_envs_workpiece_and_replay_its_episode(defects) -> None:
    """``defects=(kind, sigma)``: the same seed draws the gym env's defective workpiece,
    and the same actions give its observations, rewards, poses and ends."""
    gym_env = InsertionEnv(**TASK_BY_DOMAIN["circle2x2"].env_kwargs, defects=defects)
    env = dmc.load("circle2x2", "insert", task_kwargs={"random": 5, "defects": defects})
    rng = np.random.default_rng(0)
    for episode in range(2):
        observation, _ = gym_env.reset(seed=5 if episode == 0 else None)
        assert np.array_equal(_flat(env.reset().observation), observation)
        assert env.task.socket == gym_env.socket and env.task.socket.is_defective
        pins = env.physics.named.model.geom_pos["pin0"]
        assert np.array_equal(pins, gym_env.unwrapped.backend.model.geom("pin0").pos)
        _same_episode(gym_env, env, rng)
    with pytest.raises(ValueError, match=r"pose=.*\(defects\).*z ≥ 0"):
        dmc.load("circle2x2", "insert", task_kwargs={"pose": [0, 0, 0, -0.5], "defects": defects})


def test_defective_domain_rebuilds_the_physics_with_a_new_workpiece() -> None:
    env = dmc.load("circle2x1_defective", "insert", task_kwargs={"random": 0})
    env.reset()
    first, first_pins = env.task.socket, env.physics.named.model.geom_pos["pin0"].copy()
    env.reset()
    assert first.is_defective and env.task.socket.is_defective and first != env.task.socket
    assert not np.array_equal(env.physics.named.model.geom_pos["pin0"], first_pins)
    assert isinstance(env.physics.stepper, ServoStepper)
    assert env.physics.stepper.model is env.physics.model.ptr


def test_a_fixed_pose_in_the_holes_is_refused_with_bent_pins() -> None:
    """A bent workpiece may not fit a pose below the top: such resets failed at random."""
    with pytest.raises(ValueError, match=r"pose=.*defect_sigma.*z ≥ 0"):
        dmc.load("circle2x1_defective", "insert", task_kwargs={"pose": [0, 0, 0, -0.5]})
    env = dmc.load("circle2x1", "insert", task_kwargs={"pose": [0, 0, 0, -0.5]})
    assert env.reset().observation["height"][0] == pytest.approx(-0.5, abs=0.5)


def _physics_state(env) -> dict[str, np.ndarray]:
    data = env.physics.data
    return {name: getattr(data, name).copy() for name in ("qpos", "qvel", "act", "sensordata")}


def test_a_failed_reset_changes_nothing_and_steps_raise_until_a_reset_succeeds() -> None:
    """A pose out of the servo range set on the task: the reset used to redraw the
    workpiece and rebuild the physics first, and the next step ran on that."""

    def after_three_steps():
        env = dmc.load("circle2x1_defective", "insert", task_kwargs={"random": 0})
        env.reset()
        for _ in range(3):
            env.step(DOWN)
        return env

    env, reference = after_three_steps(), after_three_steps()
    socket, model = env.task.socket, env.physics.model.ptr
    physics, random = _physics_state(env), env.task.random.bit_generator.state
    env.task.pose = [99.0, 0.0, 0.0, 10.0]
    with pytest.raises(ValueError, match="pose"):
        env.reset()
    assert env.task.socket is socket and env.physics.model.ptr is model
    assert env.task.random.bit_generator.state == random
    for name, value in _physics_state(env).items():
        assert np.array_equal(value, physics[name]), name
    for _ in range(2):
        with pytest.raises(gym.error.ResetNeeded):
            env.step(DOWN)
    env.task.pose = None
    # The failed reset consumed nothing: the next episode is the reference's next one.
    assert np.array_equal(_flat(env.reset().observation), _flat(reference.reset().observation))
    assert env.task.socket == reference.task.socket
    for _ in range(3):
        assert np.array_equal(
            _flat(env.step(DOWN).observation), _flat(reference.step(DOWN).observation)
        )


def test_named_indexing_and_the_shared_stepper() -> None:
    env = dmc.load("circle2x2", "insert", task_kwargs={"pose": [0.5, -0.25, 0.01, 3.0]})
    env.reset()
    assert env.physics.named.data.qpos["x"][0] == 0.5
    assert env.physics.named.data.qpos["theta"][0] == 0.01
    assert env.physics.named.data.qpos["z"][0] == 3.0
    assert isinstance(env.physics.stepper, ServoStepper)


def test_simulator_fault_ends_the_episode_with_the_previous_observation(
    tmp_path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo logs the warning to ./MUJOCO_LOG.TXT
    env = dmc.load("circle2x2", "insert", task_kwargs={"random": 0})
    observation = env.reset().observation
    env.physics.data.qvel[0] = np.nan
    timestep = env.step(np.zeros(4))
    assert timestep.last() and timestep.discount == 1.0 and timestep.reward == 0.0
    assert "BADQVEL" in env.task.error
    assert np.array_equal(_flat(timestep.observation), _flat(observation))
    assert env.step(np.zeros(4)).first()


def test_render_shows_the_parts() -> None:
    env = dmc.load("circle2x4", "insert", task_kwargs={"pose": [0.8, 0.5, 0.05, 1.0]})
    env.reset()
    try:
        image = env.physics.render(240, 320, camera_id="overview")
    except Exception as error:  # no OpenGL (EGL) on this machine
        pytest.skip(f"headless OpenGL unavailable: {error}")
    assert image.shape == (240, 320, 3) and image.dtype == np.uint8
    board_green = (image[..., 1] > image[..., 0] + 30) & (image[..., 1] > image[..., 2] + 30)
    pin_gold = (image[..., 0] > 150) & (image[..., 2] < 100)
    assert board_green.mean() > 0.1 and pin_gold.sum() > 50


def test_plain_import_of_tolins_does_not_load_dm_control() -> None:
    """Gym users do not pay for dm_control's import."""
    code = "import sys, tolins; print('dm_control' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"


def _same_episode(gym_env, env, rng: np.random.Generator) -> dict:
    """Step both (reset) envs with the same random descending actions until the episode
    ends, checking that each step agrees; the gym env's last info."""
    for _ in range(HORIZON):
        action = np.append(rng.uniform(-A_MAX[:3], A_MAX[:3]) * 0.3, -A_MAX[3])
        observation, reward, terminated, truncated, info = gym_env.step(action)
        timestep = env.step(action)
        assert np.array_equal(_flat(timestep.observation), observation)
        assert timestep.reward == reward
        assert np.array_equal(env.physics.pose(), info["pose"])
        assert timestep.last() == (terminated or truncated)
        if timestep.last():
            break
    assert env.task.score.collisions == info["n_collisions"]
    return info
