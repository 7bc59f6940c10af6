"""The vector env answers gymnasium's vector API (``call``, ``get_attr``, ``set_attr``,
``render``) as ``SyncVectorEnv`` of single envs does, driven the same way."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import tolins
from tolins.envs.insertion_env import InsertionEnv
from tolins.envs.task_settings import TaskSettings
from tolins.envs.vector_views import SETTABLE, VIEW_ATTRIBUTES
from tolins.policies import EXPERTS

N = 2


def _same(a, b) -> bool:
    """Whether two attribute values are equal (generators by state, settings by field)."""
    if isinstance(a, np.random.Generator):
        return a.bit_generator.state == b.bit_generator.state
    if isinstance(a, TaskSettings):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))
    if isinstance(a, (np.ndarray, list)):
        return np.array_equal(a, b)
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return a == b


def _pair(env_id: str, backend: str, render_mode: str | None = "rgb_array"):
    """Our vector env and gymnasium's SyncVectorEnv of ``N`` single envs of ``env_id``."""
    threads = {"num_threads": 1} if backend == "mujoco" else {}
    ours = tolins.make_vec(env_id, N, backend=backend, render_mode=render_mode, **threads)
    theirs = gym.make_vec(
        env_id, N, vectorization_mode="sync", backend=backend, render_mode=render_mode
    )
    return ours.unwrapped, theirs


def _render_or_skip(render: Callable[[], Any]) -> Any:
    try:
        return render()
    except Exception as error:  # no OpenGL (EGL) on this machine
        pytest.skip(f"headless OpenGL unavailable: {error}")


def _compare_attributes(ours, theirs) -> None:
    for name in VIEW_ATTRIBUTES:
        if name == "render":
            continue  # compared frame by frame
        mine, expected = ours.get_attr(name), theirs.get_attr(name)
        assert isinstance(mine, tuple) and len(mine) == N, name
        assert all(_same(a, b) for a, b in zip(mine, expected, strict=True)), name


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_the_vector_api_answers_as_sync_vector_env_of_single_envs(backend: str) -> None:
    ours, theirs = _pair("tolins/Circle2x1Defective-v1", backend)
    observations, _ = ours.reset(seed=5)
    assert np.array_equal(observations, theirs.reset(seed=5)[0])
    frames = _render_or_skip(lambda: ours.call("render"))
    assert len(frames) == N and frames[0].shape == (480, 640, 3) and frames[0].dtype == np.uint8
    _compare_attributes(ours, theirs)
    expert = EXPERTS["safe"]()
    for k in range(48):  # past the horizon (40): autoreset draws new workpieces
        if k == 10:
            goals = [np.array([0.2, -0.1, 0.01]), np.array([-0.3, 0.2, 0.0])]
            for vector in (ours, theirs):
                vector.set_attr("goal", goals)
                assert np.array_equal(vector.get_attr("goal")[1], goals[1])
        if k == 20:
            for vector in (ours, theirs):
                vector.set_attr("goal", np.array([0.1, 0.1, 0.0]))  # one for every env
                vector.set_attr("np_random", [np.random.default_rng(40 + i) for i in range(N)])
                assert vector.get_attr("np_random_seed") == (-1,) * N
        actions = np.array([expert(o) for o in observations])
        observations, *rest = ours.step(actions)
        expected = theirs.step(actions)
        assert np.array_equal(observations, expected[0]), k
        for mine, their in zip(rest[:3], expected[1:4], strict=True):
            assert np.array_equal(mine, their), k
        if k in (10, 20, 40, 41):  # new goals, new RNGs, the autoreset and after it
            for mine, their in zip(ours.call("render"), theirs.call("render"), strict=True):
                assert np.array_equal(mine, their), k
            _compare_attributes(ours, theirs)
    assert ours.sockets[0] != ours.get_attr("nominal_socket")[0]  # a bent-pin draw
    assert all(np.array_equal(a, b) for a, b in zip(ours.render(), theirs.render(), strict=True))
    ours.close()
    theirs.close()


def test_without_render_mode_render_gives_none_per_env_as_sync_vector_env() -> None:
    ours, theirs = _pair("tolins/Circle2x2-v1", "kinematic", render_mode=None)
    for vector in (ours, theirs):
        with pytest.raises(gym.error.ResetNeeded):
            vector.render()
        vector.reset(seed=0)
    assert ours.render() == theirs.render() == (None,) * N
    assert ours.get_attr("render_mode") == theirs.get_attr("render_mode") == (None,) * N


def test_set_attr_checks_every_value_before_setting_any() -> None:
    ours, theirs = _pair("tolins/Circle2x2-v1", "kinematic", render_mode=None)
    ours.reset(seed=0)
    before = ours.get_attr("goal")
    with pytest.raises(ValueError, match="goal"):
        ours.set_attr("goal", [np.array([0.1, 0.0, 0.0]), np.array([9.0, 0.0, 0.0])])
    assert all(np.array_equal(a, b) for a, b in zip(before, ours.get_attr("goal"), strict=True))
    for vector in (ours, theirs):
        with pytest.raises(ValueError, match=r"length equal to the number|one per env"):
            vector.set_attr("goal", [np.zeros(3)] * (N + 1))
    with pytest.raises(ValueError, match=r"np_random=3; allowed: a numpy\.random\.Generator"):
        ours.set_attr("np_random", 3)


def test_unknown_and_read_only_names_say_what_is_allowed() -> None:
    vector = tolins.make_vec("tolins/Circle2x2-v1", N, backend="kinematic").unwrapped
    with pytest.raises(AttributeError, match=r"'backend' is not a per-env .*allowed: .*socket"):
        vector.get_attr("backend")
    with pytest.raises(AttributeError, match=r"'socket' is not a settable .*allowed: goal"):
        vector.set_attr("socket", tolins.CircularSocket(2, 2))
    assert set(SETTABLE) == {"goal", "np_random"}
    assert vector.metadata["render_fps"] == 4 and "rgb_array" in vector.metadata["render_modes"]


def test_render_mode_is_checked_per_backend() -> None:
    with pytest.raises(ValueError, match=r"render_mode='human'; allowed: None, 'rgb_array'"):
        tolins.make_vec("tolins/Circle2x2-v1", N, backend="kinematic", render_mode="human")
    with pytest.raises(ValueError, match=r"not supported on backend='warp'"):
        tolins.make_vec("tolins/Circle2x2-v1", N, backend="warp", render_mode="rgb_array")


def test_closing_one_renderer_leaves_the_frames_of_the_others_intact() -> None:
    envs = [InsertionEnv(tolins.CircularSocket(2, 2), render_mode="rgb_array") for _ in range(2)]
    for env in envs:
        env.reset(seed=0)
    envs[1].render()
    before = _render_or_skip(envs[0].render)
    envs[1].close()  # while the first env's OpenGL context is current
    assert np.array_equal(envs[0].render(), before)
    envs[0].close()
