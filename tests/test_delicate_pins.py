"""Delicate pins (``pins="elastic-plastic"``): beam theory on the generated model, the env's
bends and damage, determinism, dm_control, the delicate ids and the refused settings."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tolins
from tolins import dmc
from tolins.envs import InsertionEnv
from tolins.envs.tasks import DELICATE_TASKS
from tolins.geometry.delicate import check_pins, pin_beams
from tolins.geometry.specs import CircularSocket, PolygonSocket
from tolins.mjcf import make_mjcf
from tolins.physics.compiled import compile_model
from tolins.physics.servo import ServoStepper

ELASTIC = {"pins": "elastic-plastic"}


def _push(material: object = None, clearance: float = 0.2) -> dict[str, float]:
    """Pin 0 of a 2*1 socket's generated model (the workpiece held in the air by its servos)
    at a radial ``clearance`` (its grade's physics step) loaded at its tip along x through
    the env's stepper, one physics step per call: a ramp to 1.2 times the yield load,
    unloading, a rest, and the same ramp again. Returns the figures over beam theory's. A
    dead load beyond yield turns the pin until its lever shrinks (``F L cos θ = M_y``), so
    the second yield is compared as a root moment."""
    spec = CircularSocket(2, 1, hole_radius=0.3 + clearance)
    pins = check_pins(spec, "elastic-plastic", material, None)
    model = compile_model(spec, 1, pins)
    data = mujoco.MjData(model)
    stepper = ServoStepper(model, data)
    stepper.reset(np.array([0.0, 0.0, 0.0, 5.0]))
    beams = pin_beams(spec, pins.material)
    length = float(beams.length[0])
    k_tip = float(beams.k_theta[0]) / length**2  # 3EI/L³
    f_yield = float(beams.yield_moment[0]) / length  # M_y/L
    theta_y = float(beams.yield_rotation[0])
    ramp = np.linspace(0.0, 1.2 * f_yield, 1200)
    phases = [ramp, ramp[::-1], np.zeros(300), ramp]
    body, tip = model.body("pin0_root").id, model.site("pin0_tip").id
    still = np.zeros(4)
    records = []
    for phase, loads in enumerate(phases):
        for load in loads:
            force = np.array([load, 0.0, 0.0])
            arm = data.site_xpos[tip] - data.xipos[body]
            data.xfrc_applied[body] = np.concatenate([force, np.cross(arm, force)])
            state = stepper.step(still, 1)
            assert state.error is None
            rotation = np.hypot(*data.qpos[stepper.layout.elastic.hinges[0]])
            plastic = float(np.hypot(*stepper.plasticity.plastic[0]))
            moment = load * length * np.cos(rotation)
            records.append((phase, load, state.pin_deflection[0, 0], plastic, rotation, moment))
    rows = np.array(records)
    first = rows[rows[:, 0] == 0]
    elastic = first[(first[:, 1] > 0.2 * f_yield) & (first[:, 1] < 0.8 * f_yield)]
    slope = np.polyfit(elastic[:, 2], elastic[:, 1], 1)[0]
    yielded = first[first[:, 3] > 0]
    rest = rows[rows[:, 0] == 2]
    theta_max = rows[rows[:, 0] <= 1, 4].max()
    again = rows[rows[:, 0] == 3]
    set_before = rest[-1, 3]
    regrown = again[again[:, 3] > set_before + 1e-12]
    return {
        "slope": slope / k_tip,
        "first_yield": yielded[0, 1] / f_yield,
        "residual": rest[-1, 2] / (length * np.sin(theta_max - theta_y)),
        "second_yield": regrown[0, 5] / float(beams.yield_moment[0]),
        "residual_mm": rest[-1, 2],
    }


@pytest.mark.parametrize(
    ("material", "clearance", "timestep"),
    [(None, 0.2, 1e-3), ("alloy42", 0.2, 1e-3), (None, 0.05, 5e-4), ("brass", 0.02, 2.5e-4)],
)
def test_the_generated_pin_is_the_cantilever_of_beam_theory(material, clearance, timestep):
    """Elastic slope within 5 % of 3EI/L³, first yield within 5 % of M_y/L, a permanent
    offset after unloading within 5 % of L·sin(θ_max − θ_y), and yield again at M_y, at
    the paper's 200 µm and at the 50 and 20 µm grades' physics steps."""
    spec = CircularSocket(2, 1, hole_radius=0.3 + clearance)
    assert compile_model(spec, 1).opt.timestep == timestep
    figures = _push(material, clearance)
    assert figures["slope"] == pytest.approx(1.0, abs=0.05)
    assert figures["first_yield"] == pytest.approx(1.0, abs=0.05)
    assert figures["residual_mm"] > 0.05  # it stays bent
    assert figures["residual"] == pytest.approx(1.0, abs=0.05)
    assert figures["second_yield"] == pytest.approx(1.0, abs=0.05)


def test_rigid_pins_keep_their_mjcf_and_the_elastic_model_has_hinged_pins() -> None:
    spec = CircularSocket(2, 2)
    assert make_mjcf(spec, elastic=None) == make_mjcf(spec)
    pins = check_pins(spec, "elastic-plastic", None, None)
    model = compile_model(spec, 2, pins)
    assert model.nq == 4 + 2 * spec.n_pins and model.neq == 2 * spec.n_pins and model.nu == 4
    for i in range(spec.n_pins):  # the tip site and touch zone follow the pin
        body = model.body(f"pin{i}_root").id
        assert model.site(f"pin{i}_tip").bodyid[0] == body
        assert model.site(f"pin{i}_zone").bodyid[0] == body
        assert model.geom(f"pin{i}").bodyid[0] == body


def test_delicate_ids_are_registered_with_their_tag() -> None:
    ids = [task.gym_id_of(2) for task in DELICATE_TASKS]
    assert "tolins/Circle2x2Delicate-v2" in ids and "tolins/Circle2x8Fit50Delicate-v2" in ids
    for task in DELICATE_TASKS:
        assert "delicate" in task.tags and "paper" not in task.tags
        assert task.gym_id_of(2) in gym.registry and task.physics_versions == (2,)
    assert {task.domain for task in DELICATE_TASKS} <= {domain for domain, _ in dmc.DELICATE}


def test_check_env_on_a_delicate_id() -> None:
    env = gym.make("tolins/Circle2x2Delicate-v2", horizon=6)
    check_env(env.unwrapped, skip_render_check=True)
    _, info = env.reset(seed=0)
    assert info["pin_bend"].shape == (4, 2) and info["pin_deflection"].shape == (4, 2)
    assert info["damaged"] is False and info["damaged_at"] is None
    assert env.unwrapped.damage_threshold == pytest.approx(0.1)  # half of 0.2 mm


def _episode(env: gym.Env, seed: int, steps: int) -> list[np.ndarray]:
    """Random actions pressing down from just over the board (contact from the first step)."""
    observation, info = env.reset(seed=seed, options={"pose": [0.3, -0.1, 0.02, 0.3]})
    rng = np.random.default_rng(seed)
    out = [observation, info["pin_bend"]]
    for _ in range(steps):
        action = rng.uniform(-1.0, 1.0, 4) * [2.5, 2.5, 0.1, 2.5] - [0, 0, 0, 1.5]
        observation, reward, terminated, truncated, info = env.step(action)
        out += [observation, np.array([reward]), info["pin_bend"], info["pin_deflection"]]
        if terminated or truncated:
            break
    assert info["n_collisions"] > 0
    return out


def test_two_runs_are_bit_identical() -> None:
    runs = []
    for _ in range(2):
        env = gym.make("tolins/Circle2x2Delicate-v2", pin_material="brass")
        runs.append(_episode(env, 3, 8))
    assert len(runs[0]) == len(runs[1])
    for a, b in zip(*runs, strict=True):
        assert np.array_equal(a, b)


def _bend_in_a_hole(env: InsertionEnv) -> dict:
    """Pins 1 mm deep in their holes, then pushed sideways into the walls: alloy 42's pins
    yield under the servos' force (2.5 N each against 1.46 N)."""
    env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, -1.0]})
    for _ in range(2):
        *_, info = env.step([1.0, 0.0, 0.0, 0.0])
    return info


