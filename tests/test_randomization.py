"""Randomised physics: off by default, drawn from the reset's seed, visible in info, applied
to the MuJoCo model from its nominal values, and refused when out of range."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import tolins  # noqa: F401  (registers the envs)
from tolins.physics.randomization import DEFAULT_RANDOMIZATION, PhysicsRandomization

ENV = "tolins/Circle2x2-v1"


def _episode(env, seed: int, steps: int = 30):
    observation, info = env.reset(seed=seed)
    observations = [observation]
    for _ in range(steps):
        observation, *_ = env.step([0.0, 0.0, 0.0, -2.5])
        observations.append(observation)
    return info, np.array(observations)


def test_off_by_default_and_the_paper_setting_draws_nothing() -> None:
    plain, explicit = gym.make(ENV), gym.make(ENV, randomization=None)
    info, observations = _episode(plain, 3)
    other_info, other = _episode(explicit, 3)
    assert "physics" not in info and "physics" not in other_info
    assert np.array_equal(observations, other)


@pytest.mark.parametrize("backend", ["mujoco", "kinematic"])
def test_a_seed_gives_the_same_draw_and_the_draw_is_in_info(backend) -> None:
    env = gym.make(ENV, backend=backend, randomization="default")
    first, observations = _episode(env, 5)
    again, repeated = _episode(env, 5)
    other, _ = _episode(env, 6)
    assert first["physics"] == again["physics"] != other["physics"]
    assert np.array_equal(observations, repeated)
    for name, (low, high) in vars(DEFAULT_RANDOMIZATION).items():
        value = np.asarray(first["physics"][name])
        assert np.all((low <= value) & (value <= high)), name


def test_the_mujoco_model_follows_each_draw_from_its_nominal_values() -> None:
    env = gym.make(ENV, randomization={"friction": (0.5, 2.0), "force_limit": (0.8, 1.2)})
    model = env.unwrapped.backend.model
    friction, limit = model.geom_friction[:, 0].copy(), model.actuator_forcerange.copy()
    for seed in range(3):  # draws do not compound
        info, _ = _episode(env, seed, steps=0)
        drawn = info["physics"]
        np.testing.assert_allclose(model.geom_friction[:, 0], friction * drawn["friction"])
        np.testing.assert_allclose(model.actuator_forcerange, limit * drawn["force_limit"])


def test_a_lower_force_limit_pushes_less_on_the_board() -> None:
    pushes = {}
    for factor in (0.8, 1.0):
        env = gym.make(ENV, measurement_noise=0.0, randomization={"force_limit": (factor, factor)})
        env.reset(seed=0, options={"pose": [0.77, 0.0, 0.0, 1.0]})
        for _ in range(8):
            *_, info = env.step([0.0, 0.0, 0.0, -2.5])
        pushes[factor] = info["wrench"][3]
    assert pushes[0.8] == pytest.approx(0.8 * pushes[1.0], rel=1e-6)


def test_the_sensor_bias_shifts_the_force_observation() -> None:
    bias = {"force_bias": (0.3, 0.3)}
    plain = gym.make(ENV, backend="kinematic", measurement_noise=0.0)
    biased = gym.make(ENV, backend="kinematic", measurement_noise=0.0, randomization=bias)
    a, _ = plain.reset(seed=0)
    b, info = biased.reset(seed=0)
    assert info["physics"]["force_bias"] == [0.3] * 4
    np.testing.assert_allclose(b[4:] - a[4:], 0.3)


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ({"friction": (0.5, np.nan)}, "friction"),
        ({"stiffness": (0.5, 1.0)}, "stiffness"),
        ({"servo_gain": (2.0, 1.0)}, "servo_gain"),
        ({"gravity": (0, 1)}, "unknown"),
        ({"force_bias": "0.1"}, "force_bias"),
        ("wild", "allowed"),
        ({"pose_spread": (1.0, 1.5)}, "pose_spread"),
    ],
)
def test_bad_ranges_are_refused_naming_the_field(value, match) -> None:
    with pytest.raises(ValueError, match=match):
        gym.make(ENV, randomization=value)


def test_the_default_ranges_are_valid_ranges() -> None:
    assert PhysicsRandomization.of("default") is DEFAULT_RANDOMIZATION
    assert PhysicsRandomization(**vars(DEFAULT_RANDOMIZATION)) == DEFAULT_RANDOMIZATION


def test_dm_control_draws_what_the_gym_env_draws() -> None:
    from tolins import dmc

    kwargs = {"randomization": "default", "measurement_noise": 0.0}
    env = dmc.load("circle2x2", "insert", task_kwargs={**kwargs, "random": 4})
    timestep = env.reset()
    gym_env = gym.make(ENV, **kwargs)
    observation, info = gym_env.reset(seed=4)
    assert env.task.physics_draw.to_info() == info["physics"]
    flat = np.concatenate([np.ravel(v) for v in timestep.observation.values()])
    np.testing.assert_array_equal(np.sort(flat), np.sort(observation))
    for _ in range(3):
        timestep = env.step([0.0, 0.0, 0.0, -2.5])
        observation, *_ = gym_env.step([0.0, 0.0, 0.0, -2.5])
    flat = np.concatenate([np.ravel(v) for v in timestep.observation.values()])
    np.testing.assert_array_equal(np.sort(flat), np.sort(observation))
