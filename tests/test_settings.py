"""Every setting the env accepts works; every one it cannot honour is refused, naming it.

Covers "every accepted setting works" (control_dt on MuJoCo, success_depth,
defect_sigma, non-numbers in distributions, noise and actions, a property-based test over
``gym.make`` keywords, sockets, reset options and actions), one signature for every API
(each field of ``TaskSettings`` taken by the gym env, the vector env and dm_control with
the same default), bit-identical copies of a MuJoCo env, and renderers closed at exit.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
import pickle
import subprocess
import sys
import textwrap

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, event, given, settings
from hypothesis import strategies as st

import tolins
from tolins import dmc
from tolins.envs.initial_pose import InitialPoseDistribution
from tolins.envs.insertion_env import ENV_KEYWORDS, InsertionEnv
from tolins.envs.task_settings import MAX_NOISE_STD, TASK_KEYWORDS, TaskSettings
from tolins.envs.tasks import DEFECT_SIGMA
from tolins.envs.vector import VECTOR_KEYWORDS, InsertionVectorEnv
from tolins.geometry.defects import (
    MIN_VALID_SHARE,
    max_defect_sigma,
    sample_defects,
    valid_share,
)
from tolins.geometry.specs import CircularSocket, PolygonSocket
from tolins.paper import A_MAX
from tolins.physics.mujoco import MujocoBackend
from tolins.physics.versions import VERSIONS, physics_version

DOWN = np.array([0.0, 0.0, 0.0, -A_MAX[3]])
GENERIC = "tolins/Insert-v1"


def _make(**kwargs) -> gym.Env:
    kwargs.setdefault("socket", CircularSocket(2, 2))
    return gym.make(GENERIC, **kwargs)


# --- control_dt ------------------------------------------------------------------------


@pytest.mark.parametrize("control_dt", [0.002, 0.003, 0.007, 0.252, 1.0])
def test_every_allowed_control_dt_runs_on_mujoco(control_dt: float) -> None:
    """Any whole number of physics steps from two on (it failed unless five divided it)."""
    env = _make(control_dt=control_dt, measurement_noise=0.0)
    env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, 0.002]})
    backend = env.unwrapped.backend
    steps = round(control_dt / 0.001)
    assert backend.substeps == steps and backend.stepper.checks == min(5, steps)
    heights = []
    for _ in range(3):
        observation, reward, terminated, *_ = env.step(DOWN)
        assert np.isfinite(observation).all() and np.isfinite(reward)
        heights.append(observation[3])
        if terminated:
            break
    # Pushed down over its holes, the workpiece goes down into them.
    assert np.all(np.diff([0.002, *heights]) < 0)


def test_a_control_dt_of_one_physics_step_is_refused_everywhere() -> None:
    """Re-anchored at every control step, a servo pushes from its second physics step on:
    in one the workpiece never moves (measured: z stayed 0.002 mm commanded down)."""
    for backend in ("mujoco", "kinematic"):
        with pytest.raises(ValueError, match=r"control_dt=0.001 .*\[0.002, 1.0\] s"):
            _make(control_dt=0.001, backend=backend)
    with pytest.raises(ValueError, match=r"control_dt=0\.001"):
        dmc.load("circle2x2", "insert", environment_kwargs={"control_timestep": 0.001})


def test_the_default_control_step_reads_the_force_five_times_evenly() -> None:
    """The 250-step default: five reads 50 steps apart, as an explicit 5 gives (bit for bit)."""
    socket = CircularSocket(2, 2)
    default, explicit = MujocoBackend(socket, 0.25), MujocoBackend(socket, 0.25, 5)
    assert default.substeps == 250 and default.stepper.checks == 5
    pose = [0.35, 0.0, 0.0, 0.4]  # lands on the board's top beside the holes
    assert np.array_equal(default.reset(pose).pose, explicit.reset(pose).pose)
    for velocity in (DOWN, DOWN, [1.0, 0.0, 0.0, -2.5]):
        a, b = default.step(velocity), explicit.step(velocity)
        assert np.array_equal(a.pose, b.pose) and np.array_equal(a.wrench, b.wrench)
        assert a.peak_force == b.peak_force
    assert a.peak_force > 1.0


def test_gym_and_dm_control_step_one_rule_at_an_uneven_control_dt() -> None:
    """252 physics steps: five reads after 51, 51, 50, 50, 50 steps in both APIs."""
    from tolins.dmc.physics import InsertionPhysics

    socket = CircularSocket(2, 2)
    backend, physics = MujocoBackend(socket, 0.252), InsertionPhysics.from_spec(socket)
    pose = [0.35, 0.0, 0.0, 0.4]
    backend.reset(pose)
    physics.set_pose(np.array(pose))
    for _ in range(3):
        a = backend.step(DOWN)
        physics.command(DOWN)
        physics.step(252)
        b = physics.last_state
        assert np.array_equal(a.pose, b.pose) and a.peak_force == b.peak_force
    assert a.peak_force > 1.0


@pytest.mark.parametrize("contact_checks", [0, 251, 2.5, True])
def test_explicit_contact_checks_out_of_range_are_refused(contact_checks) -> None:
    with pytest.raises(ValueError, match="contact_checks"):
        MujocoBackend(CircularSocket(2, 1), 0.25, contact_checks)


# --- success_depth, defect_sigma --------------------------------------------------------


@pytest.mark.parametrize("success_depth", [4.0, 4.5, 40.0])
def test_a_success_depth_the_carrier_does_not_allow_is_refused(success_depth: float) -> None:
    with pytest.raises(ValueError, match=r"success_depth.*allowed: 0 < success_depth < 4"):
        _make(success_depth=success_depth, backend="kinematic")


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_the_deepest_allowed_success_depth_is_reached(backend: str) -> None:
    env = _make(success_depth=3.99, backend=backend, measurement_noise=0.0)
    env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, 0.5]})
    for _ in range(10):
        _, reward, terminated, truncated, info = env.step(DOWN)
        if terminated or truncated:
            break
    assert terminated and info["success"] and reward > 0


def test_a_large_defect_sigma_never_fails_a_reset() -> None:
    """σ = 1 mm on a 2*1 socket: 9 % of single draws moved a pin out of its cell (the reset
    raised); now such a draw is re-drawn."""
    socket = CircularSocket(2, 1)
    assert 1 - valid_share(socket, 1.0) == pytest.approx(0.09, abs=0.005)
    task = TaskSettings(socket, defect_sigma=1.0)
    rng = np.random.default_rng(0)
    limit = socket.offset_limit
    for _ in range(500):
        assert np.all(np.abs(task.draw_socket(rng).offsets) <= limit)
    env = _make(socket=socket, defect_sigma=1.0, backend="kinematic")
    for seed in range(100):
        env.reset(seed=seed)
        assert np.isfinite(env.step(DOWN)[0]).all()


def test_a_redrawn_workpiece_is_the_first_valid_draw_of_the_sequence() -> None:
    socket = CircularSocket(2, 1)
    redrawn = 0
    for seed in range(300):
        rng = np.random.default_rng(seed)
        draws = 0
        while True:
            draws += 1
            offsets = rng.normal(0.0, 1.5, size=(2, 2))
            if np.all(np.abs(offsets) <= socket.offset_limit):
                break
        redrawn += draws > 1
        assert np.array_equal(sample_defects(socket, 1.5, seed).offsets, offsets)
    assert redrawn > 30  # the rule was exercised


def test_the_defective_presets_workpieces_are_the_single_draws_of_before() -> None:
    """Circle2x1Defective-v1 (σ = 0.12): every seed's workpiece is the one draw it was."""
    socket = CircularSocket(2, 1)
    for seed in range(2000):
        single = np.random.default_rng(seed).normal(0.0, DEFECT_SIGMA, size=(2, 2))
        assert np.array_equal(sample_defects(socket, DEFECT_SIGMA, seed).offsets, single)
    env = gym.make("tolins/Circle2x1Defective-v1", backend="kinematic")
    for seed in range(50):
        env.reset(seed=seed)
        single = np.random.default_rng(seed).normal(0.0, DEFECT_SIGMA, size=(2, 2))
        assert np.array_equal(env.unwrapped.socket.offsets, single)