def test_a_bend_stays_and_keep_part_carries_it_to_the_next_episode() -> None:
    env = InsertionEnv(CircularSocket(2, 1), pin_material="alloy42", **ELASTIC)
    info = _bend_in_a_hole(env)
    bend = info["pin_bend"]
    assert np.all(bend[:, 0] < -0.02)  # the tips held back by the walls: bent along -x
    assert info["damaged"] and info["damaged_at"] >= 1
    _, kept = env.reset(seed=1, options={"pose": [0.0, 0.0, 0.0, 2.0], "keep_part": True})
    assert np.array_equal(kept["pin_bend"], bend)
    assert kept["damaged"] and kept["damaged_at"] == 0
    assert np.allclose(kept["pin_deflection"], bend, atol=1e-9)  # at rest at its bend
    _, fresh = env.reset(seed=1, options={"pose": [0.0, 0.0, 0.0, 2.0]})
    assert not fresh["pin_bend"].any() and fresh["damaged"] is False


def test_free_flight_holds_bent_pins_and_moves_the_part_as_rigid_pins() -> None:
    env = InsertionEnv(CircularSocket(2, 1), pin_material="alloy42", physics_version=2, **ELASTIC)
    bend = _bend_in_a_hole(env)["pin_bend"]
    rigid = InsertionEnv(CircularSocket(2, 1), physics_version=2)
    pose = [0.5, -0.5, 0.1, 5.0]  # 5 mm over the board: nothing can touch
    env.reset(seed=1, options={"pose": pose, "keep_part": True})
    rigid.reset(seed=1, options={"pose": pose})
    stepper, model = env.backend.stepper, env.backend.model
    armature, flags = model.dof_armature.copy(), model.opt.disableflags
    for action in ([1.0, -1.0, 0.05, 2.0], [-2.0, 1.0, -0.1, -1.0], [0.0, 0.0, 0.0, 0.0]):
        *_, info = env.step(action)
        rigid.step(action)
        assert stepper.step_factor > 1  # free flight's longer steps
        assert np.array_equal(info["pin_deflection"], bend)  # held exactly, at rest
        assert not stepper.data.qvel[model.nu :].any()
        part, rigid_part = stepper.data.qpos[: model.nu], rigid.backend.data.qpos[: model.nu]
        assert np.allclose(part, rigid_part, rtol=0.0, atol=1e-9)  # measured 2e-13
    assert np.array_equal(model.dof_armature, armature) and model.opt.disableflags == flags


