"""The MuJoCo Warp backend on Warp's CPU device agrees with C MuJoCo.

The same poses and commands run through ``MujocoBatch`` (C MuJoCo, float64) and
``WarpBatch`` (float32, solver tolerance clamped to 1e-6) in one batch each: insertion
outcomes of near-boundary probes (``benchmarks/physics_vs_geometry.py``), the forces of
blocked pushes, a bent-pin world, subsets that leave the other worlds untouched, faults,
and whole safe-expert episodes through ``gymnasium.make_vec(..., backend="warp")``.
``benchmarks/warp_agreement.py`` measures the same on more poses.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import tolins
from tolins import CircularSocket
from tolins.physics.mujoco import MujocoBatch
from tolins.physics.warp import WarpBatch

# Found, not imported: importing mujoco_warp takes 3 CPU-s, which each pytest-xdist worker
# would pay while collecting, though one runs this file (the tests import it).
pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        importlib.util.find_spec("mujoco_warp") is None,
        reason="backend='warp' needs pip install 'tolins[warp]'",
    ),
]
BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
SOCKET = CircularSocket(2, 2)
#: Largest difference of a wrench component or peak force between the backends (N, N·mm)
#: in a 5 N blocked push; measured: ≤ 7e-5 (benchmarks/README.md).
FORCE_TOLERANCE = 1e-3


def _module(name: str):
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look the module up
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def agreement():
    module = _module("warp_agreement")
    yield module
    sys.modules.pop("warp_agreement", None)
    sys.modules.pop("physics_vs_geometry", None)


@pytest.fixture(scope="module")
def run(agreement):
    """Probes 30 µm from the boundary, the blocked pushes and a bent-pin world, 4 control
    steps in one batch per backend."""
    pvg = agreement.physics_vs_geometry()
    probes = pvg.make_probes(
        pvg.Socket("2*2", "circle", SOCKET), 8, 7, 50.0, 32, offsets_um=np.tile([30.0, -30.0], 4)
    )
    probes = [p for p in probes if abs(p.distance_um) > 10.0]
    bent = tolins.sample_defects(SOCKET, 0.12, np.random.default_rng(5))
    poses = [[*p.pose, agreement.START_HEIGHT] for p in probes]
    poses += [p for _, p, _ in agreement.PUSHES] + [[0.0, 0.0, 0.0, agreement.START_HEIGHT]]
    velocities = [[0.0, 0.0, 0.0, -agreement.FAST]] * len(probes)
    velocities += [u for _, _, u in agreement.PUSHES] + [[0.0, 0.0, 0.0, -agreement.FAST]]
    n = len(poses)
    ids = np.arange(n)
    result = {"probes": probes, "bent": bent, "n": n}
    for name, batch in (
        ("mujoco", MujocoBatch(SOCKET, n, 0.25)),
        ("warp", WarpBatch(SOCKET, n, 0.25)),
    ):
        batch.set_socket(n - 1, bent)
        batch.reset(ids, np.array(poses))
        inserted = np.zeros(n, dtype=bool)
        for _ in range(4):
            state = batch.step(ids, np.array(velocities))
            sockets = [SOCKET] * (n - 1) + [bent]
            inserted |= [
                tolins.geometry.workspace.in_holes(s, p, 1.0)
                for s, p in zip(sockets, state.pose, strict=True)
            ]
        result[name] = {"state": state, "inserted": inserted, "batch": batch}
    return result


def test_outcomes_near_the_boundary_agree_with_c_mujoco_and_the_geometry(run) -> None:
    probes = run["probes"]
    assert len(probes) >= 6 and {p.inside for p in probes} == {True, False}
    k = len(probes)
    inside = np.array([p.inside for p in probes])
    assert np.array_equal(run["warp"]["inserted"][:k], run["mujoco"]["inserted"][:k])
    assert np.array_equal(run["warp"]["inserted"][:k], inside)
    assert run["warp"]["state"].errors == (None,) * run["n"]


def test_blocked_pushes_give_the_same_forces_and_poses(run, agreement) -> None:
    c, w = run["mujoco"]["state"], run["warp"]["state"]
    k = len(run["probes"])
    for i in range(k, k + len(agreement.PUSHES)):
        assert not run["warp"]["inserted"][i]
        assert np.abs(c.wrench[i] - w.wrench[i]).max() < FORCE_TOLERANCE, (c.wrench[i], w.wrench[i])
        assert abs(c.peak_force[i] - w.peak_force[i]) < FORCE_TOLERANCE
        assert np.abs(c.pose[i] - w.pose[i]).max() < 1e-3  # mm and rad
    down, side = k, k + 1
    assert 4.9 < w.wrench[down][3] < 5.1  # the 5 N servo limit, pushing on the board
    assert w.wrench[side][0] < -4.9  # the hole wall pushes back against +x


def test_a_bent_pin_world_moves_as_c_mujocos_bent_model(run) -> None:
    c, w = run["mujoco"]["state"], run["warp"]["state"]
    assert run["warp"]["inserted"][-1] == run["mujoco"]["inserted"][-1]
    assert np.abs(c.pose[-1] - w.pose[-1]).max() < 1e-3
    assert abs(c.peak_force[-1] - w.peak_force[-1]) < FORCE_TOLERANCE


def test_per_world_fields_are_those_of_the_bent_model_on_the_device(run) -> None:
    import mujoco
    import mujoco_warp as mjw

    from tolins.mjcf import make_mjcf

    batch = run["warp"]["batch"]
    assert "geom_pos" in batch.per_world_fields and "site_pos" in batch.per_world_fields
    alone = mjw.put_model(mujoco.MjModel.from_xml_string(make_mjcf(run["bent"])))
    nominal = mjw.put_model(batch.model)
    for name in batch.per_world_fields:
        rows = getattr(batch.m, name).numpy()
        assert np.array_equal(rows[-1], getattr(alone, name).numpy()[0]), name
        assert np.array_equal(rows[0], getattr(nominal, name).numpy()[0]), name


def test_stepping_or_resetting_a_subset_leaves_the_other_worlds_bit_for_bit(run) -> None:
    batch = run["warp"]["batch"]
    fields = ("qpos", "qvel", "act", "ctrl", "qacc_warmstart", "time", "sensordata")
    before = {f: getattr(batch.d, f).numpy().copy() for f in fields}
    state = batch.step(np.array([0]), np.array([[0.0, 0.0, 0.0, 2.5]]))
    assert state.pose[0, 3] > before["qpos"][0, 2] + 0.5  # world 0 rose
    batch.reset(np.array([1]), np.array([[0.1, 0.0, 0.0, 0.2]]))
    for f in fields:
        after = getattr(batch.d, f).numpy()
        assert np.array_equal(after[2:], before[f][2:]), f
    assert np.allclose(batch.d.qpos.numpy()[1], [0.1, 0.0, 0.2, 0.0])


def test_overflow_and_non_finite_states_are_faults() -> None:
    batch = WarpBatch(SOCKET, 2, 0.25, nconmax=1)
    batch.reset(np.arange(2), np.array([[0.25, 0.0, 0.0, 0.01], [0.0, 0.0, 0.0, 2.0]]))
    errors = batch.step(np.arange(2), np.array([[0.0, 0.0, 0.0, -2.5]] * 2)).errors
    assert "overflow" in errors[0] and "nconmax=1" in errors[0]
    batch = WarpBatch(SOCKET, 2, 0.25)
    batch.reset(np.arange(2), np.array([[0.0, 0.0, 0.0, 2.0]] * 2))
    qvel = batch.d.qvel.numpy()
    qvel[0, 0] = np.nan
    batch.d.qvel.assign(qvel)
    errors = batch.step(np.arange(2), np.zeros((2, 4))).errors
    assert errors == ("non-finite MuJoCo Warp state", None)


def test_missing_warp_and_unavailable_devices_are_clear_errors(monkeypatch) -> None:
    with pytest.raises(ValueError, match=r"device='cuda:7' is not available.*allowed: 'cpu'"):
        WarpBatch(SOCKET, 1, 0.25, device="cuda:7")
    monkeypatch.setitem(sys.modules, "mujoco_warp", None)  # import mujoco_warp now fails
    with pytest.raises(ImportError, match=r"pip install 'tolins\[warp\]'"):
        tolins.make_vec("tolins/Circle2x2-v1", 1, backend="warp")


def test_safe_expert_episodes_match_the_mujoco_backend(agreement) -> None:
    seeds = [0, 1]
    result = agreement.expert_episodes(seeds, "cpu")
    assert result["warp"]["success"] == result["mujoco"]["success"] == [True, True]
    assert result["warp"]["steps"] == result["mujoco"]["steps"]
    # Bent pins drawn per env and episode: the per-world model rows.
    result = agreement.expert_episodes([0, 1], "cpu", env_id="tolins/Circle2x1Defective-v1")
    assert result["warp"]["defective"] == result["mujoco"]["defective"] == [True, True]
    assert result["warp"]["success"] == result["mujoco"]["success"]
    assert result["warp"]["steps"] == result["mujoco"]["steps"]
    env = gym.make_vec(
        "tolins/Circle2x2-v1",
        num_envs=1,
        vectorization_mode="vector_entry_point",
        backend="warp",
        device="cpu",
    )
    assert type(env.unwrapped.physics) is WarpBatch
    env.close()


def test_gpu_script_runs_on_the_cpu_device(tmp_path) -> None:
    out = tmp_path / "rows.json"
    gpu = _module("warp_gpu")
    gpu.main(
        ["--device", "cpu", "--worlds", "2", "--steps", "1", "--sockets", "2*2", "--json", str(out)]
    )
    rows = {r["regime"]: r for r in json.loads(out.read_text())["rows"]}
    assert rows["contact"]["contacts_per_world"] > 0 and rows["free"]["contacts_per_world"] == 0
    assert all(r["faults"] == 0 and r["world_control_steps_per_s"] > 0 for r in rows.values())
    sys.modules.pop("warp_gpu", None)
