"""A new workpiece is a ``set_socket`` of the simulator the env already holds.

A defective reset swaps the backend's model and data (as a batch's ``set_socket`` swaps a
simulation's): the env keeps its backend, and each episode is what a backend built anew
for that workpiece simulates, bit for bit. Models kept for a workpiece that comes back are
at their nominal physics, and the compile cache survives pickling.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from tolins.envs import InsertionEnv
from tolins.geometry.specs import CircularSocket
from tolins.paper import CONTROL_DT
from tolins.physics.compiled import compile_model
from tolins.physics.kinematic import KinematicBackend
from tolins.physics.mujoco import MujocoBackend
from tolins.physics.randomization import PhysicsDraw

SOCKET = CircularSocket(2, 2)
BENT = CircularSocket(2, 2, pin_offsets=[[0.05, 0.0], [0.0, 0.0], [0.0, -0.04], [0.0, 0.0]])
ACTIONS = [[0.5, 0.0, 0.0, -2.5], [0.0, -0.5, 0.05, -2.5], [0.0, 0.0, 0.0, -2.5]]


def _same_state(a, b) -> bool:
    return (
        np.array_equal(a.pose, b.pose)
        and np.array_equal(a.wrench, b.wrench)
        and a.peak_force == b.peak_force
        and a.error == b.error
    )


@pytest.mark.parametrize("randomization", [None, "default"])
def test_a_defective_reset_keeps_the_backend_and_simulates_as_a_fresh_one(randomization) -> None:
    env = InsertionEnv(SOCKET, defect_sigma=0.05, randomization=randomization)
    backend = env.backend
    for seed in range(4):  # drawn poses, and poses pressing on the board's top
        options = {"pose": [0.35, 0.0, 0.0, 0.3]} if seed % 2 else None
        _, info = env.reset(seed=seed, options=options)
        assert env.backend is backend and backend.spec is env.socket
        assert backend.stepper.model is backend.model and backend.stepper.data is backend.data
        fresh = MujocoBackend(env.socket, CONTROL_DT)
        if randomization is not None:
            fresh.set_physics(env._episode.physics)
        assert _same_state(fresh.reset(info["pose"]), env._episode.state)
        for action in ACTIONS:
            env.step(action)
            assert _same_state(fresh.step(np.array(action)), env._episode.state)


def test_a_workpiece_that_comes_back_starts_from_its_nominal_physics() -> None:
    backend = MujocoBackend(SOCKET, CONTROL_DT)
    nominal = backend.model
    backend.set_physics(PhysicsDraw(friction=2.0, servo_gain=0.5))
    backend.set_socket(BENT)
    assert backend.model is not nominal and backend.spec is BENT
    backend.set_socket(SOCKET)
    assert backend.model is nominal  # kept, not compiled again
    compiled = compile_model(SOCKET)
    for name in ("geom_friction", "actuator_gainprm", "actuator_biasprm"):
        assert np.array_equal(getattr(backend.model, name), getattr(compiled, name))


def test_a_pickled_backend_finds_its_compiled_models() -> None:
    backend = MujocoBackend(SOCKET, CONTROL_DT)
    backend.set_socket(BENT)
    copy = pickle.loads(pickle.dumps(backend))
    assert copy.model is copy.stepper.model
    assert copy._compiled.get(copy.spec) is copy.model  # re-keyed to the copy's specs


def test_the_kinematic_backend_draws_its_new_workpiece() -> None:
    backend = KinematicBackend(SOCKET, CONTROL_DT)
    backend.set_socket(BENT)
    backend.reset(np.array([0.0, 0.0, 0.0, 1.0]))
    pin = compile_model(BENT).geom("pin0").pos
    assert not np.array_equal(pin, compile_model(SOCKET).geom("pin0").pos)
    assert backend.spec is BENT
    assert np.array_equal(backend.model.geom("pin0").pos, pin)