def test_the_delicate_reward_ends_the_episode_with_its_penalty_on_damage() -> None:
    """With ``damage_penalty`` the step that damages a pin gets the penalty and terminates
    the episode; without it the same step goes on, unrewarded (the same physics)."""
    penalised = InsertionEnv(
        CircularSocket(2, 1), pin_material="alloy42", damage_penalty=5.0, **ELASTIC
    )
    plain = InsertionEnv(CircularSocket(2, 1), pin_material="alloy42", **ELASTIC)
    outcomes = []
    for env in (penalised, plain):
        env.reset(seed=0, options={"pose": [0.0, 0.0, 0.0, -0.6]})
        steps = []
        for _ in range(3):
            _, reward, terminated, _, info = env.step([1.0, 0.0, 0.0, 0.0])
            steps.append((reward, terminated, info))
            if terminated:
                break
        outcomes.append(steps)
    (reward, terminated, info), plain_steps = outcomes[0][-1], outcomes[1]
    assert terminated and info["damaged"] and not info["success"]
    assert info["reward_damage"] == -5.0 and info["damaged_at"] == len(outcomes[0])
    plain_reward, plain_terminated, plain_info = plain_steps[len(outcomes[0]) - 1]
    assert plain_info["damaged"] and not plain_terminated and "reward_damage" not in plain_info
    assert reward == plain_reward - 5.0
    assert all(step[2]["reward_damage"] == 0.0 for step in outcomes[0][:-1])


