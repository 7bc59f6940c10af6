"""Delicate pins held by the Panda (``robot="panda"``, ``pins="elastic-plastic"``): the arm
bends the pins it drags, a kept part stays bent, and the vector env and dm_control step
as the single env, bit for bit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tolins
from tolins import dmc
from tolins.envs.tasks import DELICATE_ROBOT_TASKS

#: Alloy 42's pins yield under the arm's push (2.5 N a pin against 1.46 N).
DELICATE = {"pins": "elastic-plastic", "pin_material": "alloy42", "measurement_noise": 0.0}
#: Pins 0.6 mm into their holes, short of success.
IN_HOLES = [0.0, 0.0, 0.0, -0.6]
OVER_BOARD = [0.0, 0.0, 0.0, 2.0]
SIDEWAYS = [2.5, 0.0, 0.0, 0.0]


@pytest.fixture(scope="module")
def dragged() -> tuple[gym.Env, dict]:
    """The Panda's 2*1 dragged sideways for one step with its pins in their holes."""
    env = gym.make("tolins/Circle2x1Panda-v3", **DELICATE).unwrapped
    env.reset(seed=0, options={"pose": IN_HOLES})
    *_, info = env.step(SIDEWAYS)
    return env, info


def test_check_env_with_the_panda_holding_delicate_pins() -> None:
    env = gym.make("tolins/Circle2x2Panda-v3", pins="elastic-plastic", horizon=3)
    check_env(env.unwrapped, skip_render_check=True)
    _, info = env.reset(seed=0)
    assert info["pin_bend"].shape == (4, 2) and not info["pin_bend"].any()
    assert np.abs(info["pin_deflection"]).max() < 1e-9  # at rest at its plastic set
    assert info["damaged"] is False


def test_the_arm_bends_the_pins_it_drags_and_a_kept_part_stays_bent(dragged) -> None:
    env, info = dragged
    bend = info["pin_bend"]
    assert np.all(bend[:, 0] < -0.1)  # measured -0.22: the tips held back by the walls
    assert np.all(np.abs(bend[:, 1]) < 0.01)
    assert info["damaged"] and info["damaged_at"] == 1
    _, kept = env.reset(seed=1, options={"pose": OVER_BOARD, "keep_part": True})
    assert np.array_equal(kept["pin_bend"], bend)
    assert np.allclose(kept["pin_deflection"], bend, rtol=0.0, atol=1e-9)
    assert kept["damaged"] and kept["damaged_at"] == 0
    _, fresh = env.reset(seed=1, options={"pose": OVER_BOARD})
    assert not fresh["pin_bend"].any() and fresh["damaged"] is False


def test_the_vector_env_steps_each_panda_as_the_single_env(dragged) -> None:
    single, _ = dragged
    vector = tolins.make_vec("tolins/Circle2x1Panda-v3", 2, num_threads=2, **DELICATE)
    actions = np.array([SIDEWAYS, [-1.0, 2.5, 0.0, 0.0]])
    vector.reset(seed=[0, 1], options={"pose": IN_HOLES})
    batch = vector.step(actions)
    kept = vector.reset(seed=[2, 3], options={"pose": OVER_BOARD, "keep_part": True})
    for i in range(2):
        single.reset(seed=i, options={"pose": IN_HOLES})
        observation, reward, *_, info = single.step(actions[i])
        np.testing.assert_array_equal(observation, batch[0][i])
        assert reward == batch[1][i]
        np.testing.assert_array_equal(info["pin_deflection"], batch[4]["pin_deflection"][i])
        observation, info = single.reset(
            seed=2 + i, options={"pose": OVER_BOARD, "keep_part": True}
        )
        np.testing.assert_array_equal(observation, kept[0][i])
        np.testing.assert_array_equal(info["pin_bend"], kept[1]["pin_bend"][i])
    assert np.abs(kept[1]["pin_bend"]).min(axis=(1, 2)).max() > 0.05  # both dragged pins bent
    vector.close()


def test_dm_control_steps_the_panda_as_the_gym_id() -> None:
    gym_env = gym.make("tolins/Circle2x1Panda-v3", **DELICATE).unwrapped
    gym_env.reset(seed=0, options={"pose": IN_HOLES})
    task_kwargs = {**DELICATE, "pose": IN_HOLES}
    env = dmc.load("circle2x1_panda", "insert", task_kwargs=task_kwargs)
    env.reset()
    for action in [SIDEWAYS, [0.0, 1.0, 0.0, 0.0]]:
        *_, info = gym_env.step(action)
        env.step(action)
        state = env.physics.last_state
        assert np.array_equal(state.pose, info["pose"])
        assert np.array_equal(state.pin_bend, info["pin_bend"])
        assert np.array_equal(state.pin_deflection, info["pin_deflection"])
    assert np.abs(info["pin_bend"]).max() > 0.1


def test_the_registered_ids_are_the_panda_with_delicate_pins(dragged) -> None:
    _, info = dragged
    registered = gym.make(
        "tolins/Circle2x1DelicatePanda-v3", pin_material="alloy42", measurement_noise=0.0
    ).unwrapped
    assert registered.settings.robot == "panda" and registered.settings.pins == "elastic-plastic"
    registered.reset(seed=0, options={"pose": IN_HOLES})
    *_, again = registered.step(SIDEWAYS)
    assert np.array_equal(again["pin_bend"], info["pin_bend"])
    assert np.array_equal(again["pose"], info["pose"])
    ids = [task.gym_id_of(3) for task in DELICATE_ROBOT_TASKS]
    assert ids[1] == "tolins/Circle2x2DelicatePanda-v3" and all(i in gym.registry for i in ids)
    assert all({"robot", "delicate"} <= set(task.tags) for task in DELICATE_ROBOT_TASKS)
    assert ("circle2x8_fit50_delicate_panda", "insert") in dmc.DELICATE