@pytest.mark.parametrize(
    "socket", [CircularSocket(2, 1), CircularSocket(2, 2), CircularSocket(2, 8)]
)
def test_a_defect_sigma_with_fewer_than_half_valid_draws_is_refused(socket) -> None:
    largest = max_defect_sigma(socket)
    assert valid_share(socket, largest) == pytest.approx(MIN_VALID_SHARE)
    TaskSettings(socket, defect_sigma=largest)
    with pytest.raises(ValueError, match=r"defect_sigma=.*allowed: 0 < defect_sigma ≤ "):
        TaskSettings(socket, defect_sigma=largest * 1.01)


# --- one signature: TaskSettings -------------------------------------------------------

#: Every keyword of ``TaskSettings`` (its socket and its settings).
SETTING_FIELDS = tuple(f.name for f in dataclasses.fields(TaskSettings) if f.init)


def _same_settings(a: TaskSettings, b: TaskSettings) -> list[str]:
    """The fields (every one, the resolved ``version`` too) on which ``a`` and ``b`` differ."""
    differ = []
    for f in dataclasses.fields(TaskSettings):
        x, y = getattr(a, f.name), getattr(b, f.name)
        same = np.array_equal(x, y) if isinstance(x, np.ndarray) else x == y
        if not same or type(x) is not type(y):
            differ.append(f.name)
    return differ


