"""The vector env: every env's episodes are the single env's bit for bit, and the
gymnasium vector conventions hold (autoreset modes, batched info with masks, seeding)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import tolins
from tolins.envs.tasks import GENERIC_ID, TASKS
from tolins.envs.vector import InsertionVectorEnv
from tolins.policies import EXPERTS

DEFECTIVE = "tolins/Circle2x1Defective-v1"


def _policies(n: int, rng: np.random.Generator):
    """Per env: the safe expert, the efficient one, then random actions (horizons)."""
    experts = [EXPERTS["safe"](), EXPERTS["efficient"]()]
    return [
        experts[i] if i < len(experts) else (lambda _obs: rng.uniform(-2.5, 2.5, 4))
        for i in range(n)
    ]


def _assert_info_row(vector_info: dict, i: int, info: dict) -> None:
    for key, value in info.items():
        assert vector_info[f"_{key}"][i], key
        if isinstance(value, dict):  # batched key by key (info["workpiece"])
            _assert_info_row(vector_info[key], i, value)
            continue
        assert np.array_equal(np.asarray(vector_info[key][i]), np.asarray(value)), key
    extra = [k for k in vector_info if not k.startswith("_") and vector_info[f"_{k}"][i]]
    assert set(extra) == set(info), (extra, sorted(info))


def _compare(env_id: str, backend: str, n: int, steps: int, threads: int, fault_at=None, **task):
    """Step ``n`` single envs and the vector env side by side; return what happened."""
    kwargs = {"num_threads": threads} if backend == "mujoco" else {}
    vector = tolins.make_vec(env_id, n, backend=backend, **kwargs, **task)
    singles = [gym.make(env_id, backend=backend, **task) for _ in range(n)]
    observations, info = vector.reset(seed=7)
    for i, env in enumerate(singles):
        single_observation, single_info = env.reset(seed=7 + i)
        assert np.array_equal(observations[i], single_observation)
        _assert_info_row(info, i, single_info)
    rng = np.random.default_rng(0)
    policies = _policies(n, rng)
    seen = {"success": 0, "horizon": 0, "fault": 0, "sockets": set()}
    autoreset = np.zeros(n, dtype=bool)
    for step in range(steps):
        actions = np.array([policies[i](observations[i]) for i in range(n)])
        if fault_at == step:  # a simulator fault in env 1 of both
            vector.unwrapped.physics.batch.bind("qvel")[1, 0] = np.nan
            singles[1].unwrapped.backend.data.qvel[0] = np.nan
        observations, rewards, terminated, truncated, info = vector.step(actions)
        for i, env in enumerate(singles):
            if autoreset[i]:
                expected = (*env.reset(), 0.0, False, False)
                expected = (expected[0], expected[2], expected[3], expected[4], expected[1])
            else:
                expected = env.step(actions[i])
            assert np.array_equal(observations[i], expected[0]), (step, i)
            assert rewards[i] == expected[1] and terminated[i] == expected[2]
            assert truncated[i] == expected[3]
            _assert_info_row(info, i, expected[4])
            seen["sockets"].add(env.unwrapped.socket)
            seen["success"] += bool(expected[2])
            seen["horizon"] += bool(expected[3]) and "error" not in expected[4]
            seen["fault"] += "error" in expected[4]
        autoreset = terminated | truncated
    vector.close()
    return seen


@pytest.mark.parametrize("threads", [1, 2])
def test_mujoco_vector_env_is_the_single_env_bit_for_bit(threads, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # MuJoCo logs the fault's warning to ./MUJOCO_LOG.TXT
    seen = _compare("tolins/Circle2x2-v1", "mujoco", 3, 90, threads, fault_at=50)
    assert seen["success"] >= 2 and seen["horizon"] >= 1 and seen["fault"] == 1


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_defects_are_redrawn_per_env_as_in_the_single_env(backend) -> None:
    seen = _compare(DEFECTIVE, backend, 3, 80, threads=2)
    assert len(seen["sockets"]) >= 6  # a new bent-pin workpiece per episode and env
    assert seen["success"] >= 1 and seen["horizon"] >= 1


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_randomised_physics_is_drawn_per_env_as_in_the_single_env(backend) -> None:
    seen = _compare(DEFECTIVE, backend, 3, 80, threads=2, randomization="default")
    assert len(seen["sockets"]) >= 6 and seen["success"] >= 1


def test_kinematic_vector_env_is_the_single_env_bit_for_bit() -> None:
    seen = _compare("tolins/Square-v1", "kinematic", 5, 120, threads=1)
    assert seen["success"] >= 4 and seen["horizon"] >= 3


def test_same_step_autoreset_reports_the_final_observation_and_info() -> None:
    vector = tolins.make_vec(
        "tolins/Circle2x2-v1", 2, backend="kinematic", autoreset_mode="SameStep"
    )
    single = gym.make("tolins/Circle2x2-v1", backend="kinematic")
    assert vector.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    observations, _ = vector.reset(seed=3)
    single.reset(seed=3)
    expert = EXPERTS["safe"]()
    for _ in range(200):
        actions = np.array([expert(o) for o in observations])
        observations, _, terminated, truncated, info = vector.step(actions)
        expected = single.step(actions[0])
        if terminated[0] or truncated[0]:
            assert info["_final_obs"][0] and np.array_equal(info["final_obs"][0], expected[0])
            assert info["final_info"]["step"][0] == expected[4]["step"]
            reset_observation, reset_info = single.reset()
            assert np.array_equal(observations[0], reset_observation)
            assert info["step"][0] == 0 == reset_info["step"]
            break
    else:
        pytest.fail("no episode ended")


def test_reset_seeds_follow_gymnasium() -> None:
    vector = tolins.make_vec("tolins/Circle2x2-v1", 3, backend="kinematic")
    by_int, _ = vector.reset(seed=5)
    by_list, _ = vector.reset(seed=[5, 6, 7])
    assert np.array_equal(by_int, by_list)
    again, _ = vector.reset(seed=[7, None, 5])
    assert np.array_equal(again[0], by_int[2]) and np.array_equal(again[2], by_int[0])
    with pytest.raises(ValueError, match="a list of 3"):
        vector.reset(seed=[1, 2])


def test_reset_mask_resets_only_the_masked_envs() -> None:
    vector = tolins.make_vec(
        "tolins/Circle2x2-v1", 3, backend="kinematic", autoreset_mode="Disabled"
    )
    first, _ = vector.reset(seed=0)
    stepped, *_ = vector.step(np.zeros((3, 4)))
    mask = np.array([False, True, False])
    observations, info = vector.reset(seed=[None, 1, None], options={"reset_mask": mask})
    assert np.array_equal(observations[1], first[1])  # env 1 seeded as before
    assert np.array_equal(observations[[0, 2]], stepped[[0, 2]])
    assert list(info["_step"]) == [False, True, False]


def test_a_failed_reset_changes_nothing_and_then_stepping_needs_a_reset() -> None:
    vector = tolins.make_vec("tolins/Circle2x2-v1", 2, backend="kinematic")
    vector.reset(seed=0)
    vector.step(np.zeros((2, 4)))
    poses = [episode.state.pose.copy() for episode in vector.unwrapped.episodes]
    with pytest.raises(ValueError, match="servo range"):
        vector.reset(options={"pose": [99.0, 0.0, 0.0, 10.0]})
    assert all(
        np.array_equal(e.state.pose, p)
        for e, p in zip(vector.unwrapped.episodes, poses, strict=True)
    )
    with pytest.raises(gym.error.ResetNeeded):
        vector.step(np.zeros((2, 4)))
    vector.reset(seed=1)
    vector.step(np.zeros((2, 4)))


@pytest.mark.parametrize(
    ("actions", "match"),
    [(np.zeros((3, 4)), "shape"), (np.full((2, 4), np.nan), "NaN"), (np.zeros((2, 3)), "shape")],
)
def test_bad_actions_raise_before_anything_steps(actions, match) -> None:
    vector = tolins.make_vec("tolins/Circle2x2-v1", 2, backend="kinematic")
    vector.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        vector.step(actions)
    poses = [e.state.pose.copy() for e in vector.unwrapped.episodes]
    assert np.array_equal(poses[0][:3] - vector.unwrapped.episodes[0].episode_goal, poses[0][:3])


def test_gymnasium_checks_and_wrappers_accept_it() -> None:
    from gymnasium.utils.env_checker import check_reset_seed_determinism
    from gymnasium.wrappers.vector import RecordEpisodeStatistics

    vector = gym.make_vec("tolins/Hexagon-v1", num_envs=2, vectorization_mode="vector_entry_point")
    assert isinstance(vector.unwrapped, InsertionVectorEnv)
    assert vector.spec.id == "tolins/Hexagon-v1"
    check_reset_seed_determinism(vector)  # gymnasium's check_step_determinism is single-env
    wrapped = RecordEpisodeStatistics(vector)
    wrapped.reset(seed=0)
    for _ in range(40):
        *_, truncated, info = wrapped.step(wrapped.action_space.sample())
    assert truncated.all() and info["_episode"].all()
    assert list(info["episode"]["l"]) == [40, 40]
    assert info["success"].dtype == bool and info["pose"].shape == (2, 4)


@pytest.mark.parametrize("env_id", [task.gym_id for task in TASKS])
def test_every_id_has_a_vector_entry_point(env_id) -> None:
    vector = tolins.make_vec(env_id, 2, backend="kinematic")
    observations, _ = vector.reset(seed=0)
    assert observations.shape == (2, 8) and vector.observation_space.contains(observations)
    assert vector.unwrapped.settings.socket == gym.make(env_id).unwrapped.nominal_socket


def test_generic_id_takes_a_socket_and_refuses_unknown_ids() -> None:
    socket = tolins.CircularSocket(rows=2, cols=3)
    vector = tolins.make_vec(GENERIC_ID, 2, socket=socket, num_threads=1)
    vector.reset(seed=0)
    assert vector.unwrapped.sockets == [socket, socket]
    with pytest.raises(ValueError, match="socket is required"):
        tolins.make_vec(GENERIC_ID, 2)
    with pytest.raises(ValueError, match="unknown env"):
        tolins.make_vec("CartPole-v1", 2)
    with pytest.raises(ValueError, match="backend"):
        tolins.make_vec("tolins/Circle2x2-v1", 2, backend="bullet")


def test_batched_infos_are_gymnasiums_add_info_exactly() -> None:
    from tolins.envs.vector import batch_infos

    infos = [
        {"a": 1, "b": np.array([1.0, 2.0]), "c": True, "d": {"e": 0.5}, "final_obs": np.ones(2)},
        None,
        {"a": 3, "b": np.array([3.0, 4.0]), "error": "boom", "d": {"e": 1.5, "f": "x"}},
        {"a": 2.5, "c": np.bool_(False), "g": [1, 2], "h": np.float32(1.5)},
    ]
    vector = tolins.make_vec("tolins/Circle2x2-v1", 4, backend="kinematic").unwrapped
    expected: dict = {}
    for i, info in enumerate(infos):
        if info is not None:
            expected = vector._add_info(expected, info, i)

    def same(a, b) -> None:
        assert type(a) is type(b)
        if isinstance(a, dict):
            assert list(a) == list(b) or set(a) == set(b)
            for key in a:
                same(a[key], b[key])
        else:
            assert a.dtype == b.dtype and a.shape == b.shape
            for x, y in zip(a, b, strict=True):
                assert np.array_equal(np.asarray(x), np.asarray(y))

    same(batch_infos(infos, 4), expected)


@pytest.mark.parametrize(
    ("env_id", "task"),
    [
        ("tolins/Circle2x2-v2", {"fault_at": 40}),
        ("tolins/Circle2x1Defective-v2", {"randomization": "default"}),
    ],
)
def test_v2_vector_env_is_the_single_env_bit_for_bit(env_id, task, tmp_path, monkeypatch) -> None:
    # Simulations in free flight and in contact step side by side on different step lengths
    # (and, randomised, on models of their own): each is still the single env's.
    monkeypatch.chdir(tmp_path)
    seen = _compare(env_id, "mujoco", 3, 80, 2, **task)
    assert seen["success"] >= 2 and seen["fault"] == ("fault_at" in task)