def test_dm_control_steps_as_the_gym_id() -> None:
    pose = [0.3, -0.1, 0.02, 0.6]  # outside the clearance: pushes, slides, collides
    gym_env = gym.make("tolins/Circle2x2Delicate-v2", measurement_noise=0).unwrapped
    gym_env.reset(seed=0, options={"pose": pose})
    env = dmc.load(
        "circle2x2_delicate", "insert", task_kwargs={"measurement_noise": 0, "pose": pose}
    )
    env.reset()
    for action in [[0, 0, 0, -2.5]] * 3 + [[1.0, 0.5, -0.05, -1.0]] * 4:
        _, reward, terminated, truncated, info = gym_env.step(action)
        timestep = env.step(action)
        state = env.physics.last_state
        assert np.array_equal(state.pose, info["pose"])
        assert np.array_equal(state.pin_deflection, info["pin_deflection"])
        assert np.array_equal(state.pin_bend, info["pin_bend"])
        assert timestep.reward == reward
        if terminated or truncated:
            break
    assert info["n_collisions"] > 0


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: InsertionEnv(CircularSocket(2, 2), pins="bendy"), r"pins='bendy'; allowed"),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), pin_material="gold", **ELASTIC),
            r"pin_material='gold' is not a known material; allowed: one of 'phosphor_bronze'",
        ),
        (
            lambda: InsertionEnv(
                CircularSocket(2, 2),
                pin_material={"youngs_modulus": 0, "yield_strength": 500},
                **ELASTIC,
            ),
            r"pin_material\['youngs_modulus'\]=0 is out of range; allowed: .*0 < value",
        ),
        (
            lambda: InsertionEnv(
                CircularSocket(2, 2),
                pin_material={"youngs_modulus": 110, "yield_strength": -5},
                **ELASTIC,
            ),
            r"pin_material\['yield_strength'\]=-5 is out of range",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), damage_threshold=0.0, **ELASTIC),
            r"damage_threshold=0.0 is out of range; allowed: 0 < damage_threshold ≤ 0.2 mm",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), damage_threshold=0.25, **ELASTIC),
            r"damage_threshold=0.25 is out of range",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), damage_threshold=0.05),
            r"damage_threshold=0.05 applies to bending pins only",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), damage_penalty=1.0),
            r"damage_penalty=1.0 applies to bending pins only",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), damage_penalty=-1.0, **ELASTIC),
            r"damage_penalty=-1.0 is out of range; allowed: 0 < damage_penalty ≤ 1000",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), damage_penalty="big", **ELASTIC),
            r"damage_penalty='big'.*allowed: 0 < damage_penalty",
        ),
        (
            lambda: InsertionEnv(PolygonSocket(4, 1.5, 1.65), **ELASTIC),
            r"round pins .* a solid 2.12132 mm peg.* bends 1\.0 µm under the servos' 5 N "
            r"and yields only at 120\.7 N",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2), backend="kinematic", **ELASTIC),
            r"not supported on backend='kinematic'; allowed: backend='mujoco'",
        ),
        (
            lambda: tolins.make_vec("tolins/Circle2x2Delicate-v2", 2, backend="warp"),
            r"not supported on backend='warp' in the vector env",
        ),
        (
            lambda: InsertionEnv(CircularSocket(2, 2)).reset(options={"keep_part": True}),
            r"keep_part'\]=True keeps the bends of elastic-plastic pins",
        ),
    ],
)
def test_bad_settings_are_refused_in_one_line(make, match: str) -> None:
    with pytest.raises(ValueError, match=match) as raised:
        make()
    assert "\n" not in str(raised.value)


def test_the_vector_env_steps_each_simulation_as_the_single_env_does() -> None:
    """Three simulations on two threads, pressing and dragging from just over the board,
    then a reset keeping the parts' bends: observations, rewards and bends bit for bit the
    single env's."""
    kwargs = {"pin_material": "alloy42", "measurement_noise": 0.0}
    env_id = "tolins/Circle2x1Delicate-v2"
    vector = tolins.make_vec(env_id, 3, num_threads=2, **kwargs)
    single = gym.make(env_id, **kwargs).unwrapped
    pose = [0.0, 0.0, 0.0, -0.6]  # pins in their holes, short of success
    actions = np.array([[1.0, 0.0, 0.0, 0.0], [-1.0, 1.0, 0.0, 0.0], [0.0, -1.0, 0.05, 0.0]])
    vector.reset(seed=[5, 6, 7], options={"pose": pose})
    batch = [vector.step(actions) for _ in range(3)]
    kept = vector.reset(seed=[8, 9, 10], options={"pose": [0.0, 0.0, 0.0, 2.0], "keep_part": True})
    for i in range(3):
        single.reset(seed=5 + i, options={"pose": pose})
        for k in range(3):
            observation, reward, *_, info = single.step(actions[i])
            np.testing.assert_array_equal(observation, batch[k][0][i])
            assert reward == batch[k][1][i]
            np.testing.assert_array_equal(info["pin_bend"], batch[k][4]["pin_bend"][i])
        observation, info = single.reset(
            seed=8 + i, options={"pose": [0.0, 0.0, 0.0, 2.0], "keep_part": True}
        )
        np.testing.assert_array_equal(observation, kept[0][i])
        np.testing.assert_array_equal(info["pin_bend"], kept[1]["pin_bend"][i])
    assert np.abs(kept[1]["pin_bend"]).max() > 0.02  # the first simulation's pins stayed bent
    vector.close()