def _settings_of_every_api(socket, **keywords) -> dict[str, TaskSettings]:
    """The settings each API builds of ``socket`` and the settings' ``keywords``."""
    control_dt = keywords.get("control_dt", TaskSettings(socket).control_dt)
    task_kwargs = {k: v for k, v in keywords.items() if k != "control_dt"}
    loaded = dmc.load(
        "circle2x2",
        "insert",
        task_kwargs=task_kwargs,
        environment_kwargs={"control_timestep": control_dt},
    )
    single = {"backend": "kinematic", **keywords}
    return {
        "InsertionEnv": InsertionEnv(socket, **single).settings,
        "gym.make": gym.make(GENERIC, socket=socket, **single).unwrapped.settings,
        "InsertionVectorEnv": InsertionVectorEnv(2, socket, **single).settings,
        "tolins.make_vec": tolins.make_vec(GENERIC, 2, socket=socket, **single).settings,
        "dmc.Insert": dmc.Insert(socket, **keywords).settings,
        "dmc.load": loaded.task.settings,
    }


def test_every_api_takes_every_setting_with_the_same_default() -> None:
    """A new field of ``TaskSettings`` reaches every API: built with no setting, each API's
    settings are ``TaskSettings(socket)``'s; handed every setting at once (its default, as
    the settings hold it), each takes them all and holds the same."""
    socket = CircularSocket(2, 2)  # dmc.load's circle2x2
    expected = TaskSettings(socket)
    for api, built in _settings_of_every_api(socket).items():
        assert not _same_settings(built, expected), (
            f"{api}: default of {_same_settings(built, expected)}"
        )
    every = {name: getattr(expected, name) for name in SETTING_FIELDS if name != "socket"}
    assert set(every) == set(TASK_KEYWORDS)
    for api, built in _settings_of_every_api(socket, **every).items():
        assert not _same_settings(built, expected), f"{api}: {_same_settings(built, expected)}"


