"""Misuse of the single and the vector env: each refused by an error that names the argument,
the bad value and what is allowed; closed envs refuse to run; one rule for step-before-reset."""

from __future__ import annotations

import inspect
import os

import gymnasium as gym
import numpy as np
import pytest

import tolins
from tolins.geometry.defects import sample_defects
from tolins.paper import CONTROL_DT
from tolins.physics.mujoco import MujocoBatch

ENV = "tolins/Circle2x2-v1"
SOCKET = tolins.CircularSocket(2, 2)


def _vector(n: int = 2, **kwargs) -> gym.vector.VectorEnv:
    return tolins.make_vec(ENV, n, backend="kinematic", **kwargs)


# --- errors that name the argument ------------------------------------------------------


def test_vector_reset_options_must_be_a_dict() -> None:
    vector = _vector()
    with pytest.raises(ValueError, match=r"options=\[1, 2\]; allowed: None or a dict"):
        vector.reset(options=[1, 2])


def test_a_ragged_action_list_names_the_actions_and_the_shape_allowed() -> None:
    vector = _vector()
    vector.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions .*ragged.*allowed: \(2, 4\)"):
        vector.step([[0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])


@pytest.mark.parametrize("vectorized", [False, True])
def test_an_array_as_randomization_names_it(vectorized: bool) -> None:
    value = np.array([1.0, 2.0])
    with pytest.raises(ValueError, match=r"randomization=array\(\[1\., 2\.\]\); allowed: None"):
        if vectorized:
            _vector(randomization=value)
        else:
            gym.make(ENV, randomization=value)


def test_sb3_step_async_refuses_a_wrong_batch_before_stepping() -> None:
    pytest.importorskip("stable_baselines3")
    from tolins.rollouts.sb3_vec import Sb3VectorEnv

    env = Sb3VectorEnv(ENV, 2, backend="kinematic")
    env.reset()
    with pytest.raises(ValueError, match=r"actions have shape \(3, 4\); allowed: \(2, 4\)"):
        env.step_async(np.zeros((3, 4), np.float32))
    with pytest.raises(ValueError, match=r"ragged.*allowed: \(2, 4\)"):
        env.step_async([[0.0] * 4, [0.0] * 3])
    env.step(np.zeros((2, 4), np.float32))  # nothing was held from the refused calls


@pytest.mark.parametrize("rng", [-1, "abc", 1.5, True, [1, -2], []])
@pytest.mark.parametrize("kind", ["bent", "burr"])
def test_sample_defects_names_a_bad_rng(rng, kind: str) -> None:
    sigma = 0.1 if kind == "bent" else 0.01
    with pytest.raises(ValueError, match=r"rng=.* is not a random generator or seed; allowed"):
        sample_defects(SOCKET, sigma, rng=rng, kind=kind)


def test_sample_defects_takes_every_seed_it_took_and_numpy_integers() -> None:
    expected = sample_defects(SOCKET, 0.1, rng=3)
    assert sample_defects(SOCKET, 0.1, rng=np.int64(3)) == expected
    assert sample_defects(SOCKET, 0.1, rng=np.random.default_rng(3)) == expected
    assert sample_defects(SOCKET, 0.1, rng=[3, 12]) == sample_defects(
        SOCKET, 0.1, np.random.default_rng([3, 12])
    )
    assert sample_defects(SOCKET, 0.1, rng=np.random.SeedSequence(3)) == expected


def test_an_unknown_vector_keyword_is_named_with_the_allowed_ones() -> None:
    with pytest.raises(ValueError) as caught:
        tolins.make_vec(ENV, 2, backend="kinematic", rewrad_mode="dense")
    message = str(caught.value)
    assert "'rewrad_mode'" in message and "TaskSettings" not in message
    assert "allowed:" in message and "reward_mode" in message and "num_threads" in message


def test_an_unknown_single_env_keyword_is_named_concisely() -> None:
    with pytest.raises(ValueError) as caught:
        gym.make(ENV, rewrad_mode="dense")
    message = str(caught.value)
    assert "'rewrad_mode'" in message and "allowed:" in message and "reward_mode" in message
    # No socket dump: the names only (the list grows with the settings: 3 for delicate pins).
    assert "CircularSocket(" not in message and len(message) < 400


# --- close ------------------------------------------------------------------------------


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_a_closed_single_env_releases_its_simulation_and_refuses_to_run(backend: str) -> None:
    env = gym.make(ENV, backend=backend)
    env.reset(seed=0)
    env.step(np.zeros(4))
    env.close()
    assert env.unwrapped.backend is None and env.unwrapped.closed
    for call in (lambda: env.step(np.zeros(4)), env.reset, env.unwrapped.render):
        with pytest.raises(gym.error.ClosedEnvironmentError, match="closed"):
            call()
    env.close()  # twice is harmless


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_a_closed_vector_env_releases_its_batch_and_refuses_to_run(backend: str) -> None:
    kwargs = {"num_threads": 1} if backend == "mujoco" else {}
    vector = tolins.make_vec(ENV, 2, backend=backend, **kwargs)
    vector.reset(seed=0)
    physics = vector.unwrapped.physics
    vector.close()
    assert vector.unwrapped.physics is None and vector.closed
    if backend == "mujoco":
        assert physics.batch is None and physics._models == []
    for call in (lambda: vector.step(np.zeros((2, 4))), vector.reset, vector.unwrapped.render):
        with pytest.raises(gym.error.ClosedEnvironmentError, match="closed"):
            call()
    vector.close()


def test_num_threads_is_bounded_by_the_cores() -> None:
    cores = os.cpu_count()
    with pytest.raises(
        ValueError, match=rf"num_threads=1000000 .*allowed: 1 ≤ num_threads ≤ {cores}"
    ):
        tolins.make_vec(ENV, 2, num_threads=10**6)
    for bad in (0, True, 2.0):
        with pytest.raises(ValueError, match="num_threads"):
            MujocoBatch(SOCKET, 1, CONTROL_DT, num_threads=bad)
    assert MujocoBatch(SOCKET, 1, CONTROL_DT, num_threads=cores).num_threads == cores


# --- step before reset ------------------------------------------------------------------


@pytest.mark.parametrize("mode", ["NextStep", "SameStep", "Disabled"])
def test_stepping_before_reset_raises_in_every_autoreset_mode(mode: str) -> None:
    vector = _vector(autoreset_mode=mode)
    with pytest.raises(gym.error.ResetNeeded, match=r"step\(\) called before reset\(\)"):
        vector.step(np.zeros((2, 4)))
    single = gym.make(ENV, backend="kinematic")
    with pytest.raises(gym.error.ResetNeeded):
        single.step(np.zeros(4))
    with pytest.raises(gym.error.ResetNeeded, match=r"step\(\) called before reset\(\)"):
        single.unwrapped.step(np.zeros(4))
    vector.reset(seed=0)
    vector.step(np.zeros((2, 4)))


def test_a_masked_first_reset_still_steps_the_reset_envs_without_autoreset() -> None:
    vector = _vector(3, autoreset_mode="Disabled")
    observations, _ = vector.reset(seed=0, options={"reset_mask": np.array([True, False, True])})
    stepped, rewards, *_ = vector.step(np.zeros((3, 4)))
    assert not np.array_equal(stepped[0], observations[0])
    assert np.array_equal(stepped[1], np.zeros(8)) and rewards[1] == 0.0


# --- honest defaults and seeds ----------------------------------------------------------


def test_sample_defects_has_no_sigma_default_and_says_which_kind_takes_none() -> None:
    assert inspect.signature(sample_defects).parameters["sigma"].default is inspect.Parameter.empty
    for kind in ("bent", "pitch", "burr", "short"):
        with pytest.raises(ValueError, match=r"sigma=None is for kind='blocked' only"):
            sample_defects(SOCKET, None, rng=0, kind=kind)
    assert sample_defects(SOCKET, None, rng=0, kind="blocked").blocked_holes


def test_a_seed_list_of_numpy_integers_seeds_as_python_ints() -> None:
    vector = _vector(3)
    expected, _ = vector.reset(seed=[4, None, 6])
    for kind in (np.int64, np.int32, np.uint64):
        observations, _ = vector.reset(seed=[kind(4), None, kind(6)])
        assert np.array_equal(observations[[0, 2]], expected[[0, 2]])
    by_scalar, _ = vector.reset(seed=np.int64(4))
    assert np.array_equal(by_scalar[0], expected[0])
    for bad in ([-1, 0, 1], [True, 0, 1], [0.5, 0, 1]):
        with pytest.raises(ValueError, match=r"seed\[0\]=.* is not a seed; allowed"):
            vector.reset(seed=bad)


def test_the_single_env_refuses_a_bool_seed_and_takes_numpy_integers_as_the_vector_env() -> None:
    env = gym.make(ENV, backend="kinematic").unwrapped
    expected, _ = env.reset(seed=4)
    for bad in (True, False, -1, 0.5):
        with pytest.raises(ValueError, match=r"seed=.* is not a seed; allowed: None or an int"):
            env.reset(seed=bad)
    for kind in (np.int64, np.uint32):
        assert np.array_equal(env.reset(seed=kind(4))[0], expected)
