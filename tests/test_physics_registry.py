"""One registry of simulators, and the capabilities each simulator class declares."""

from __future__ import annotations

import pytest

import tolins
from tolins.envs import InsertionEnv
from tolins.geometry.defects import DEFECT_KINDS
from tolins.paper import CONTROL_DT
from tolins.physics import (
    BACKENDS,
    BATCH_BACKENDS,
    SIMULATORS,
    Capabilities,
    make_backend,
    make_batch,
    simulator,
)
from tolins.physics.kinematic import KinematicBackend, KinematicBatch
from tolins.physics.mujoco import MujocoBackend, MujocoBatch

SOCKET = tolins.CircularSocket(2, 2)
FLAGS = ("supports_render", "supports_randomization", "supports_touch_points")


def test_the_registry_names_every_simulator_once() -> None:
    assert BATCH_BACKENDS == ("mujoco", "kinematic", "warp")
    assert BACKENDS == ("mujoco", "kinematic")
    assert SIMULATORS["mujoco"].single is MujocoBackend
    assert SIMULATORS["kinematic"].batch is KinematicBatch
    assert SIMULATORS["warp"].single is None
    assert tolins.envs.BACKENDS == BACKENDS


@pytest.mark.parametrize("name", BATCH_BACKENDS)
def test_every_simulator_class_declares_every_capability(name: str) -> None:
    classes = [SIMULATORS[name].batch, SIMULATORS[name].single]
    for cls in filter(None, classes):
        assert issubclass(cls, Capabilities)
        for flag in FLAGS:
            assert isinstance(getattr(cls, flag), bool), (cls, flag)
        assert cls.defect_kinds <= set(DEFECT_KINDS)
        assert cls.batch_options <= {"num_threads", "device", "persistent"}


def test_the_single_env_takes_every_defect_kind_and_the_batches_what_they_declare() -> None:
    for name in BACKENDS:
        assert SIMULATORS[name].single.defect_kinds == set(DEFECT_KINDS)
    assert "blocked" not in MujocoBatch.defect_kinds
    assert SIMULATORS["warp"].batch.defect_kinds == frozenset()


def test_unknown_names_are_refused_naming_the_allowed_ones() -> None:
    with pytest.raises(
        ValueError, match=r"backend='bullet'; allowed: 'mujoco', 'kinematic', 'warp'"
    ):
        simulator("bullet")
    with pytest.raises(ValueError, match=r"backend='warp'; allowed: \['kinematic', 'mujoco'\]"):
        make_backend("warp", SOCKET, CONTROL_DT)
    with pytest.raises(ValueError, match=r"backend=\['mujoco'\]; allowed"):
        InsertionEnv(SOCKET, backend=["mujoco"])


def test_a_device_is_refused_where_the_simulator_runs_on_none() -> None:
    with pytest.raises(ValueError, match=r"device='cpu' is for backend='warp' only"):
        make_batch("kinematic", SOCKET, 1, CONTROL_DT, device="cpu")


def test_hints_a_simulator_does_not_take_are_ignored() -> None:
    batch = make_batch("kinematic", SOCKET, 2, CONTROL_DT, num_threads=1, persistent=True)
    assert isinstance(batch, KinematicBatch) and batch.num_envs == 2
    batch = make_batch("mujoco", SOCKET, 2, CONTROL_DT, num_threads=1)
    assert isinstance(batch, MujocoBatch) and batch.num_threads == 1
    assert isinstance(make_backend("kinematic", SOCKET, CONTROL_DT), KinematicBackend)


def test_the_vector_env_refuses_what_the_batch_cannot_simulate() -> None:
    with pytest.raises(ValueError, match=r"not supported on backend='mujoco'; .*'kinematic'$"):
        tolins.make_vec("tolins/Circle2x2-v1", 1, num_threads=1, defects=("blocked", None))