def test_every_setting_is_a_listed_keyword_and_documented_once() -> None:
    """The keyword lists (and the errors naming them) come from the settings' fields, and
    each field has its line in ``TaskSettings``' docstring."""
    for keywords in (ENV_KEYWORDS, VECTOR_KEYWORDS, (*dmc.TASK_KWARGS, "socket", "control_dt")):
        assert set(SETTING_FIELDS) <= set(keywords)
        assert len(set(keywords)) == len(keywords)
    attributes = TaskSettings.__doc__.split("Attributes:")[1]
    undocumented = [name for name in SETTING_FIELDS if f"\n        {name}: " not in attributes]
    assert not undocumented, f"TaskSettings' docstring lacks {undocumented}"


@pytest.mark.parametrize(
    "make", [InsertionEnv, dmc.Insert, lambda s, **k: InsertionVectorEnv(2, s, **k)]
)
def test_an_unknown_setting_is_refused_naming_the_allowed_ones(make) -> None:
    with pytest.raises(ValueError, match=r"unknown keyword 'horizn'; allowed: .*horizon"):
        make(CircularSocket(2, 2), horizn=10)


def test_the_physics_version_is_resolved_once_and_handed_down() -> None:
    """The settings hold the version's number and its ``PhysicsVersion``, which the single
    env's and the vector env's simulators and dm_control's physics get as they are."""
    assert physics_version(VERSIONS[2]) is VERSIONS[2]
    settings_ = TaskSettings(CircularSocket(2, 2), physics_version=VERSIONS[2])
    assert settings_.physics_version == 2 and settings_.version is VERSIONS[2]
    env = InsertionEnv(CircularSocket(2, 2), physics_version=2)
    assert env.physics_version == 2 and env.backend.version is env.settings.version
    vector = InsertionVectorEnv(2, CircularSocket(2, 2), physics_version=2, num_threads=1)
    assert vector.physics.version is vector.settings.version is VERSIONS[2]
    loaded = dmc.load("circle2x2", "insert", task_kwargs={"physics_version": 2})
    assert loaded.physics.version is loaded.task.settings.version is VERSIONS[2]


# --- non-numbers, NaN, inf, huge values -------------------------------------------------


NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"control_dt": "0.25"}, "control_dt"),
        ({"control_dt": True}, "control_dt"),
        ({"control_dt": NAN}, "control_dt"),
        ({"success_depth": "1"}, "success_depth"),
        ({"defect_sigma": NAN}, "defect_sigma"),
        ({"defect_sigma": "0.1"}, "defect_sigma"),
        ({"measurement_noise": 1e308}, "measurement_noise"),
        ({"measurement_noise": MAX_NOISE_STD * 1.5}, "measurement_noise"),
        ({"measurement_noise": "0.1"}, "measurement_noise"),
        ({"measurement_noise": [0.1, 0.1, 0.0, 1j]}, "measurement_noise"),
        ({"measurement_noise": {"x": 0.1}}, "measurement_noise"),
        ({"force_noise": [True, 0, 0, 0]}, "force_noise"),
        ({"force_noise": INF}, "force_noise"),
        ({"initial_pose": {"radius_min": 1}}, "initial_pose"),
        ({"initial_pose": "wide"}, "initial_pose"),
        ({"goal": ["0", "0", "0"]}, "goal"),
        ({"goal": [True, False, False]}, "goal"),
        ({"horizon": 40.0}, "horizon"),
    ],
)
def test_non_numbers_and_non_finite_settings_are_refused_naming_the_field(kwargs, field) -> None:
    with pytest.raises(ValueError, match=field):
        _make(backend="kinematic", **kwargs).reset(seed=0)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"theta_max": NAN},
        {"radius_max": INF},
        {"z_max": NAN},
        {"radius_min": "1"},
        {"z_min": 1j},
        {"theta_max": True},
    ],
)
def test_an_initial_pose_distribution_takes_finite_numbers_only(kwargs) -> None:
    (field,) = kwargs
    with pytest.raises(ValueError, match=f"^{field}="):
        InitialPoseDistribution(**kwargs)


def test_the_largest_noise_keeps_observations_finite() -> None:
    env = _make(backend="kinematic", measurement_noise=MAX_NOISE_STD, force_noise=MAX_NOISE_STD)
    observations = [env.reset(seed=0)[0]] + [env.step(DOWN)[0] for _ in range(5)]
    assert np.isfinite(observations).all() and np.abs(observations).max() > MAX_NOISE_STD


@pytest.mark.parametrize(
    "action",
    [
        "1, 0, 0, 0",
        ["1", "0", "0", "0"],
        [1j, 0, 0, 0],
        np.array([1j, 0, 0, 0]),
        [True, 0.0, 0.0, 0.0],
        np.ones(4, dtype=bool),
        [None, 0, 0, 0],
    ],
)
@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_actions_must_be_real_numbers(backend: str, action) -> None:
    """Strings, complex numbers and bools are refused (a bool is no velocity); the state
    is untouched, so the episode goes on as if the call had not been made."""
    env, reference = _make(backend=backend), _make(backend=backend)
    env.reset(seed=3)
    reference.reset(seed=3)
    with pytest.raises(ValueError, match="action"):
        env.step(action)
    assert np.array_equal(env.step([0, 0, 0, -2])[0], reference.step([0, 0, 0, -2])[0])


def test_int_and_float32_actions_are_real_numbers() -> None:
    env, reference = _make(backend="kinematic"), _make(backend="kinematic")
    env.reset(seed=1)
    reference.reset(seed=1)
    for action, same in (
        ([0, 1, 0, -2], [0.0, 1.0, 0.0, -2.0]),
        (np.float32([1, 0, 0, -1]), [1, 0, 0, -1]),
    ):
        assert np.array_equal(env.step(action)[0], reference.step(np.array(same, float))[0])


# --- property-based: any keywords, socket, options and actions ----------------------------


_REALS = st.floats(allow_nan=True, allow_infinity=True, width=64)
_ODD = st.sampled_from(["0.1", None, True, 1j, {"a": 1}, [0.1, 0.2], ()])


def _value(good):
    """Mostly plausible values (``good``), sometimes any float or an odd object."""
    return _mostly(good, st.one_of(_REALS, _ODD), 0.1)


def _mostly(good, bad, share_bad: float):
    """``good``, or ``bad`` with a probability of about ``share_bad``."""
    return st.integers(1, 100).flatmap(lambda k: bad if k > 100 * (1 - share_bad) else good)


def _circular(rows: int, cols: int, pin: float, clearance: float) -> CircularSocket:
    return CircularSocket(rows, cols, pin_radius=pin, hole_radius=pin + clearance)


_SOCKETS = _mostly(
    st.one_of(
        st.builds(
            _circular,
            st.integers(1, 3),
            st.integers(1, 4),
            st.floats(0.1, 0.5),
            st.floats(0.01, 0.4),
        ),
        st.builds(
            lambda sides, pin, clearance: PolygonSocket(sides, pin, pin + clearance),
            st.integers(3, 8),
            st.floats(0.5, 2.0),
            st.floats(0.02, 0.4),
        ),
    ),
    st.builds(PolygonSocket, st.integers(1, 8), st.floats(0.5, 2.0), st.floats(-1.0, 2.0)),
    0.1,
)
_POSE_DISTRIBUTIONS = st.builds(
    InitialPoseDistribution,
    radius_min=_value(st.floats(0.0, 2.0)),
    radius_max=_value(st.floats(2.0, 3.0)),
    theta_max=_value(st.floats(0.0, 0.15)),
    z_min=_value(st.floats(0.01, 10.0)),
    z_max=_value(st.floats(10.0, 40.0)),
)
_KWARGS = st.fixed_dictionaries(
    {},
    optional={
        "control_dt": _value(st.sampled_from([0.002, 0.003, 0.05, 0.25, 0.252, 1.0, 0.001])),
        "success_depth": _value(st.floats(0.01, 4.5)),
        "measurement_noise": _value(st.floats(0.0, 1.1e3)),
        "force_noise": _value(st.lists(st.floats(0.0, 5.0), min_size=4, max_size=4)),
        "horizon": _value(st.integers(1, 60)),
        "collision_force": _value(st.floats(0.01, 10.0)),
        "reward_mode": _mostly(
            st.sampled_from(["sparse", "dense", "normalized_dense"]),
            st.sampled_from(["other", 3]),
            0.1,
        ),
        "goal": _value(st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3)),
        "initial_pose": _mostly(st.none(), _ODD, 0.2),
    },
)
_ACTIONS = st.one_of(
    st.lists(st.floats(-5.0, 5.0), min_size=4, max_size=4),
    st.lists(st.floats(-5.0, 5.0), min_size=4, max_size=4),
    st.lists(st.floats(-5.0, 5.0), min_size=4, max_size=4),
    st.lists(_REALS, min_size=4, max_size=4),
    st.lists(st.one_of(st.floats(-3, 3), _ODD), min_size=3, max_size=5),
)
_OPTIONS = st.one_of(
    st.none(),
    st.fixed_dictionaries(
        {},
        optional={
            "pose": _value(st.lists(st.floats(-6.0, 41.0), min_size=4, max_size=4)),
            "goal": _value(st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3)),
            "speed": st.just(1.0),
        },
    ),
)


def _names_a_field(error: Exception, fields) -> bool:
    return any(field in str(error) for field in fields)


def _check_any_settings(data, backend: str) -> None:
    """Either a ValueError/TypeError naming a field, or an env whose resets never fail and
    whose first 20 steps are finite."""
    kwargs = data.draw(_KWARGS, label="kwargs")
    fields = set(kwargs) | {"socket", "pin", "hole", "rows", "cols", "sides", "pitch"}
    try:
        kwargs["socket"] = data.draw(_SOCKETS, label="socket")
        circular = isinstance(kwargs["socket"], CircularSocket)
        if data.draw(st.integers(0, 9 if circular else 19), label="defects") < 3:
            fields.add("defect_sigma")
            kwargs["defect_sigma"] = data.draw(_value(st.floats(0.001, 1.0)), label="sigma")
        if data.draw(st.integers(0, 3), label="custom initial_pose") == 0:
            fields |= {"initial_pose", "radius_m", "theta_max", "z_m"}
            kwargs["initial_pose"] = data.draw(_POSE_DISTRIBUTIONS, label="initial_pose")
        env = gym.make(GENERIC, backend=backend, **kwargs)
    except (ValueError, TypeError) as error:
        assert _names_a_field(error, fields), error
        event("refused: " + str(error).split("=")[0][:30])
        return
    event("made")
    seed = data.draw(st.integers(0, 2**32 - 1), label="seed")
    observation, _ = env.reset(seed=seed)
    assert np.isfinite(observation).all()
    for _ in range(20):
        if data.draw(st.integers(0, 9), label="reset now") == 0:
            try:
                observation, _ = env.reset(options=data.draw(_OPTIONS, label="options"))
            except ValueError as error:
                assert _names_a_field(error, ("options", "pose", "goal")), error
                with pytest.raises(gym.error.ResetNeeded):
                    env.step(DOWN)
                observation, _ = env.reset()
            assert np.isfinite(observation).all()
        try:
            observation, reward, terminated, truncated, info = env.step(
                data.draw(_ACTIONS, label="action")
            )
        except ValueError as error:
            assert "action" in str(error), error
            continue
        assert np.isfinite(observation).all() and math.isfinite(reward)
        assert "error" not in info, info["error"]
        if terminated or truncated:
            observation, _ = env.reset()
            assert np.isfinite(observation).all()
    env.close()


_PROPERTY = settings(
    deadline=None,
    derandomize=True,
    database=None,
    phases=[Phase.explicit, Phase.generate],  # no shrinking: minutes for these examples
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@settings(_PROPERTY, max_examples=200)
@given(data=st.data())
def test_any_settings_on_the_kinematic_backend_work_or_are_refused(data) -> None:
    _check_any_settings(data, "kinematic")


@settings(_PROPERTY, max_examples=24)
@given(data=st.data())
def test_any_settings_on_mujoco_work_or_are_refused(data) -> None:
    _check_any_settings(data, "mujoco")


# --- copies -----------------------------------------------------------------------------


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_a_pickled_or_copied_env_goes_on_bit_identically(backend: str) -> None:
    """In contact: a copy of a MuJoCo env used to read frozen sensor views (0 N)."""
    env = _make(backend=backend)
    env.reset(seed=0, options={"pose": [0.35, 0.0, 0.0, 0.4]})
    for _ in range(3):
        env.step(DOWN)
    copies = [pickle.loads(pickle.dumps(env)), copy.deepcopy(env)]
    # Pressing on the board's top beside the holes, sliding away from them, lifting off.
    actions = [DOWN, [1.0, 0.0, 0.0, -2.5], [0.0, 1.0, 0.05, -2.5], DOWN, [0, 0, 0, 1.0]]
    for action in actions:
        expected = env.step(action)
        for other in copies:
            got = other.step(action)
            assert np.array_equal(got[0], expected[0]) and got[1:4] == expected[1:4]
            assert got[4]["peak_force"] == expected[4]["peak_force"]
            assert np.array_equal(got[4]["wrench"], expected[4]["wrench"])
    assert expected[4]["step"] == 8 and got[4]["n_collisions"] >= 4


# --- renderers at exit ------------------------------------------------------------------


def _exit_without_close(body: str) -> subprocess.CompletedProcess:
    script = "import numpy as np, gymnasium as gym, mujoco, tolins\n" + textwrap.dedent(body)
    environment = {**os.environ, "MUJOCO_GL": "egl"}
    return subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        timeout=120,
        env=environment,
    )


def _skip_without_egl(result: subprocess.CompletedProcess) -> None:
    if result.returncode != 0:
        pytest.skip(f"headless OpenGL unavailable: {result.stderr[-300:]}")


def test_renderers_from_open_renderer_close_before_opengl_exits() -> None:
    plain = _exit_without_close("""
        env = gym.make("tolins/Circle2x2-v2"); env.reset(seed=0)
        renderer = mujoco.Renderer(env.unwrapped.backend.model, 48, 64)
        renderer.update_scene(env.unwrapped.backend.data); renderer.render()
    """)
    _skip_without_egl(plain)
    if "EGLError" not in plain.stderr:  # what an unclosed renderer prints at exit here
        pytest.skip("an unclosed mujoco.Renderer exits cleanly with this OpenGL")
    result = _exit_without_close("""
        from tolins.envs.rendering import open_renderer
        env = gym.make("tolins/Circle2x2-v2"); env.reset(seed=0)
        renderers = [open_renderer(env.unwrapped.backend.model, 48, 64) for _ in range(2)]
        for renderer in renderers:
            renderer.update_scene(env.unwrapped.backend.data); renderer.render()
        renderers[0].close()
    """)
    assert result.returncode == 0 and result.stderr == "", result.stderr


def test_an_env_that_rendered_and_was_not_closed_exits_cleanly() -> None:
    result = _exit_without_close("""
        env = gym.make("tolins/Circle2x2-v2", render_mode="rgb_array"); env.reset(seed=0)
        assert env.render().shape == (480, 640, 3)
    """)
    _skip_without_egl(result)
    assert result.stderr == "", result.stderr
